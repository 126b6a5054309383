"""The service's memory estimate for ``scope="local"`` against what a job really takes.

Each case runs in a fresh process warmed as a service worker is
(:func:`service.worker.jobs.warmup`): the mask is read as a worker reads a job (the
networks cleaned with ``fill_holes=64``, ``min_area=64``), estimated
(:func:`skelprune.budget.estimate` with the scope) and pruned with ``scope="local"``; its
peak resident memory over the warm baseline against the estimate. The cases: the drawn
road, vessel and crack networks of :mod:`testkit.networks` at the sizes of
``SKELPRUNE_NETWORK_SIZES`` (default ``4096,8192``), and 50 % pixel noise at 2048²
(the estimate's worst case: every pixel a boundary, thousands of components).

``python -m benchmarks local_budget`` (a few minutes: the noise alone takes a minute).
"""

from __future__ import annotations

import multiprocessing as mp
import os
import resource
import time

import numpy as np

SIZES = tuple(int(s) for s in os.environ.get("SKELPRUNE_NETWORK_SIZES", "4096,8192").split(","))
CASES = [(kind, size) for size in SIZES for kind in ("road", "vessel", "crack")] + [("noise", 2048)]


def _mask(kind: str, size: int) -> np.ndarray:
    if kind == "noise":
        return np.random.default_rng(0).random((size, size)) < 0.5
    from testkit.networks import network

    return network(kind, size, seed=1).mask


def _case(kind: str, size: int, out: mp.Queue) -> None:
    from service.worker.jobs import warmup
    from skelprune.api import prune_input
    from skelprune.budget import estimate, resident_bytes
    from skelprune.io.input import read_input
    from skelprune.options import PruneOptions, ReadOptions

    warmup()
    mask = _mask(kind, size)
    clean = 0 if kind == "noise" else 64
    base = resident_bytes()
    t0 = time.perf_counter()
    shape = read_input(mask, read=ReadOptions(fill_holes=clean, min_area=clean))
    cost = estimate(shape.mask, scope="local")
    prune_input(shape, PruneOptions(scope="local")).to_dict()
    took = time.perf_counter() - t0
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024 - base
    out.put((took, peak, cost.bytes, estimate(shape.mask).bytes))


def main() -> None:
    ctx = mp.get_context("spawn")
    print("| mask | s | peak MiB | estimate MiB | estimate / peak | global estimate MiB |")
    print("|---|---|---|---|---|---|")
    for kind, size in CASES:
        out: mp.Queue = ctx.Queue()
        proc = ctx.Process(target=_case, args=(kind, size, out))
        proc.start()
        took, peak, est, est_global = out.get()
        proc.join()
        print(
            f"| {kind} {size}² | {took:.1f} | {peak / 2**20:.0f} | {est / 2**20:.0f} | "
            f"{est / max(peak, 1):.2f} | {est_global / 2**20:.0f} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
