"""Large shapes: the default pipeline on silhouettes filling 1024, 2048 and 4096 px.

The library benchmark stops at 512 × 512; the service accepts up to
``SKELPRUNE_MAX_PIXELS`` (4096²)
under a 30 s job limit. The shapes: blob-like ones, whose maximal disks are huge (a
filled disk, a filled square, and kimia216's heart-1 and brick-3 scaled up), and three
kimia216 silhouettes (bird-10, car-6, hammer-3). Each shape at each size runs in a fresh
process, so that its peak memory is its own; in the same process and on the same mask,
``scipy.ndimage.distance_transform_edt`` is timed as the yardstick (the pipeline needs
an exact distance transform anyway, so it cannot be faster than that).

The drawn shapes (apple, heart, cup, holed blob) are rasterised small and scaled up, as
a scanned silhouette is: their softened staircase boundary gives hundreds of branches
with huge disks, the slow case for the pruning. After the table, the slowest shape is run
once more under cProfile and its top entries printed.

Each shape is timed with the default options and with ``trim=False`` (the tips'
cut off), which shows the other stages alone. ``SKELPRUNE_BENCH_TRIM=off`` times only
the latter (the tips' cut of a 4096-px blob can take minutes), and
``SKELPRUNE_BENCH_SIZES=1024,2048`` picks the sizes.

``python -m benchmarks large`` (about ten minutes on one core).
"""

from __future__ import annotations

import cProfile
import io
import multiprocessing as mp
import os
import pstats
import resource
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from .common import DATA, table, upscale

SIZES = tuple(int(s) for s in os.environ.get("SKELPRUNE_BENCH_SIZES", "1024,2048,4096").split(","))
#: Whether the default options are timed too, or ``trim=False`` only.
DEFAULT_TOO = os.environ.get("SKELPRUNE_BENCH_TRIM", "both") != "off"
SHAPES = (
    "filled disk",
    "filled square",
    "heart-1",
    "brick-3",
    "bird-10",
    "car-6",
    "hammer-3",
    "apple",
    "heart",
    "cup",
    "holed blob",
    "octopus",
    "holed disk",
)


def _polar(size: int, radius) -> np.ndarray:
    """The pixels within ``radius(θ)`` (a fraction of the half frame) of the centre."""
    yy, xx = np.mgrid[:size, :size]
    c = (size - 1) / 2
    dy, dx = (yy - c) / (size / 2 - 2), (xx - c) / (size / 2 - 2)
    return np.hypot(dy, dx) <= radius(np.arctan2(-dy, dx))


#: Side at which the drawn silhouettes (apple, heart, cup, holed blob) are rasterised
#: before they are scaled up like the kimia shapes: a scanned silhouette scaled up has
#: the softened staircase boundary that makes many small branches with large disks.
DRAWN = 160


def blob(name: str, size: int) -> np.ndarray:
    """``name`` (a shape of SHAPES) filling a ``size``-px frame."""
    if name in ("apple", "heart", "cup", "holed blob", "octopus"):
        return upscale(_drawn(name, DRAWN), size)
    if name in ("filled disk", "holed disk"):
        yy, xx = np.mgrid[:size, :size]
        c = (size - 1) / 2
        disk = (yy - c) ** 2 + (xx - c) ** 2 <= (size / 2 - 2) ** 2
        if name == "holed disk":  # five round holes of different sizes
            for cy, cx, rad in (
                (-0.4, -0.3, 0.12),
                (0.35, -0.4, 0.08),
                (0.1, 0.45, 0.18),
                (-0.45, 0.35, 0.06),
                (0.45, 0.2, 0.1),
            ):
                disk &= np.hypot(yy / (size / 2) - 1 - cy, xx / (size / 2) - 1 - cx) > rad
        return disk
    if name == "filled square":
        mask = np.zeros((size, size), bool)
        mask[2:-2, 2:-2] = True
        return mask
    from PIL import Image

    with Image.open(DATA / "kimia216" / f"{name}.png") as im:
        return upscale(np.asarray(im) > 0, size)


