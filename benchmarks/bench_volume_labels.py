"""Label volumes and voxelized neurons: skelprune beside kimimaro, in the same run.

``python -m benchmarks volumes --labels`` (or ``python -m benchmarks volume_labels``).

1. **Label volumes**: :func:`testkit.volumes.touching_trees`, ``n`` random branching
   tubes packed into a ``side``³ cube, each its own label, touching where they meet,
   with known centre lines and tips. Cases ``SKELPRUNE_BENCH_LABEL_CASES`` (default
   ``256:100,256:300,512:2000``, ``side:n``). Each method runs in a fresh process on the
   same ``.npy``: skelprune (:func:`skelprune.volume.prune_volume_labels`, default
   options) and kimimaro (TEASAR, the parameters of :mod:`benchmarks.volume_methods`), on
   one process and on ``SKELPRUNE_BENCH_WORKERS`` (default 2; 1: one process only).
   Time is the median of ``SKELPRUNE_BENCH_REPEAT`` runs (default 1), reading the array
   included; peak MB is the largest process's peak resident size over the parent's size
   before the run (workers: their own peak, the forked parent's pages they share
   included). Quality: F1 of the skeleton voxels within 2 voxels of the true centre
   lines, tips found (an end point of the label's skeleton within the tip's radius + 2),
   spurs (end points near no tip).
2. **Voxelized neurons**: navis's example neurons drawn at up to 256 voxels a side
   (:func:`testkit.neurons.example_neurons`), one process each method, the same scores.
3. With ``--large`` (``--large-only``: it alone): a chunked 1024³ label volume on a local
   2-worker Dask cluster (:mod:`benchmarks.bench_volume_chunks`).

``--volumes-only`` and ``--neurons-only`` run one of the first two tables.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import resource
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from .common import table

CASES = [
    tuple(int(v) for v in case.split(":"))
    for case in os.environ.get("SKELPRUNE_BENCH_LABEL_CASES", "256:100,256:300,512:2000").split(",")
]
WORKERS = int(os.environ.get("SKELPRUNE_BENCH_WORKERS", "2"))
REPEAT = int(os.environ.get("SKELPRUNE_BENCH_REPEAT", "1"))
TOLERANCE = 2.0
_OFFSETS = np.array(
    [
        (a, b, c)
        for a in (-1, 0, 1)
        for b in (-1, 0, 1)
        for c in (-1, 0, 1)
        if (a, b, c) != (0, 0, 0)
    ]
)


def _status_mb(field: str) -> float:
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith(field + ":"):
                return int(line.split()[1]) / 1024
    return float("nan")


def _skelprune(volume: np.ndarray, workers: int) -> tuple[np.ndarray, np.ndarray]:
    from skelprune.volume import prune_volume_labels

    res = prune_volume_labels(volume, workers=workers)
    pts, labels = [], []
    for comp in res.components:
        sk = comp.skeleton
        idx = sk.points()
        oz, oy, ox = sk.origin
        pts.append(np.stack([sk.z[idx] + oz, sk.y[idx] + oy, sk.x[idx] + ox], axis=1))
        labels.append(np.full(idx.size, 1 if comp.label is None else comp.label, np.int64))
    return np.concatenate(pts), np.concatenate(labels)


def _kimimaro(volume: np.ndarray, workers: int) -> tuple[np.ndarray, np.ndarray]:
    import kimimaro

    from .volume_methods import KIMIMARO

    skels = kimimaro.skeletonize(
        volume if volume.dtype != np.bool_ else volume.astype(np.uint8),
        teasar_params=KIMIMARO,
        anisotropy=(1.0, 1.0, 1.0),
        dust_threshold=1000,
        fix_branching=True,
        fix_borders=True,
        progress=False,
        parallel=workers,
    )
    pts, labels = [np.zeros((0, 3), np.int64)], [np.zeros(0, np.int64)]
    for label, sk in skels.items():
        idx = np.unique(np.rint(sk.vertices).astype(np.int64), axis=0)
        pts.append(np.clip(idx, 0, np.array(volume.shape) - 1))
        labels.append(np.full(len(idx), int(label), np.int64))
    return np.concatenate(pts), np.concatenate(labels)


METHODS = {"skelprune": _skelprune, "kimimaro": _kimimaro}


def _timed(path: str, method: str, workers: int, out: mp.Queue) -> None:
    """In a fresh process: the run's median time, its peak memory, its skeleton."""
    warm = np.zeros((14, 14, 20), np.uint32)  # the label volumes' dtype: kernels compiled
    warm[3:11, 3:11, 2:10] = 1
    warm[3:11, 3:11, 10:18] = 2
    METHODS[method](warm, 1)  # kernels loaded from their cache, imports done
    with open("/proc/self/clear_refs", "w") as fh:
        fh.write("5")  # the peak resident size starts again from now
    base = _status_mb("VmRSS")
    times = []
    for _ in range(REPEAT):
        t = time.perf_counter()
        volume = np.load(path)
        got = METHODS[method](volume, workers)
        times.append(time.perf_counter() - t)
        del volume
    children = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    peak = max(_status_mb("VmHWM") - base, children if workers > 1 else 0.0)
    out.put((float(np.median(times)), peak, got))


