"""Large shapes: the default pipeline on silhouettes filling 1024, 2048 and 4096 px.

The library benchmark stops at 512 × 512; the service accepts up to
``SKELPRUNE_MAX_PIXELS`` (4096²)
under a 30 s job limit. The shapes: blob-like ones, whose maximal disks are huge (a
filled disk, a filled square, and kimia216's heart-1 and brick-3 scaled up), and three
kimia216 silhouettes (bird-10, car-6, hammer-3). Each shape at each size runs in a fresh
process, so that its peak memory is its own; in the same process and on the same mask,
``scipy.ndimage.distance_transform_edt`` is timed as the yardstick (the pipeline needs
an exact distance transform anyway, so it cannot be faster than that).

The drawn shapes (apple, heart, cup, holed blob, octopus, teddy, horseshoe) are
rasterised small and scaled up, as a scanned silhouette is: their softened staircase
boundary gives hundreds of branches with huge disks, the slow case for the pruning.
After the table, the slowest shape is run once more under cProfile and its top entries
printed; the last three columns are the CPU seconds of the pruning runs (both option
sets when both are timed: what a job's process spends, whatever the machine's load), the
service's time estimate (:func:`skelprune.budget.estimate`) and the one over the other.

Each shape is timed with the default options and with ``trim=False`` (the tips'
cut off), which shows the other stages alone. ``SKELPRUNE_BENCH_TRIM=off`` times only
the latter and ``on`` only the former, and
``SKELPRUNE_BENCH_SIZES=1024,2048`` picks the sizes.

``SKELPRUNE_BENCH_SHAPES=apple,cup`` picks the shapes, ``SKELPRUNE_BENCH_REPEAT=5`` the runs
per shape (median; default 3 up to 2048 px, 1 above). ``SKELPRUNE_BENCH_BEFORE=DIR`` also
times the checkout in ``DIR`` (another version of the library, e.g. ``git archive`` of an
older commit unpacked there) on the same masks, its runs interleaved with this tree's, and
prints both times, each one's ratio to the EDT of its own process, and the speed-up.

``python -m benchmarks large`` (about ten minutes on one core); the large blobs against an
older commit: ``SKELPRUNE_BENCH_SIZES=2048,4096 SKELPRUNE_BENCH_TRIM=on
SKELPRUNE_BENCH_SHAPES=apple,octopus,cup,teddy,heart,horseshoe
SKELPRUNE_BENCH_BEFORE=/tmp/base python -m benchmarks large``.
"""

from __future__ import annotations

import cProfile
import io
import json
import multiprocessing as mp
import os
import pstats
import subprocess
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from skelprune.budget import estimate

from .common import DATA, table, upscale

SIZES = tuple(int(s) for s in os.environ.get("SKELPRUNE_BENCH_SIZES", "1024,2048,4096").split(","))
#: Whether the default options are timed too, or ``trim=False`` only (``off``), or the
#: default options only (``on``).
DEFAULT_TOO = os.environ.get("SKELPRUNE_BENCH_TRIM", "both") != "off"
UNTRIMMED_TOO = os.environ.get("SKELPRUNE_BENCH_TRIM", "both") != "on"
#: Another checkout timed on the same masks (``SKELPRUNE_BENCH_BEFORE``), or none.
BEFORE = os.environ.get("SKELPRUNE_BENCH_BEFORE") or None
REPEAT = int(os.environ.get("SKELPRUNE_BENCH_REPEAT", "0"))
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
    "teddy",
    "horseshoe",
)
if os.environ.get("SKELPRUNE_BENCH_SHAPES"):
    SHAPES = tuple(os.environ["SKELPRUNE_BENCH_SHAPES"].split(","))


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
    if name in ("apple", "heart", "cup", "holed blob", "octopus", "teddy", "horseshoe"):
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
    if name == "teddy":  # a round belly, a head, two ears, two arms and two legs
        parts = [(0.25, 0.0, 0.5, 0.45), (-0.45, 0.0, 0.33, 0.33)]  # (y, x, ry, rx)
        parts += [(-0.72, s * 0.28, 0.13, 0.13) for s in (-1, 1)]
        parts += [(0.05, s * 0.52, 0.13, 0.3) for s in (-1, 1)]
        parts += [(0.72, s * 0.3, 0.2, 0.17) for s in (-1, 1)]
        out = np.zeros_like(xx, dtype=bool)
        for cy, cx, ry, rx in parts:
            out |= ((yy - cy) / ry) ** 2 + ((xx - cx) / rx) ** 2 <= 1
        return out
    if name == "horseshoe":  # a thick arc open at the bottom, round-ended
        rad, ang = np.hypot(yy + 0.05, xx), np.arctan2(-(yy + 0.05), xx)
        arc = (np.abs(rad - 0.62) < 0.24) & (ang > -np.pi / 2 + 0.8) | (
            (np.abs(rad - 0.62) < 0.24) & (ang < -np.pi / 2 - 0.8)
        )
        for t in (-np.pi / 2 + 0.8, -np.pi / 2 - 0.8):  # the round ends
            ey, ex = -0.05 - 0.62 * np.sin(t), 0.62 * np.cos(t)
            arc |= np.hypot(yy - ey, xx - ex) < 0.24
        return arc
    if name == "holed blob":  # a wobbly disc with three round holes
        outer = _polar(size, lambda t: 0.85 + 0.08 * np.sin(3 * t) + 0.04 * np.cos(5 * t))
        holes = np.zeros_like(outer)
        for cy, cx, rad in ((-0.35, -0.3, 0.16), (0.3, -0.25, 0.12), (0.05, 0.4, 0.2)):
            holes |= np.hypot(yy - cy, xx - cx) < rad
        return outer & ~holes
    raise ValueError(name)


