"""HTTP service vs the library, on loopback (the speed targets).

1. Round trip: one client, sequential ``POST /v1/prune`` of a 256 × 256 PNG to a real
   ``python -m service`` process, against the direct library call on the same PNG in
   this process (decode + prune + document, the same work the service does).
   Target: ratio of medians ≤ 1.2. Beside it, the server process's own CPU time per
   request (Linux): the fixed cost the ratio pays, and a figure that a busy shared
   machine disturbs less than the wall-clock ratio.
2. Throughput: the same requests from ``2 × workers`` concurrent clients, to a server
   with 1 worker and to one with 2 workers, both up at once and measured in alternating
   rounds (the median of the per-round ratios, so that a slow spell of a shared machine
   falls on both). Target: ≥ 1.8× jobs/s. Beside it, the bound this machine sets when
   the load client and the server run on the same 2 cores as the workers: with ``w`` the
   worker's CPU a job and ``o`` the server's and client's, 2 workers reach at most
   ``2 / (w + o)`` jobs/s and 1 worker ``1 / w``, so the ratio is at most ``2w / (w + o)``.

Run: ``python -m benchmarks service`` (or ``python -m benchmarks.bench_service``).
Bounded: fixed request counts, every request with a timeout.
"""

from __future__ import annotations

import io
import json
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import httpx
import numpy as np
from PIL import Image

import skelprune
from skelprune.io.png import read_mask
from testkit.realserver import running_server, stop

from .common import DATA, table, upscale

REPO = Path(__file__).resolve().parents[1]
ROUND_TRIPS = 20
THROUGHPUT_JOBS = 24
THROUGHPUT_ROUNDS = 5
SHAPE = "kimia216/elephant-1.png"


def shape_png(side: int = 256) -> bytes:
    """A kimia shape rescaled to fit a ``side`` × ``side`` image with a small border."""
    mask = np.asarray(Image.open(DATA / SHAPE)) > 0
    inner = upscale(mask, side - 8)
    canvas = np.zeros((side, side), dtype=np.uint8)
    r0 = (side - inner.shape[0]) // 2
    c0 = (side - inner.shape[1]) // 2
    canvas[r0 : r0 + inner.shape[0], c0 : c0 + inner.shape[1]] = inner * 255
    buf = io.BytesIO()
    Image.fromarray(canvas).save(buf, "PNG")
    return buf.getvalue()


@contextmanager
def server(workers: int) -> Iterator[tuple[str, int]]:
    """A real ``python -m service`` on a free loopback port: its base URL and process ID.

    Stopped (SIGINT) on exit.
    """
    with (
        tempfile.TemporaryDirectory() as tmp,
        running_server(Path(tmp) / "server.log", workers=str(workers), queue_size="256") as (
            proc,
            base,
        ),
    ):
        yield base, proc.pid
        stop(proc, signal.SIGINT, 30)


def cpu_seconds(pid: int) -> float | None:
    """CPU time of process ``pid`` so far, all its threads (living or not), in seconds;
    None where it cannot be read. The pool's workers are other processes: not counted.

    Linux's per-process CPU clock, the id that ``clock_getcpuclockid(pid)`` returns (which
    Python lacks): nanosecond resolution, where ``/proc/<pid>/stat`` counts 10 ms ticks.
    """
    try:
        return time.clock_gettime(((~pid) << 3) | 2)  # MAKE_PROCESS_CPUCLOCK(pid, SCHED)
    except (OSError, OverflowError, AttributeError):
        return None


def _post(client: httpx.Client, png: bytes) -> None:
    resp = client.post("/v1/prune", content=png, headers={"content-type": "image/png"})
    resp.raise_for_status()


def paired_ms(
    base: str, png: bytes, n: int, pid: int | None = None
) -> tuple[list[float], list[float], list[float], float | None]:
    """Interleaved timings, so that a noisy machine hits both sides alike.

    Returns HTTP round trips, direct library calls (decode + prune + to_dict + JSON, the
    work the service does), library calls on a decoded mask (prune + to_dict), and the
    CPU milliseconds per request of the server process ``pid`` (None if not measured).
    """
    mask = read_mask(png)
    http, full, core = [], [], []
    with httpx.Client(base_url=base, timeout=60) as client:
        for _ in range(3):  # warm the connection, the worker and this process's JIT
            _post(client, png)
            skelprune.prune(mask).to_dict()
        cpu0 = cpu_seconds(pid) if pid is not None else None
        for _ in range(n):
            t = time.perf_counter()
            _post(client, png)
            http.append(1000 * (time.perf_counter() - t))
            t = time.perf_counter()
            json.dumps(skelprune.prune(read_mask(png)).to_dict())
            full.append(1000 * (time.perf_counter() - t))
            t = time.perf_counter()
            skelprune.prune(mask).to_dict()
            core.append(1000 * (time.perf_counter() - t))
        cpu1 = cpu_seconds(pid) if pid is not None else None
    # the server idles while this process runs the library: all its CPU is the requests'
    server_ms = None if cpu0 is None or cpu1 is None else 1000 * (cpu1 - cpu0) / n
    return http, full, core, server_ms


