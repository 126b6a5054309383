"""Volumes: the 3-D curve skeleton beside kimimaro and skan on synthetic trees.

The trees (:func:`testkit.volumes.random_tree`) are random branching tubes with known
centre lines and tips, radii from up to 12 down to 1.5 voxels (3 on the 1:1:3 grid,
where thinner tubes fall apart), on an isotropic grid and on one three times coarser
along ``z`` (``spacing = (3, 1, 1)``), with smooth surfaces and with surface noise (a
smooth random field of standard deviation ``SKELPRUNE_BENCH_NOISE`` voxels, 0.7 by
default, that moves the surface). The methods: :mod:`benchmarks.volume_methods`: the
curve skeleton unpruned and pruned by :func:`skelprune.prune` at its default options,
kimimaro, and skan at two length thresholds.

Three tables:

1. **quality** on ``SKELPRUNE_BENCH_TREES`` trees (6) at 128 voxels a side, per grid and
   surface: F1 of the skeleton voxels within 2 voxels of the true centre lines, tips
   found of the true tips, spurs (end points near no true tip), and the lost volume of
   the union of balls for the medial axis;
2. **stability**: each tree's end point count on four noisy copies against its clean
   one, the share equal and the share within ±1;
3. **time and peak memory** of one tree at 128³ and 256³ (``SKELPRUNE_BENCH_SIZES``,
   e.g. ``128,256,512``), each method in a fresh process, median of three runs at 128³
   and one above, beside ``scipy.ndimage.distance_transform_edt`` with ``sampling`` on
   the same volume in the same process: the ratio is to that EDT.

``python -m benchmarks volumes`` (a few minutes on one core). ``python -m benchmarks
volumes --labels``: label volumes and voxelized neurons against kimimaro
(:mod:`benchmarks.bench_volume_labels`). The picture of
docs/volumes.md: ``python -m benchmarks.bench_volumes --figure docs/figures/volumes-tree.png``.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from testkit.volumes import random_tree

from .common import table
from .volume_methods import METHODS, endpoints, scores

TREES = int(os.environ.get("SKELPRUNE_BENCH_TREES", "6"))
NOISE = float(os.environ.get("SKELPRUNE_BENCH_NOISE", "0.7"))
SIZES = tuple(int(s) for s in os.environ.get("SKELPRUNE_BENCH_SIZES", "128,256").split(","))
GRIDS = {"iso": (1.0, 1.0, 1.0), "1:1:3": (3.0, 1.0, 1.0)}
COPIES = 4  # noisy copies of each tree for the stability table


def _quality() -> None:
    from skelprune.grid3d import curve_skeleton, lost_volume

    rows = []
    stable: dict[str, list[int]] = {name: [0, 0, 0] for name in METHODS}
    for grid, spacing in GRIDS.items():
        for surface in ("smooth", "noisy"):
            acc: dict[str, dict[str, float]] = {name: {} for name in METHODS}
            lost = []
            for seed in range(TREES):
                tree = random_tree(seed, 128, spacing)
                volume = tree.volume(NOISE if surface == "noisy" else 0.0, seed=100 + seed)
                for name, method in METHODS.items():
                    for key, value in scores(method(volume, spacing), tree).items():
                        acc[name].setdefault(key, []).append(value)  # type: ignore[attr-defined]
                sk = curve_skeleton(volume, spacing)
                lost.append(lost_volume(volume, sk.z, sk.y, sk.x, sk.r2, spacing) / volume.sum())
            for name in METHODS:
                a = acc[name]
                rows.append(
                    [
                        grid,
                        surface,
                        name,
                        float(np.mean(a["f1"])),
                        float(np.mean(a["precision"])),
                        float(np.mean(a["recall"])),
                        f"{int(np.sum(a['tips found']))}/{int(np.sum(a['true tips']))}",
                        int(np.sum(a["spurs"])),
                        f"{100 * float(np.median(lost)):.1f} %"
                        if name.startswith("medial")
                        else "",
                    ]
                )
        for seed in range(TREES):
            tree = random_tree(seed, 128, spacing)
            clean = {n: len(endpoints(m(tree.volume(), spacing))) for n, m in METHODS.items()}
            for copy in range(COPIES):
                noisy = tree.volume(NOISE, seed=1000 * seed + copy)
                for name, method in METHODS.items():
                    delta = abs(len(endpoints(method(noisy, spacing))) - clean[name])
                    stable[name][0] += delta == 0
                    stable[name][1] += delta <= 1
                    stable[name][2] += 1
    header = ["grid", "surface", "method", "F1@2", "precision", "recall"]
    header += ["tips found", "spurs", "lost volume (median)"]
    print(f"Quality on {TREES} trees a grid at 128 voxels a side (surface noise {NOISE}):\n")
    print(table(header, rows))
    print(f"\nEnd points under surface noise ({COPIES} noisy copies of each tree, both grids):\n")
    print(
        table(
            ["method", "same count", "within ±1"],
            [
                [name, f"{100 * e / n:.0f} %", f"{100 * w / n:.0f} %"]
                for name, (e, w, n) in stable.items()
            ],
        )
    )


def _status_mb(field: str) -> float:
    """A size from /proc/self/status (``VmRSS``: resident now, ``VmHWM``: its peak)."""
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith(field + ":"):
                return int(line.split()[1]) / 1024
    return float("nan")


def _timed(path: str, spacing, method: str, repeat: int, out: mp.Queue) -> None:
    """In a fresh process: the method's median time and peak memory over its baseline."""
    from scipy import ndimage

    warm = np.zeros((12, 12, 12), bool)
    warm[3:9, 3:9, 2:10] = True
    run = (
        (lambda v: ndimage.distance_transform_edt(np.pad(v, 1), sampling=spacing))
        if method == "EDT"
        else (lambda v: METHODS[method](v, spacing))
    )
    run(warm)  # numba kernels loaded from their cache, imports done
    volume = np.load(path)
    with open("/proc/self/clear_refs", "w") as fh:
        fh.write("5")  # the peak resident size starts again from now
    base = _status_mb("VmRSS")
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        run(volume)
        times.append(time.perf_counter() - t)
    out.put((float(np.median(times)), max(_status_mb("VmHWM") - base, 0.0)))