def _drawn(name: str, size: int) -> np.ndarray:
    yy, xx = np.mgrid[:size, :size] / (size / 2) - 1.0  # the frame as [-1, 1]²
    if name == "apple":  # round, a dimple at the top and one at the bottom, a stem
        body = _polar(
            size,
            lambda t: (
                0.86
                - 0.16 * np.exp(-(((t - np.pi / 2) / 0.35) ** 2))
                - 0.05 * np.exp(-(((t + np.pi / 2) / 0.3) ** 2))
                + 0.04 * np.cos(2 * t)
            ),
        )
        stem = (np.abs(xx - 0.03 + 0.1 * (yy + 0.8)) < 0.03) & (yy > -0.95) & (yy < -0.6)
        return body | stem
    if name == "heart":  # the classic implicit heart curve
        x, y = 1.15 * xx, -1.15 * yy + 0.15
        return (x * x + y * y - 1) ** 3 - x * x * y**3 <= 0
    if name == "cup":  # a tapered body with a ring handle: one hole
        body = (np.abs(xx + 0.2) < 0.55 - 0.12 * (yy + 0.8) / 1.6) & (np.abs(yy) < 0.8)
        ring = np.hypot(yy + 0.05, xx - 0.45) / 0.42
        return body | ((ring > 0.6) & (ring < 1.0) & (xx > 0.2))
    if name == "octopus":  # a round body with eight wavy arms
        return _polar(
            size,
            lambda t: 0.3 + 0.6 * (0.5 + 0.5 * np.cos(8 * t + 0.3 * np.sin(3 * t))) ** 2.5,
        )
    if name == "holed blob":  # a wobbly disc with three round holes
        outer = _polar(size, lambda t: 0.85 + 0.08 * np.sin(3 * t) + 0.04 * np.cos(5 * t))
        holes = np.zeros_like(outer)
        for cy, cx, rad in ((-0.35, -0.3, 0.16), (0.3, -0.25, 0.12), (0.05, 0.4, 0.2)):
            holes |= np.hypot(yy - cy, xx - cx) < rad
        return outer & ~holes
    raise ValueError(name)


def _run(name: str, size: int, repeat: int, out: mp.Queue) -> None:
    import importlib

    from scipy import ndimage

    import skelprune

    medial_axis = importlib.import_module("skelprune.grid.medial_axis")
    from skelprune.api import components

    skelprune.prune(blob("filled square", 64))  # loads the compiled kernels
    mask = blob(name, size)
    total, untrimmed, edt = [], [], []
    for _ in range(repeat):  # interleaved, so that a slow spell hits all
        if DEFAULT_TOO:
            t = time.perf_counter()
            skelprune.prune(mask).to_dict()
            total.append(time.perf_counter() - t)
        t = time.perf_counter()
        skelprune.prune(mask, trim=False).to_dict()
        untrimmed.append(time.perf_counter() - t)
        t = time.perf_counter()
        ndimage.distance_transform_edt(mask)
        edt.append(time.perf_counter() - t)
    crop = components(mask)[0][0]
    t = time.perf_counter()
    medial_axis.medial_axis(crop)
    axis = time.perf_counter() - t
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    out.put(
        (
            float(np.median(total)) if total else float("nan"),
            float(np.median(untrimmed)),
            float(np.median(edt)),
            axis,
            rss,
        )
    )


def _profile(name: str, size: int, out: mp.Queue) -> None:
    import skelprune

    skelprune.prune(blob("filled square", 64))  # loads the compiled kernels
    mask = blob(name, size)
    prof = cProfile.Profile()
    prof.enable()
    skelprune.prune(mask, trim=DEFAULT_TOO).to_dict()
    prof.disable()
    text = io.StringIO()
    pstats.Stats(prof, stream=text).sort_stats("tottime").print_stats(PROFILE_TOP)
    out.put(text.getvalue())


#: Entries of the slowest shape's profile that are printed.
PROFILE_TOP = 10


def _in_process(target: Callable[..., None], *args: object) -> Any:
    """Run ``target(*args, queue)`` in a fresh process; return what it put."""
    ctx = mp.get_context("spawn")
    out: mp.Queue = ctx.Queue()
    proc = ctx.Process(target=target, args=(*args, out))
    proc.start()
    answer = out.get()
    proc.join()
    return answer


def main() -> None:
    rows = []
    slowest = (0.0, "", 0)
    for size in SIZES:
        repeat = 3 if size <= 2048 else 1
        for name in SHAPES:
            total, untrimmed, edt, axis, rss = _in_process(_run, name, size, repeat)
            slowest = max(slowest, (total if DEFAULT_TOO else untrimmed, name, size))
            rows.append(
                [f"{size} px", name]
                + ([f"{total:.2f}", f"{total / edt:.1f}×"] if DEFAULT_TOO else [])
                + [
                    f"{untrimmed:.2f}",
                    f"{untrimmed / edt:.1f}×",
                    f"{edt:.2f}",
                    f"{100 * axis / untrimmed:.0f} %",
                    f"{rss:.0f}",
                ]
            )
    print(
        table(
            ["longest side", "shape"]
            + (["pipeline, s", "ratio to EDT"] if DEFAULT_TOO else [])
            + [
                "trim off, s",
                "trim off: ratio to EDT",
                "EDT alone, s",
                "medial axis / trim off",
                "peak RSS, MB",
            ],
            rows,
        )
    )
    print("\nmedian of 3 runs at 1024 and 2048 px, one run at 4096 px; one core")
    _, name, size = slowest
    lines = _in_process(_profile, name, size).splitlines()
    top = [line for line in lines if line.strip()][-PROFILE_TOP - 1 :]
    how = "default options" if DEFAULT_TOO else "trim=False"
    print(f"\nslowest: {name} at {size} px ({how}), cProfile, top {PROFILE_TOP} by own time:\n")
    print("\n".join(top))
