"""Speed of the full pipeline, one core, medians over shapes of the best of 3.

The default pipeline (coarse DCE stage) beside ``coarse=None`` (the coarse stage must not
cost much time), on the datasets and, because that is what the stage is for, on every
second kimia216 shape with boundary noise N(0, 1) and scaled by 2. In the same run: bare
``skimage.morphology.skeletonize`` plus a distance transform on the same masks, and the
naive from-scratch oracle on a few small shapes.
"""

from __future__ import annotations

import time

import numpy as np
from scipy import ndimage
from skimage.morphology import skeletonize

import skelprune
from evaluation.stability import PERTURBATIONS, _rng
from skelprune.api import components
from skelprune.pruning.bayesian import pruning_sequence
from skelprune.skeleton import Skeleton

from .common import dataset, table, upscale


def _each(masks, fns, repeat: int = 3) -> list[list[float]]:
    """ms a shape for each of ``fns``: best of ``repeat``, the functions interleaved shape by
    shape, so that a slow spell of a shared machine falls on all of them alike."""
    out: list[list[float]] = [[] for _ in fns]
    for m in masks:
        best = [np.inf] * len(fns)
        for _ in range(repeat):
            for k, fn in enumerate(fns):
                t = time.perf_counter()
                fn(m)
                best[k] = min(best[k], 1000 * (time.perf_counter() - t))
        for k in range(len(fns)):
            out[k].append(best[k])
    return out


def bare(m: np.ndarray) -> None:
    skeletonize(m)
    ndimage.distance_transform_edt(m)


def full(m: np.ndarray) -> None:
    """The default pipeline (coarse DCE stage, then the Bayesian pruning)."""
    skelprune.prune(m).to_dict()


def from_medial_axis(m: np.ndarray) -> None:
    """``coarse=None``: the Bayesian pruning of the full medial axis."""
    skelprune.prune(m, coarse=None).to_dict()


def _sequence_only(crop, naive: bool) -> float:
    from testkit.oracle import naive_sequence

    medial = Skeleton.medial_axis(crop)
    norm = medial.normalisation(9.0)
    graph = medial.working_graph()  # (the fast sequence copies its own)
    t = time.perf_counter()
    if naive:
        naive_sequence(graph, medial.mask, medial.r2, norm.alpha, norm.lbar)
    else:
        pruning_sequence(medial, norm.alpha, norm.lbar)
    return 1000 * (time.perf_counter() - t)


def main() -> None:
    sets = {"kimia216": dataset("kimia216"), "kimia99": dataset("kimia99")}
    sets["512x512"] = [upscale(m, 512) for m in sets["kimia216"][::17]]
    for name in ("gaussian-1", "scale-2"):
        sets[f"kimia216/2, {name}"] = [
            PERTURBATIONS[name].apply(m, _rng(0, i, name))
            for i, m in enumerate(sets["kimia216"][::2])
        ]
    full(sets["kimia216"][0])  # JIT warm-up (cached on disk after the first run)
    from_medial_axis(sets["kimia216"][0])
    rows = []
    for name, masks in sets.items():
        ours, plain, ref = _each(masks, [full, from_medial_axis, bare])
        rows.append(
            [
                name,
                len(masks),
                float(np.median(ours)),
                float(np.median(plain)),
                float(np.median(np.array(ours) / np.array(plain))),
                float(np.median(ref)),
                float(np.median(ours) / np.median(ref)),
            ]
        )
    print(
        table(
            [
                "shapes",
                "n",
                "default ms (median)",
                "coarse=None ms (median)",
                "default/None (median of ratios)",
                "skeletonize+EDT ms (median)",
                "default/bare",
            ],
            rows,
        )
    )
    small = [crop for m in sets["kimia216"][::34] for crop, _ in components(m)]
    speed = []
    for crop in small:
        fast = min(_sequence_only(crop, False) for _ in range(3))
        slow = _sequence_only(crop, True)
        speed.append(slow / fast)
    rows = [
        [
            "pruning sequence, kimia216",
            len(small),
            float(np.median(speed)),
            float(np.min(speed)),
            float(np.max(speed)),
        ]
    ]
    # The fast sequence is incremental, the oracle repaints every disk for every
    # candidate: the ratio grows with the shape. One larger shape each (the oracle
    # needs seconds there, minutes at 512 px).
    for longest in (200, 256):
        crop = components(upscale(sets["kimia216"][34], longest))[0][0]
        fast = min(_sequence_only(crop, False) for _ in range(3))
        ratio = _sequence_only(crop, True) / fast
        rows.append([f"pruning sequence, one shape at {longest} px", 1, ratio, ratio, ratio])
    print()
    print(table(["oracle comparison", "shapes", "naive/fast (median)", "min", "max"], rows))
