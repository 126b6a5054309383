"""The service's volume estimate against what pruning a volume really takes.

Each case runs in a fresh process warmed as a service worker is
(:func:`service.worker.jobs.warmup`, which loads the volume kernels too): its peak
resident memory over the warm baseline (``ru_maxrss`` against ``/proc/self/statm``) and
its time in :func:`skelprune.volume.prune_volume` plus the document, beside
:func:`skelprune.budget.volume_estimate`. The cases: a random tree of tubes
(:func:`testkit.volumes.random_tree`, thin and sparse), a ball (dense) and opened
Bernoulli noise (all surface, many components), at 96³-256³.

``python -m benchmarks volume_budget`` (a minute).
"""

from __future__ import annotations

import multiprocessing as mp
import resource
import time

import numpy as np

CASES = (("tree", 128), ("tree", 256), ("ball", 128), ("ball", 256), ("noise", 96))


def _volume(kind: str, n: int) -> np.ndarray:
    if kind == "tree":
        from testkit.volumes import random_tree

        return random_tree(1, size=n).volume()
    if kind == "ball":
        z, y, x = np.ogrid[:n, :n, :n]
        return (z - n / 2) ** 2 + (y - n / 2) ** 2 + (x - n / 2) ** 2 < (0.45 * n) ** 2
    from scipy import ndimage

    return ndimage.binary_opening(np.random.default_rng(0).random((n, n, n)) < 0.5)


def _case(kind: str, n: int, out: mp.Queue) -> None:
    from service.worker.jobs import warmup
    from skelprune.budget import resident_bytes, volume_estimate
    from skelprune.options import PruneOptions, VolumeOptions
    from skelprune.volume import prune_volume

    warmup()
    volume = _volume(kind, n)
    base = resident_bytes()
    cost = volume_estimate(volume)
    t0 = time.perf_counter()
    prune_volume(volume, PruneOptions(), VolumeOptions()).to_dict()
    took = time.perf_counter() - t0
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024 - base
    out.put((int(np.count_nonzero(volume)), took, cost.seconds, peak, cost.bytes))


def main() -> None:
    ctx = mp.get_context("spawn")
    print("| volume | inside | s | estimate s | peak MiB | estimate MiB | estimate / peak |")
    print("|---|---|---|---|---|---|---|")
    for kind, n in CASES:
        out: mp.Queue = ctx.Queue()
        proc = ctx.Process(target=_case, args=(kind, n, out))
        proc.start()
        inside, took, est_s, peak, est_b = out.get()
        proc.join()
        print(
            f"| {kind} {n}³ | {inside:,} | {took:.2f} | {est_s:.2f} | {peak / 2**20:.0f} | "
            f"{est_b / 2**20:.0f} | {est_b / max(peak, 1):.2f} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
