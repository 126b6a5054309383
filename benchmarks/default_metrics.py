"""The measures of ``python -m benchmarks default`` on 2-D answers, and the methods' answers.

An *answer* is a bool mask of skeleton pixels on the input's grid: skelprune's kept
skeleton points (:meth:`skelprune.PruneResult.skeleton_points`), or skan's pruned
``skeletonize`` image.

- :func:`centre_line_kept`: the share of the raw centre line (``skeletonize``'s pixels)
  within 2 px of the answer: what of the structure the answer keeps;
- :func:`short_end_branches`: the answer's end branches (junction to free end) longer
  than two pixels and shorter than 10 px whose free end is off the image border: the
  spurs a person would cut.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import ndimage

__all__ = [
    "answer_skan",
    "answer_skelprune",
    "centre_line_kept",
    "raw_centre_line",
    "short_end_branches",
]


def raw_centre_line(mask: np.ndarray) -> np.ndarray:
    """``skimage.morphology.skeletonize`` of the mask: the centre line before any pruning."""
    from skimage.morphology import skeletonize

    return np.asarray(skeletonize(mask), bool)


def answer_skelprune(mask: np.ndarray, options: dict[str, Any]) -> np.ndarray:
    """skelprune's kept skeleton points at ``options``, as a mask."""
    import skelprune

    res = skelprune.prune(mask, **options)
    rows, cols, _ = res.skeleton_points()
    out = np.zeros(mask.shape, bool)
    out[rows, cols] = True
    return out


def answer_skan(mask: np.ndarray, shorter: float) -> np.ndarray:
    """``skeletonize`` with skan's ``prune_paths`` of the end branches under ``shorter`` px,
    once (:mod:`benchmarks.volume_methods`' recipe, on the plane)."""
    from .volume_methods import _skan

    return np.asarray(_skan(mask, (1.0, 1.0), shorter), bool)


def centre_line_kept(raw: np.ndarray, answer: np.ndarray, tolerance: float = 2.0) -> float:
    """Share of the ``raw`` centre line's pixels within ``tolerance`` px of ``answer``'s.

    >>> raw = np.zeros((9, 30), bool); raw[4, 2:28] = True
    >>> centre_line_kept(raw, raw)
    1.0
    >>> half = raw.copy(); half[:, 15:] = False
    >>> round(centre_line_kept(raw, half), 3)  # 13 kept, 2 more within 2 px, of 26
    0.577
    """
    if not raw.any():
        return 1.0
    if not answer.any():
        return 0.0
    near = ndimage.distance_transform_edt(~answer) <= tolerance
    return float(near[raw].mean())


#: The longest stub (px) read as a pixel staircase, not a branch: two diagonal steps.
STUB = 2 * 2**0.5 + 1e-6


def short_end_branches(answer: np.ndarray, shorter: float = 10.0, stub: float = STUB) -> int:
    """End branches (junction to free end, skan's branch type 1) longer than ``stub`` and
    shorter than ``shorter`` px whose free end lies off the image border (an end on the
    border is where the structure leaves the image, not a tip). The answer is thinned to
    one pixel first (``skeletonize``), and a stub of one or two pixels beside a line is
    its pixels' staircase, not a branch: neither is read as a spur.

    >>> m = np.zeros((30, 40), bool); m[15, 3:37] = True; m[16:21, 20] = True
    >>> short_end_branches(m)  # a 5-px spur off a 34-px line
    1
    """
    from skan import Skeleton, summarize
    from skimage.morphology import skeletonize

    answer = np.asarray(skeletonize(answer), bool)
    if np.count_nonzero(answer) < 2:
        return 0
    skel = Skeleton(answer)
    branches = summarize(skel, separator="_")
    ends = _free_ends(answer)
    h, w = answer.shape
    count = 0
    for i in np.flatnonzero(
        (branches["branch_type"].to_numpy() == 1)
        & (branches["branch_distance"].to_numpy() < shorter)
        & (branches["branch_distance"].to_numpy() > stub)
    ):
        path = np.asarray(skel.path_coordinates(int(i)))
        for r, c in (path[0], path[-1]):
            r, c = round(r), round(c)
            if ends[r, c]:
                count += not (r <= 1 or c <= 1 or r >= h - 2 or c >= w - 2)
                break
    return count


def _free_ends(answer: np.ndarray) -> np.ndarray:
    """Pixels of ``answer`` with exactly one 8-neighbour in it."""
    k = np.ones((3, 3), np.uint8)
    count = ndimage.convolve(answer.astype(np.uint8), k, mode="constant")
    return answer & (count == 2)