def _run(path: str, method: str, workers: int):
    ctx = mp.get_context("spawn")
    out: mp.Queue = ctx.Queue()
    proc = ctx.Process(target=_timed, args=(path, method, workers, out))
    proc.start()
    try:
        got = out.get(timeout=3600)
    except Exception:  # the run died or took over an hour
        got = None
    proc.join(60)
    if proc.is_alive():
        proc.kill()
    return got


def _endpoints(pts: np.ndarray, labels: np.ndarray, shape) -> np.ndarray:
    """Skeleton voxels with exactly one 26-neighbour of their own label."""
    if not len(pts):
        return pts
    ny, nx = shape[1], shape[2]
    key = (pts[:, 0] * ny + pts[:, 1]) * nx + pts[:, 2]
    order = np.argsort(key)
    key_s, lab_s = key[order], labels[order]
    count = np.zeros(len(pts), np.int64)
    for off in _OFFSETS:
        q = pts + off
        qk = (q[:, 0] * ny + q[:, 1]) * nx + q[:, 2]
        i = np.clip(np.searchsorted(key_s, qk), 0, len(key_s) - 1)
        count += (key_s[i] == qk) & (lab_s[i] == labels)
    return pts[count == 1]


def _scores(pts: np.ndarray, labels: np.ndarray, truth) -> dict[str, float]:
    centre = np.argwhere(truth.centre_mask())
    if not len(pts):
        return {"f1": 0.0, "found": 0, "tips": len(truth.tips), "spurs": 0}
    precision = float(np.mean(cKDTree(centre).query(pts)[0] <= TOLERANCE))
    recall = float(np.mean(cKDTree(pts).query(centre)[0] <= TOLERANCE))
    f1 = 2 * precision * recall / (precision + recall) if precision + recall else 0.0
    tips = np.asarray(truth.tips).reshape(-1, 3)
    ends = _endpoints(pts, labels, truth.shape).astype(np.float64)
    line_ends = np.concatenate([np.stack([ln[0], ln[-1]]) for ln in truth.lines])
    end_radii = np.concatenate([np.array([r[0], r[-1]]) for r in truth.radii])
    reach = end_radii[cKDTree(line_ends).query(tips)[1]] + TOLERANCE
    found = spurs = 0
    if len(ends) and len(tips):
        ends_tree = cKDTree(ends)
        near = ends_tree.query_ball_point(tips, reach)
        found = sum(1 for hits in near if hits)
        hit = np.zeros(len(ends), bool)
        for hits in near:
            hit[hits] = True
        spurs = int((~hit).sum())
    return {"f1": f1, "found": found, "tips": len(tips), "spurs": spurs}


def _rows(name: str, path: str, truth, workers_list: list[int]) -> list[list[object]]:
    rows: list[list[object]] = []
    for method in METHODS:
        for workers in workers_list:
            got = _run(path, method, workers)
            label = f"{method}" + (f" ×{workers}" if workers > 1 else "")
            if got is None:
                rows.append([name, label, "failed", "", "", "", ""])
                continue
            seconds, peak, (pts, labels) = got
            s = _scores(pts, labels, truth)
            rows.append(
                [
                    name,
                    label,
                    f"{seconds:.2f}",
                    f"{peak:.0f}",
                    f"{s['f1']:.3f}",
                    f"{s['found']}/{s['tips']}",
                    s["spurs"],
                ]
            )
    return rows


def label_volumes() -> None:
    from testkit.volumes import touching_trees

    rows: list[list[object]] = []
    with tempfile.TemporaryDirectory() as tmp:
        for side, n in CASES:
            lv = touching_trees(n, side, seed=side + n)
            path = str(Path(tmp) / f"labels{side}-{n}.npy")
            np.save(path, lv.labels)
            name = f"{side}³, {n} labels"
            del lv.labels
            rows += _rows(name, path, lv.truth, [1, WORKERS] if WORKERS > 1 else [1])
            Path(path).unlink()
            print(f"{name}: done", flush=True)
    header = ["volume", "method", "s", "peak MB", "F1@2", "tips found", "spurs"]
    print("Label volumes of touching branching tubes (fresh process each; same run):\n")
    print(table(header, rows), flush=True)


def neurons() -> None:
    from testkit.neurons import example_neurons

    rows: list[list[object]] = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, shape in example_neurons(256):
            path = str(Path(tmp) / f"{name}.npy")
            np.save(path, shape.volume().astype(np.uint8))
            rows += _rows(f"{name} {'×'.join(map(str, shape.shape))}", path, shape, [1])
    header = ["neuron", "method", "s", "peak MB", "F1@2", "tips found", "spurs"]
    print("\nnavis's example neurons, voxelized at <= 256 a side (one process each):\n")
    print(table(header, rows))
    times = {m: [float(r[2]) for r in rows if r[1] == m and r[2] != "failed"] for m in METHODS}
    if all(times.values()):
        print("\nmedian s: " + ", ".join(f"{m} {np.median(t):.2f}" for m, t in times.items()))


def main(argv: list[str] | None = None) -> None:
    args = argv or []
    if "--large-only" not in args:
        if "--neurons-only" not in args:
            label_volumes()
        if "--volumes-only" not in args:
            neurons()
    if "--large" in args or "--large-only" in args:
        from .bench_volume_chunks import main as large

        large()


if __name__ == "__main__":
    import sys

    main(sys.argv[1:])
