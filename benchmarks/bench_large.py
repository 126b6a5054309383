"""Large shapes: the default pipeline on kimia216 silhouettes scaled to fill 1024–4096 px.

SPEC §5 stops at 512 × 512; the service accepts up to ``SKELPRUNE_MAX_PIXELS`` (4096²)
under a 30 s job limit, so this shows how close a full-frame mask comes to it. Each size
runs in a fresh process (one shape after the other, one run each: a 4096-px shape takes
seconds), which also gives the peak memory of that process.

``python -m benchmarks large`` (about a minute and a half on one core).
"""

from __future__ import annotations

import multiprocessing as mp
import resource
import time

import numpy as np

from .common import dataset, table, upscale

SIZES = (1024, 2048, 4096)
SHAPES = (0, 57, 140)  # bird-10, car-6, hammer-3: indices into sorted kimia216


def _run(size: int, out: mp.Queue) -> None:
    import importlib

    import skelprune

    medial_axis = importlib.import_module("skelprune.medial_axis")
    from skelprune.api import components

    masks = dataset("kimia216")
    skelprune.prune(upscale(masks[0], 128))  # JIT warm-up (numba's disk cache)
    total, axis = [], []
    for i in SHAPES:
        mask = upscale(masks[i], size)
        t = time.perf_counter()
        skelprune.prune(mask).to_dict()
        total.append(time.perf_counter() - t)
        crop = components(mask)[0][0]
        t = time.perf_counter()
        medial_axis.medial_axis(crop)
        axis.append(time.perf_counter() - t)
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    out.put((float(np.median(total)), float(np.median(axis)), rss))


def main() -> None:
    ctx = mp.get_context("spawn")
    rows = []
    for size in SIZES:
        out: mp.Queue = ctx.Queue()
        proc = ctx.Process(target=_run, args=(size, out))
        proc.start()
        total, axis, rss = out.get()
        proc.join()
        rows.append([f"{size} px", f"{total:.2f}", f"{axis:.2f}", f"{100 * axis / total:.0f} %",
                     f"{rss:.0f}"])
    print(table(["longest side", "s a shape (median of 3)", "medial axis alone, s",
                 "share", "peak RSS, MB"], rows))
