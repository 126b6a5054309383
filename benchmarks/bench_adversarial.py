"""Adversarial masks against the real service: the answer, its time and each worker's peak memory.

The masks of :data:`testkit.adversarial.CORPUS` (pixel noise at three densities,
checkerboards, a fractal boundary, one-pixel lines, isolated dots) as PNGs, at the
service's pixel limit (4096², the default ``SKELPRUNE_MAX_PIXELS``), at 1024² and 512²,
plus an overlay at ``overlay_scale=16``, go one at a time to ``python -m service`` with
its default budgets (``SKELPRUNE_JOB_MEMORY_MB`` 2048, ``SKELPRUNE_JOB_TIMEOUT`` 30 s)
and one worker. Before each request the workers' peak-RSS counters are reset
(``/proc/PID/clear_refs``), after it their peak (``VmHWM``) is read: the table shows the
largest, which must stay under the memory budget, and the answer, which must be a 200
or a clear 4xx. The estimate columns are the service's own (:mod:`service.budget`).

``python -m benchmarks adversarial`` (Linux; about ten minutes: the masks the budget
accepts are pruned in full).
"""

from __future__ import annotations

import contextlib
import io
import os
import tempfile
import time
from pathlib import Path

import httpx
import numpy as np
from PIL import Image

from service.budget import estimate, shape_counts
from service.settings import Settings
from testkit.adversarial import CORPUS, checkerboard
from testkit.realserver import running_server

from .common import table

SIZES = (4096, 1024, 512)


def _png(mask: np.ndarray) -> bytes:
    buf = io.BytesIO()
    Image.fromarray(mask.astype(np.uint8) * 255).save(buf, "PNG", optimize=True)
    return buf.getvalue()


def _descendants(pid: int) -> list[int]:
    children: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                stat = Path(f"/proc/{entry}/stat").read_text()
            except OSError:
                continue
            ppid = int(stat.rsplit(")", 1)[1].split()[1])
            children.setdefault(ppid, []).append(int(entry))
    out, todo = [], [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            out.append(child)
            todo.append(child)
    return out


def _reset_peaks(pids: list[int]) -> None:
    for pid in pids:
        with contextlib.suppress(OSError):
            Path(f"/proc/{pid}/clear_refs").write_text("5")


def _peak_mib(pids: list[int]) -> float:
    peak = 0
    for pid in pids:
        try:
            for line in Path(f"/proc/{pid}/status").read_text().splitlines():
                if line.startswith("VmHWM:"):
                    peak = max(peak, int(line.split()[1]))
        except OSError:
            pass
    return peak / 1024


def main() -> None:
    settings = Settings()
    budget_mib = settings.job_memory_mb
    cases = [(f"{name}, {n}²", make(n), {}) for n in SIZES for name, make in CORPUS.items()]
    cases.append(("overlay_scale=16, checkerboard 3 px, 1024²", checkerboard(1024, 3), "png16"))
    rows = []
    worst = 0.0
    with tempfile.TemporaryDirectory() as tmp:
        log = Path(tmp) / "server.log"
        with running_server(log, workers="1", access_log="false") as (proc, base):
            client = httpx.Client(base_url=base, timeout=settings.job_timeout + 30)
            for label, mask, extra in cases:
                png = _png(mask)
                _, fg, boundary, n_components = shape_counts(mask)
                cost = estimate(mask)
                # foreground=nonzero: the service prunes this very mask (the auto rule
                # would take the side that does not hold most of the border)
                params, headers = {"foreground": "nonzero"}, {"Content-Type": "image/png"}
                if extra == "png16":
                    params["overlay_scale"], headers["Accept"] = "16", "image/png"
                pids = _descendants(proc.pid)
                _reset_peaks(pids)
                t = time.perf_counter()
                r = client.post("/v1/prune", content=png, params=params, headers=headers)
                took = time.perf_counter() - t
                peak = _peak_mib(_descendants(proc.pid))
                worst = max(worst, peak)
                answer = str(r.status_code)
                if r.headers.get("content-type", "").startswith("application/problem+json"):
                    answer += " " + r.json()["type"].rsplit(":", 1)[-1]
                rows.append(
                    [
                        label,
                        f"{len(png) / 1024:,.0f}",
                        f"{boundary:,}",
                        f"{n_components:,}",
                        f"{min(fg, boundary):,}",
                        f"{cost.bytes / 2**20:,.0f}",
                        f"{cost.seconds:.1f}",
                        answer,
                        f"{took:.1f}",
                        f"{peak:,.0f}",
                    ]
                )
                print(" | ".join(rows[-1]), flush=True)
    print()
    print(
        table(
            [
                "mask",
                "PNG, KB",
                "boundary px",
                "components",
                "min(shape, boundary) px",
                "estimate, MiB",
                "estimate, s",
                "answer",
                "time, s",
                "worker peak RSS, MiB",
            ],
            rows,
        )
    )
    print(
        f"\nMemory budget {budget_mib} MiB a job (a worker's peak, its own memory included); "
        f"largest worker peak seen: {worst:,.0f} MiB "
        f"({'under' if worst < budget_mib else 'OVER'} the budget)."
    )


if __name__ == "__main__":
    main()
