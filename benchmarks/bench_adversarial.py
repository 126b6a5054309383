"""Hostile and large inputs against the real service: each answer, its time, and the
worker's resident peak against the memory budget.

One ``python -m service`` with its default budgets (``SKELPRUNE_JOB_MEMORY_MB`` 2048,
``SKELPRUNE_JOB_TIMEOUT`` 30 s) and one worker; requests one at a time. Three parts:

- ``masks``: the masks of :data:`testkit.adversarial.CORPUS` (pixel noise at three
  densities, checkerboards, a fractal boundary, one-pixel lines, isolated dots) as PNGs
  at the service's pixel limit (4096²), 1024² and 512², plus an overlay at
  ``overlay_scale=16``;
- ``inputs``: polygons with many parts (20,000 unit squares) or many vertices (circles
  of 31,000 and 99,999 vertices; 1,000,000 vertices, 14 MB, over the vertex limit), a
  batch of 150,000 items, 16-bit PNGs;
- ``silhouettes``: every 4096² silhouette of ``python -m benchmarks large`` in a row,
  then small shapes: all must answer 200.

Before each request the workers' peak-RSS counters are reset (``/proc/PID/clear_refs``);
while it runs they are read every 5 ms (a worker replaced after its job is measured
before it goes), and the main process's peak after it. "predicted" is what
the worker held before the job plus the service's own estimate
(:func:`skelprune.budget.estimate`): the estimate is calibrated so that it is within 1.5x
of the measured peak, and the peak must stay under the budget.

``python -m benchmarks adversarial`` (Linux; about fifteen minutes);
``SKELPRUNE_BENCH_PARTS=silhouettes`` (or a comma-separated choice) runs some parts.
"""

from __future__ import annotations

import contextlib
import io
import itertools
import json
import os
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import httpx
import numpy as np
from PIL import Image

from service.http.scan import count_polygon
from service.settings import Settings
from skelprune.budget import estimate, polygon_estimate, shape_counts
from testkit.adversarial import CORPUS, checkerboard, circle_polygon, unit_squares
from testkit.pngfile import png16
from testkit.realserver import running_server

from .common import table

SIZES = (4096, 1024, 512)
PARTS = os.environ.get("SKELPRUNE_BENCH_PARTS", "masks,inputs,silhouettes").split(",")


def _png(mask: np.ndarray) -> bytes:
    buf = io.BytesIO()
    Image.fromarray(mask.astype(np.uint8) * 255).save(buf, "PNG", optimize=True)
    return buf.getvalue()


def _png16(grey: np.ndarray, alpha: bool) -> bytes:
    """A 16-bit grey-and-alpha (or RGB) PNG of ``grey``, unfiltered."""
    if alpha:
        return png16(np.stack([grey, np.full_like(grey, 65535)], -1), 4)
    return png16(np.repeat(grey[..., None], 3, -1), 2)


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


def _status(pid: int, key: str) -> float:
    """A ``/proc/PID/status`` memory field, MiB (0 when gone)."""
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith(key):
                return int(line.split()[1]) / 1024
    except OSError:
        pass
    return 0.0


def _workers(server_pid: int) -> list[int]:
    """The service's child processes: the workers (the largest), the fork server."""
    return _descendants(server_pid)


@dataclass
class Case:
    """One request: what it is, how it is sent, and the service's own estimate."""

    label: str
    send: Callable[[httpx.Client], httpx.Response]
    estimate_mib: float | None = None
    extra: dict[str, Any] = field(default_factory=dict)


def _mask_case(label: str, mask: np.ndarray, overlay: bool = False) -> Case:
    png = _png(mask)
    # foreground=nonzero: the service prunes this very mask (the auto rule would take
    # the side that does not hold most of the border)
    params, headers = {"foreground": "nonzero"}, {"Content-Type": "image/png"}
    if overlay:
        params["overlay_scale"], headers["Accept"] = "16", "image/png"
    _, _, boundary, n_components = shape_counts(mask)
    cost = estimate(mask)
    return Case(
        label,
        lambda c: c.post("/v1/prune", content=png, params=params, headers=headers),
        cost.bytes / 2**20,
        {
            "KB": f"{len(png) / 1024:,.0f}",
            "counts": f"{boundary:,} / {n_components:,}",
            "est. s": f"{cost.seconds:.1f}",
        },
    )


