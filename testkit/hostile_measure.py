"""The red team's hostile requests (:data:`testkit.hostile_cases.CASES`) measured
against a real server.

``python -m testkit.hostile_measure`` sends each to a real ``python -m service`` at its
default settings and reports, per case, the status, the time to answer, the slowest
``/healthz`` while it ran (polled every 20 ms), the server's process tree's largest
resident set and the time of a small job right after, as a Markdown table.
"""

from __future__ import annotations

import io
import json
import sys
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

from .hostile_cases import CASES, Case

__all__ = ["measure"]


def _png(values: np.ndarray) -> bytes:
    buf = io.BytesIO()
    Image.fromarray(values).save(buf, "PNG")
    return buf.getvalue()


def _tree_rss(pid: int) -> int:
    """Resident bytes of ``pid`` and its children (one level: the workers)."""
    from skelprune.budget import resident_bytes

    total = resident_bytes(pid)
    try:
        children = Path(f"/proc/{pid}/task/{pid}/children").read_text().split()
    except OSError:
        children = []
    for child in children:
        total += resident_bytes(int(child))
        try:
            grand = Path(f"/proc/{child}/task/{child}/children").read_text().split()
        except OSError:
            grand = []
        total += sum(resident_bytes(int(g)) for g in grand)
    return total


def measure(base: str, pid: int, case: Case, small: bytes) -> dict[str, Any]:
    """Send ``case``, polling ``/healthz`` and the process tree's memory meanwhile."""
    import httpx

    stop = threading.Event()
    worst = {"health": 0.0, "rss": 0}

    def poll() -> None:
        with httpx.Client(timeout=10) as c:
            while not stop.is_set():
                t0 = time.perf_counter()
                c.get(f"{base}/healthz")
                worst["health"] = max(worst["health"], time.perf_counter() - t0)
                worst["rss"] = max(worst["rss"], _tree_rss(pid))
                time.sleep(0.02)

    body, ctype = case.body()
    headers = {"content-type": ctype}
    if case.accept:
        headers["accept"] = case.accept
    poller = threading.Thread(target=poll)
    poller.start()
    t0 = time.perf_counter()
    with httpx.Client(timeout=120) as c:
        resp = c.post(f"{base}{case.path}", content=body, params=case.params, headers=headers)
        took = time.perf_counter() - t0
        stop.set()
        poller.join()
        t1 = time.perf_counter()
        after = c.post(f"{base}/v1/prune", content=small, headers={"content-type": "image/png"})
        small_took = time.perf_counter() - t1
    text = resp.text
    detail = (
        json.loads(text).get("detail", "")
        if resp.headers.get("content-type", "").endswith("json") and text.startswith("{")
        else text[:120]
    )
    return {
        "case": case.name,
        "bytes": len(body),
        "status": resp.status_code,
        "seconds": took,
        "healthz_max_ms": 1000 * worst["health"],
        "tree_rss_mib": worst["rss"] / 2**20,
        "small_job": (after.status_code, small_took),
        "detail": str(detail)[:90],
    }


def main() -> None:
    """Every case (or those named on the command line) against a real server at its
    default settings; a Markdown table."""
    import tempfile

    from .realserver import running_server

    small = _png(np.pad(np.ones((20, 40), np.uint8) * 255, 5))
    log = Path(tempfile.mkdtemp()) / "server.log"
    print(
        "| case | body, bytes | status | time, s | slowest /healthz, ms | tree RSS, MiB "
        "| small job after |"
    )
    print("|---|---|---|---|---|---|---|")
    with running_server(log) as (proc, base):
        chosen = sys.argv[1:]  # case names; none: every case
        for case in [c for c in CASES if not chosen or c.name in chosen]:
            r = measure(base, proc.pid, case, small)
            status, t = r["small_job"]
            print(
                f"| {r['case']} | {r['bytes']:,} | {r['status']} | {r['seconds']:.2f} | "
                f"{r['healthz_max_ms']:.0f} | {r['tree_rss_mib']:,.0f} | {status} in {t:.2f} s |",
                flush=True,
            )
            print(f"  detail: {r['detail']}", file=sys.stderr)


if __name__ == "__main__":
    main()
