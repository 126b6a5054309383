"""Label images: a 4096² image of 2,000 touching labels against pruning each object alone
from its bounding-box crop (target ≤ 1.5×).

``python -m benchmarks labels`` tiles the image with the Voronoi cells of 2,000 random
seeds (every cell touches its neighbours; 16-bit label values spread over the range),
then times, three times each and interleaved, ``prune(labels, labels=True)`` (the whole
image: reading the labels, finding each label's box, pruning every object) and the sum
over the objects of ``prune(labels[box] == value)`` (each object alone in its own
bounding-box crop, the crop's cost included). It prints the medians, their ratio and
that the two give the same components.
"""

from __future__ import annotations

import time

import numpy as np
from scipy import ndimage
from scipy.spatial import cKDTree

import skelprune
from skelprune.io.foreground import label_boxes

from .common import table

SIDE = 4096
LABELS = 2000
REPEAT = 3


def voronoi_labels(side: int = SIDE, n: int = LABELS, seed: int = 0) -> np.ndarray:
    """Voronoi cells of ``n`` random seeds tiling a ``side``² image, 16-bit labels."""
    rng = np.random.default_rng(seed)
    seeds = rng.uniform(0, side, (n, 2))
    values = rng.choice(np.arange(1, 65536), n, replace=False).astype(np.uint16)
    rows = np.arange(side)
    out = np.empty((side, side), np.uint16)
    tree = cKDTree(seeds)
    for r0 in range(0, side, 256):  # in bands: bounded memory
        yy, xx = np.meshgrid(rows[r0 : r0 + 256], rows, indexing="ij")
        _, idx = tree.query(np.column_stack([yy.ravel(), xx.ravel()]), workers=1)
        out[r0 : r0 + 256] = values[idx].reshape(yy.shape)
    return out


def whole(labels: np.ndarray) -> list:
    return skelprune.prune(labels, labels=True, curve=False).components


def alone(labels: np.ndarray, boxes: list) -> list:
    out = []
    for v, box in boxes:
        res = skelprune.prune(labels[box] == v, curve=False)
        out.append((v, box, res.components))
    return out


def main() -> None:
    labels = voronoi_labels()
    boxes = label_boxes(labels.astype(np.int64))
    assert len(boxes) == LABELS
    sizes = ndimage.sum_labels(np.ones_like(labels), labels, [v for v, _ in boxes])
    whole(labels[:512, :512])  # kernels loaded outside the timings
    t_whole, t_alone = [], []
    for _ in range(REPEAT):
        t = time.perf_counter()
        comps = whole(labels)
        t_whole.append(time.perf_counter() - t)
        t = time.perf_counter()
        each = alone(labels, boxes)
        t_alone.append(time.perf_counter() - t)
    # the same components: each label's, at its place in the image
    same = len(comps) == sum(len(c) for _, _, c in each)
    it = iter(comps)
    for _, box, cs in each:
        for c in cs:
            got = next(it)
            shifted = (c.origin[0] + box[0].start, c.origin[1] + box[1].start)
            same &= got.origin == shifted and got.area == c.area and got.rer == c.rer
    w, a = float(np.median(t_whole)), float(np.median(t_alone))
    print(
        table(
            ["image", "labels", "median object px", "whole image s", "each alone s", "ratio"],
            [[f"{SIDE}²", LABELS, float(np.median(sizes)), w, a, w / a]],
        )
    )
    print(f"\nsame components as each alone: {same}; target: ratio ≤ 1.5 (medians of {REPEAT})")