def _json_case(label: str, doc: Any, path: str = "/v1/prune") -> Case:
    body = json.dumps(doc).encode()
    counts = count_polygon(body)
    return Case(
        label,
        lambda c: c.post(path, content=body, headers={"Content-Type": "application/json"}),
        None,
        {
            "KB": f"{len(body) / 1024:,.0f}",
            "counts": f"{counts.parts:,} parts / {counts.positions:,} pos.",
            "est. s": f"{polygon_estimate(counts.parts, counts.positions).seconds:.1f}",
        },
    )


def mask_cases() -> list[Case]:
    cases = [_mask_case(f"{name}, {n}²", make(n)) for n in SIZES for name, make in CORPUS.items()]
    cases.append(
        _mask_case("overlay_scale=16, checkerboard 3 px, 1024²", checkerboard(1024, 3), True)
    )
    return cases


def input_cases() -> list[Case]:
    grey = np.full((512, 512), 256, np.uint16)
    grey[128:384, 100:400] = 511  # differs from the background in the low byte only
    png16 = {"RGB": _png16(grey, False), "grey+alpha": _png16(grey, True)}
    cases = [
        _json_case("MultiPolygon, 20,000 unit squares", unit_squares(20_000)),
        _json_case("MultiPolygon, 10,000 unit squares", unit_squares(10_000)),
        _json_case("MultiPolygon, 4,000 unit squares", unit_squares(4_000)),
        _json_case("circle, 31,000 vertices", circle_polygon(31_000)),
        _json_case("circle, 99,999 vertices", circle_polygon(99_999)),
        _json_case("circle, 1,000,000 vertices", circle_polygon(1_000_000, 99, 0)),
        _json_case("batch of 150,000 items", [{"type": "Point"}] * 150_000, "/v1/prune/batch"),
    ]
    for name, data in png16.items():
        cases.append(
            Case(
                f"16-bit {name} PNG, levels 256 and 511",
                lambda c, d=data: c.post(
                    "/v1/prune", content=d, headers={"Content-Type": "image/png"}
                ),
                None,
                {"KB": f"{len(data) / 1024:,.0f}"},
            )
        )
    return cases


def silhouette_cases() -> list[Case]:
    from .bench_large import SHAPES, blob

    cases = [_mask_case(f"{name}, 4096² (silhouette)", blob(name, 4096)) for name in SHAPES]
    for name in ("filled disk", "heart", "cup"):
        cases.append(_mask_case(f"{name}, 256² (after)", blob(name, 256)))
    cases.append(_json_case("square polygon (after)", unit_squares(1)))
    return cases


def _answer(r: httpx.Response) -> str:
    answer = str(r.status_code)
    if r.headers.get("content-type", "").startswith("application/problem+json"):
        answer += " " + r.json()["type"].rsplit(":", 1)[-1]
    elif r.headers.get("content-type", "") == "application/x-ndjson":
        answer += f" ({len(r.text.splitlines())} lines)"
    return answer


class _Sampler(threading.Thread):
    """The largest resident set of the service's children, read every 5 ms, and their
    peak counters (``VmHWM``) read at each pass: a worker replaced after its job (killed,
    or recycled because its memory did not come back) is measured before it goes."""

    def __init__(self, server_pid: int) -> None:
        super().__init__(daemon=True)
        self.server_pid = server_pid
        self.peak = 0.0
        self.done = threading.Event()

    def run(self) -> None:
        pids: list[int] = []
        for n in itertools.count():
            if self.done.is_set():
                return
            if n % 20 == 0:  # a replacement worker joins: walking /proc costs, not often
                pids = _workers(self.server_pid)
            for pid in pids:
                self.peak = max(self.peak, _status(pid, "VmHWM:"))
            time.sleep(0.005)