def throughput(clients: list[httpx.Client], png: bytes, jobs: int) -> float:
    """Jobs per second with one thread per client sharing ``jobs`` requests.

    The clients are made by the caller, outside the timing: an ``httpx.Client`` costs about
    90 ms of CPU to build (its TLS context), which on 2 cores would be taken from the
    workers being measured.
    """
    remaining = list(range(jobs))
    lock = threading.Lock()
    errors: list[BaseException] = []

    def client_loop(client: httpx.Client) -> None:
        _post(client, png)  # each client's first request is counted too (see return)
        while True:
            with lock:
                if not remaining:
                    return
                remaining.pop()
            try:
                _post(client, png)
            except BaseException as exc:  # reported after the run
                errors.append(exc)
                return

    threads = [threading.Thread(target=client_loop, args=(c,)) for c in clients]
    t = time.perf_counter()
    for th in threads:
        th.start()
    for th in threads:
        th.join(600)
    elapsed = time.perf_counter() - t
    if errors:
        raise RuntimeError(f"throughput run failed: {errors[0]!r}")
    return (jobs + len(clients)) / elapsed


def machine_parallelism(n: int = 5_000_000) -> float:
    """Speed-up of 2 busy-looping processes over 1, right now: the ceiling for 2 workers.

    On a shared or throttled machine this is below 2, and so is any pool's gain.
    """
    code = f"s = 0\nfor i in range({n}): s += i"

    def timed(k: int) -> float:
        t = time.perf_counter()
        procs = [subprocess.Popen([sys.executable, "-S", "-c", code]) for _ in range(k)]
        for p in procs:
            p.wait(120)
        return time.perf_counter() - t

    one = timed(1)
    return 2 * one / timed(2)


def main() -> None:
    png = shape_png()
    with server(1) as (base, pid), server(2) as (base2, _):
        http, lib_full, lib_core, server_cpu = paired_ms(base, png, ROUND_TRIPS, pid)
        tput1, tput2, ratios = [], [], []
        clients1 = [httpx.Client(base_url=base, timeout=120) for _ in range(2)]
        clients2 = [httpx.Client(base_url=base2, timeout=120) for _ in range(4)]
        try:
            client0 = time.process_time()
            for _ in range(THROUGHPUT_ROUNDS):
                tput1.append(throughput(clients1, png, THROUGHPUT_JOBS))
                tput2.append(throughput(clients2, png, THROUGHPUT_JOBS))
                ratios.append(tput2[-1] / tput1[-1])
            # every round: the jobs of both servers, plus each client's first request
            jobs = THROUGHPUT_ROUNDS * (2 * THROUGHPUT_JOBS + len(clients1) + len(clients2))
            client_ms = 1000 * (time.process_time() - client0) / jobs
        finally:
            for c in clients1 + clients2:
                c.close()
    ceiling = machine_parallelism()
    med = statistics.median
    overhead = client_ms + (server_cpu or 0.0)
    rows: list[list[object]] = [
        ["library: decode + prune + to_dict + json (ms)", med(lib_full), ""],
        ["library: prune + to_dict (ms)", med(lib_core), ""],
        ["HTTP round trip, 1 worker (ms)", med(http), ""],
        ["ratio HTTP / library (decode..json)", med(http) / med(lib_full), "≤ 1.2"],
        ["ratio HTTP / library (prune + to_dict)", med(http) / med(lib_core), ""],
        ["server process CPU per request (ms)", "n/a" if server_cpu is None else server_cpu, ""],
        ["load client CPU per request (ms)", client_ms, ""],
        ["throughput 1 worker (jobs/s, median of rounds)", med(tput1), ""],
        ["throughput 2 workers (jobs/s, median of rounds)", med(tput2), ""],
        ["ratio 2 / 1 workers (median of per-round ratios)", med(ratios), "≥ 1.8"],
        [
            "bound on 2 cores shared with server and client: 2w / (w + o)",
            2 * med(lib_full) / (med(lib_full) + overhead),
            "",
        ],
        ["machine ceiling: 2 / 1 busy processes", ceiling, "(2 if idle)"],
    ]
    load = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    print(
        f"shape: {SHAPE} in 256×256, {ROUND_TRIPS} round trips, {THROUGHPUT_ROUNDS} "
        f"alternating rounds of {THROUGHPUT_JOBS} jobs per throughput measure, "
        f"{os.cpu_count()} CPUs, load average {load}\n"
    )
    print(table(["measure", "median / value", "target"], rows))
