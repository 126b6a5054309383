"""A 512³ label volume of 400 touching tubes, pruned as a long job by a real server.

``python -m benchmarks longjobs`` builds the volume (20 × 20 wavy tubes along x, each
its own 16-bit label, each touching its neighbours: their cross-sections are the
Voronoi cells of the tubes' centres, clipped to a disc), starts ``python -m service``
on loopback with the limits such a volume needs (the pixel and body limits raised to
its 512³ voxels and 256-MiB ``.npy``, the job memory budget to 8 GiB), submits it to
``POST /v1/prune`` with ``Prefer: respond-async``, and polls ``GET /v1/jobs/{id}``
every second until it is done. It prints the answer's time (202, first progress, done),
the progress seen over time, the workers' peak resident memory (sampled from ``/proc``
while it runs), the result's size and components, and that the synchronous route
refuses the same volume on its time estimate or times out (504) within its limit.

``--side N --tubes K`` run a smaller volume (``--side 256 --tubes 10``: a minute).
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import httpx
import numpy as np

from testkit.label_volumes import npy_bytes, touching_tubes
from testkit.procs import descendants, rss_mib
from testkit.realserver import running_server

from .common import table

SIDE = 512
TUBES = 20  # per side: 400 tubes
POLL_SECONDS = 1.0


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m benchmarks longjobs")
    parser.add_argument("--side", type=int, default=SIDE)
    parser.add_argument("--tubes", type=int, default=TUBES, help="tubes per side")
    args = parser.parse_args(argv or [])
    t0 = time.perf_counter()
    volume = touching_tubes(args.side, args.tubes)
    body = npy_bytes(volume)
    labels = len(np.unique(volume)) - 1
    built = time.perf_counter() - t0
    del volume
    print(
        f"volume: {args.side}³ voxels, {labels} labels, .npy of {len(body) / 2**20:.0f} MiB, "
        f"built in {built:.1f} s"
    )
    with (
        tempfile.TemporaryDirectory() as tmp,
        running_server(
            Path(tmp) / "server.log",
            workers="2",
            max_pixels=str(args.side**3),
            max_body_bytes=str(len(body) + 2**20),
            job_memory_mb="8192",
            main_memory_mb="4096",
        ) as (proc, base),
    ):
        client = httpx.Client(base_url=base, timeout=120)
        headers = {"content-type": "application/x-npy", "prefer": "respond-async"}
        t0 = time.perf_counter()
        accepted = client.post("/v1/prune", content=body, headers=headers)
        t_accepted = time.perf_counter() - t0
        assert accepted.status_code == 202, accepted.text
        url = accepted.headers["location"]
        seen: list[tuple[float, str, int, int]] = []
        peak = 0.0
        first_progress = None
        while True:
            status = client.get(url).json()
            now = time.perf_counter() - t0
            done, total = status["progress"]["done"], status["progress"]["total"]
            if not seen or seen[-1][1:] != (status["state"], done, total):
                seen.append((now, status["state"], done, total))
            if first_progress is None and total:
                first_progress = now
            workers = descendants(proc.pid)
            peak = max([peak, *(rss_mib(p) for p in workers)])
            if status["state"] not in ("queued", "running"):
                break
            time.sleep(POLL_SECONDS)
        t_done = time.perf_counter() - t0
        result = client.get(url + "/result")
        print(
            f"state {status['state']}, result {result.status_code} "
            f"{result.headers.get('content-type')}, {len(result.content) / 2**20:.1f} MiB"
        )
        components = len(result.json().get("components", [])) if result.is_success else 0
        sync = client.post("/v1/prune", content=body, headers={"content-type": "application/x-npy"})
        sync_problem = sync.json().get("type", "") if sync.status_code >= 400 else ""
    step = max(1, len(seen) // 12)
    shown = [*seen[::step], seen[-1]] if seen[-1] not in seen[::step] else seen[::step]
    print(
        table(["t (s)", "state", "done", "total"], [[f"{t:.1f}", s, d, n] for t, s, d, n in shown])
    )
    print(
        table(
            [
                "202 after (s)",
                "total known (s)",
                "done (s)",
                "components",
                "worker peak RSS (MiB)",
                "sync route",
            ],
            [
                [
                    f"{t_accepted:.1f}",
                    f"{first_progress:.1f}" if first_progress is not None else "-",
                    f"{t_done:.1f}",
                    components,
                    f"{peak:.0f}",
                    f"{sync.status_code} {sync_problem.rsplit(':', 1)[-1]}",
                ]
            ],
        )
    )
    print(f"cores: {os.cpu_count()}; polled every {POLL_SECONDS:g} s")


if __name__ == "__main__":
    import sys

    main(sys.argv[1:])