def run(cases: list[Case], proc_pid: int, client: httpx.Client, budget_mib: int) -> list[list[str]]:
    rows = []
    warm = _png(np.pad(np.ones((8, 8), bool), 2))
    for case in cases:
        # a tiny job first: a worker replaced after the last case is warm again, so that
        # what it holds is what the next job starts from
        client.post("/v1/prune", content=warm, headers={"Content-Type": "image/png"})
        workers = _workers(proc_pid)
        held = max((_status(p, "VmRSS:") for p in workers), default=0.0)
        for pid in [proc_pid, *workers]:
            with contextlib.suppress(OSError):
                Path(f"/proc/{pid}/clear_refs").write_text("5")
        sampler = _Sampler(proc_pid)
        sampler.start()
        t = time.perf_counter()
        r = case.send(client)
        took = time.perf_counter() - t
        sampler.done.set()
        sampler.join()
        peak = sampler.peak
        main_peak = _status(proc_pid, "VmHWM:")
        predicted = "—" if case.estimate_mib is None else f"{held + case.estimate_mib:,.0f}"
        ratio = (
            "—"
            if case.estimate_mib is None or not r.is_success
            else f"{(held + case.estimate_mib) / peak:.2f}"
        )
        rows.append(
            [
                case.label,
                case.extra.get("KB", ""),
                case.extra.get("counts", ""),
                case.extra.get("est. s", ""),
                _answer(r),
                f"{took:.1f}",
                f"{held:,.0f}",
                predicted,
                f"{peak:,.0f}",
                ratio,
                f"{main_peak:,.0f}",
            ]
        )
        print(" | ".join(rows[-1]), flush=True)
    return rows


HEADER = [
    "input",
    "body, KB",
    "boundary px / components (or parts / positions)",
    "estimate, s",
    "answer",
    "time, s",
    "worker before, MiB",
    "predicted peak, MiB",
    "worker peak, MiB",
    "predicted / peak",
    "main process peak, MiB",
]


def main() -> None:
    settings = Settings()
    budget_mib = settings.job_memory_mb
    parts = {
        "masks": mask_cases,
        "inputs": input_cases,
        "silhouettes": silhouette_cases,
    }
    with tempfile.TemporaryDirectory() as tmp:
        log = Path(tmp) / "server.log"
        with running_server(log, workers="1", access_log="false") as (proc, base):
            client = httpx.Client(base_url=base, timeout=settings.job_timeout + 60)
            for name in PARTS:
                rows = run(parts[name](), proc.pid, client, budget_mib)
                peaks = [float(r[8].replace(",", "")) for r in rows]
                ratios = [float(r[9]) for r in rows if r[9] != "—"]
                print(f"\n{name}:\n")
                print(table(HEADER, rows))
                print(
                    f"\nMemory budget {budget_mib} MiB a job (the worker's resident set, its "
                    f"own memory included); largest worker peak: {max(peaks):,.0f} MiB "
                    f"({'under' if max(peaks) < budget_mib else 'OVER'} the budget)"
                    + (
                        f"; predicted / peak from {min(ratios):.2f} to {max(ratios):.2f} on "
                        f"the {len(ratios)} answered masks"
                        if ratios
                        else ""
                    )
                    + ".\n"
                )
            load = ", ".join(f"{x:.1f}" for x in os.getloadavg())
            print(f"load average at the end (1, 5, 15 min): {load} on {os.cpu_count()} cores")
            text = log.read_text(errors="replace")
            print(
                f"server log: {text.count('worker replaced')} worker replacements, "
                f"{text.count('MemoryError')} MemoryError, "
                f"{text.count(chr(34) + 'level' + chr(34) + ': ' + chr(34) + 'ERROR')} errors"
            )


if __name__ == "__main__":
    main()