#: One shape's timing in a fresh process of one checkout (its working directory): the
#: mask from a file, so that both checkouts time the same pixels; a run on a smaller copy
#: of it first loads (or compiles) every kernel it needs. Prints JSON.
_CHILD = """
import json, resource, sys, time
import numpy as np
from scipy import ndimage
import skelprune
from skelprune.api import components
mask = np.load(sys.argv[1])
repeat, default_too, untrimmed_too = int(sys.argv[2]), sys.argv[3] == "1", sys.argv[4] == "1"
skelprune.prune(mask[::8, ::8]).to_dict()
skelprune.prune(mask[::8, ::8], trim=False).to_dict()
total, untrimmed, edt, cpu = [], [], [], []
for _ in range(repeat):  # interleaved, so that a slow spell hits all
    c = time.process_time()
    if default_too:
        t = time.perf_counter()
        skelprune.prune(mask).to_dict()
        total.append(time.perf_counter() - t)
    if untrimmed_too:
        t = time.perf_counter()
        skelprune.prune(mask, trim=False).to_dict()
        untrimmed.append(time.perf_counter() - t)
    cpu.append(time.process_time() - c)
    t = time.perf_counter()
    ndimage.distance_transform_edt(mask)
    edt.append(time.perf_counter() - t)
axis = float("nan")
try:
    from skelprune.grid.medial_axis import medial_axis
    crop = components(mask)[0][0]
    t = time.perf_counter()
    medial_axis(crop)
    axis = time.perf_counter() - t
except ImportError:  # (a checkout whose medial axis lives elsewhere)
    pass
med = lambda v: float(np.median(v)) if v else float("nan")
print(json.dumps([med(total), med(untrimmed), med(edt), axis,
                  resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, med(cpu)]))
"""


def _run(tree: str, mask_file: str, repeat: int) -> tuple[float, float, float, float, float, float]:
    """Time one mask in a fresh process of the checkout ``tree``: (pipeline, trim off,
    EDT, medial axis, peak RSS in MB, CPU seconds of the pruning runs), medians of
    ``repeat`` runs."""
    env = {**os.environ, "PYTHONPATH": tree}
    args = [mask_file, str(repeat), str(int(DEFAULT_TOO)), str(int(UNTRIMMED_TOO))]
    out = subprocess.run(
        [sys.executable, "-c", _CHILD, *args],
        cwd=tree,
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    total, untrimmed, edt, axis, rss, cpu = json.loads(out.stdout.strip().splitlines()[-1])
    return total, untrimmed, edt, axis, rss, cpu


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


def _cells(t: float, edt: float) -> list[str]:
    return [f"{t:.2f}", f"{t / edt:.1f}×"]


def main() -> None:
    rows = []
    slowest = (0.0, "", 0)
    here = str(Path(__file__).resolve().parents[1])
    with tempfile.TemporaryDirectory() as tmp:
        for size in SIZES:
            repeat = REPEAT or (3 if size <= 2048 else 1)
            for name in SHAPES:
                mask_file = os.path.join(tmp, f"{name}-{size}.npy")
                mask = blob(name, size)
                np.save(mask_file, mask)
                guess = estimate(mask).seconds
                before = _run(BEFORE, mask_file, repeat) if BEFORE else None
                total, untrimmed, edt, axis, rss, cpu = _run(here, mask_file, repeat)
                timed = total if DEFAULT_TOO else untrimmed
                slowest = max(slowest, (timed, name, size))
                row = [f"{size} px", name]
                if before is not None:
                    b_timed = before[0] if DEFAULT_TOO else before[1]
                    row += [*_cells(b_timed, before[2]), f"{b_timed / timed:.1f}×"]
                if DEFAULT_TOO:
                    row += _cells(total, edt)
                if UNTRIMMED_TOO:
                    row += _cells(untrimmed, edt)
                row += [f"{edt:.2f}", f"{100 * axis / timed:.0f} %", f"{rss:.0f}"]
                row += [f"{cpu:.2f}", f"{guess:.1f}", f"{cpu / guess:.2f}"]
                rows.append(row)
    how = "pipeline" if DEFAULT_TOO else "trim off"
    header = ["longest side", "shape"]
    if BEFORE:
        header += [f"before: {how}, s", "before: ratio to its EDT", "speed-up"]
    if DEFAULT_TOO:
        header += ["pipeline, s", "ratio to EDT"]
    if UNTRIMMED_TOO:
        header += ["trim off, s", "trim off: ratio to EDT"]
    header += ["EDT alone, s", f"medial axis / {how}", "peak RSS, MB"]
    header += ["CPU, s", "estimate, s", "CPU / estimate"]
    print(table(header, rows))
    reps = f"median of {REPEAT} runs" if REPEAT else "median of 3 runs up to 2048 px, one above"
    print(f"\n{reps}; one process per shape, size and checkout")
    if BEFORE:
        print(f"before: {BEFORE}, its runs just before this tree's, on the same mask")
    _, name, size = slowest
    lines = _in_process(_profile, name, size).splitlines()
    top = [line for line in lines if line.strip()][-PROFILE_TOP - 1 :]
    how = "default options" if DEFAULT_TOO else "trim=False"
    print(f"\nslowest: {name} at {size} px ({how}), cProfile, top {PROFILE_TOP} by own time:\n")
    print("\n".join(top))