def _in_process(*args: object) -> tuple[float, float] | None:
    ctx = mp.get_context("spawn")
    out: mp.Queue = ctx.Queue()
    proc = ctx.Process(target=_timed, args=(*args, out))
    proc.start()
    proc.join(1800)
    if proc.is_alive():
        proc.kill()
        return None
    return out.get() if proc.exitcode == 0 else None


def _speed() -> None:
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for size in SIZES:
            depth = 3 + max(0, int(np.log2(size / 128)))
            tree = random_tree(0, size, depth=depth)
            volume = tree.volume()
            path = str(Path(tmp) / f"tree{size}.npy")
            np.save(path, volume)
            repeat = 3 if size <= 128 else 1
            edt = _in_process(path, tree.spacing, "EDT", repeat)
            rows.append([f"{size}³", "EDT (scipy)", *_cells(edt, edt)])
            for name in METHODS:
                rows.append(
                    [f"{size}³", name, *_cells(_in_process(path, tree.spacing, name, repeat), edt)]
                )
            del volume
    print("\nTime and peak memory (one tree, clean, isotropic; fresh process each):\n")
    print(table(["size", "method", "s", "× EDT", "peak MB"], rows))


def _cells(got, edt) -> list[object]:
    if got is None:
        return ["failed", "", ""]
    ratio = f"{got[0] / edt[0]:.2f}" if edt else ""
    return [f"{got[0]:.2f}", ratio, f"{got[1]:.0f}"]


def figure(path: str, seed: int = 3) -> None:
    """Maximum-intensity projections of a noisy tree with each skeleton drawn on them."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    tree = random_tree(seed, 128)
    volume = tree.volume(NOISE, seed=7)
    tips = tree.tip_voxels()
    lo = np.maximum(np.argwhere(volume).min(axis=0) - 4, 0)  # the tree's box, with a margin
    hi = np.argwhere(volume).max(axis=0) + 5
    ext = hi - lo
    fig, axes = plt.subplots(
        2,
        len(METHODS),
        figsize=(4 * len(METHODS), 1.2 + 4 * (ext[1] + ext[0]) / ext[2]),
        gridspec_kw={"height_ratios": [ext[1], ext[0]]},
    )
    for col, (name, method) in enumerate(METHODS.items()):
        mask = method(volume, tree.spacing)
        ends = endpoints(mask)
        for row, axis in enumerate((0, 1)):  # seen along z (y, x) and along y (z, x)
            ax = axes[row, col]
            ax.imshow(volume.max(axis=axis), cmap="gray_r", vmin=0, vmax=2.5, origin="lower")
            ax.imshow(
                np.ma.masked_where(~mask.any(axis=axis), mask.any(axis=axis)),
                cmap="autumn",
                origin="lower",
                interpolation="nearest",
            )
            keep = [a for a in range(3) if a != axis]
            ax.scatter(
                tips[:, keep[1]],
                tips[:, keep[0]],
                s=70,
                facecolors="none",
                edgecolors="tab:blue",
                linewidths=1.5,
                label="true tips",
            )
            ax.scatter(ends[:, keep[1]], ends[:, keep[0]], s=10, c="k", label="end points")
            ax.set_xlim(lo[keep[1]], hi[keep[1]])
            ax.set_ylim(lo[keep[0]], hi[keep[0]])
            ax.set_xticks([])
            ax.set_yticks([])
            if row == 0:
                ax.set_title(f"{name}: {len(ends)} end points", fontsize=10)
    axes[0, 0].set_ylabel("seen along z")
    axes[1, 0].set_ylabel("seen along y")
    axes[0, 0].legend(loc="upper left", fontsize=8)
    fig.suptitle(
        f"A synthetic tree, 128³, surface noise {NOISE}: {len(tips)} true tips "
        "(blue rings), skeleton in red, end points in black",
        fontsize=11,
    )
    fig.tight_layout()
    fig.savefig(path, dpi=80)


def main(argv: list[str] | None = None) -> None:
    if argv and "--labels" in argv:  # label volumes and neurons against kimimaro
        from .bench_volume_labels import main as labels_main

        labels_main([a for a in argv if a != "--labels"])
        return
    _quality()
    _speed()


if __name__ == "__main__":
    if sys.argv[1:2] == ["--figure"]:
        figure(sys.argv[2])
    else:
        main()
