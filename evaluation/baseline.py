"""The baseline users would otherwise pick: ``skeletonize`` plus a fixed branch-length cut.

This is the skan / PlantCV recipe: thin the mask with :func:`skimage.morphology.skeletonize`,
then repeatedly remove end branches shorter than ``L`` pixels, so that the cut adapts to
branches that become end branches once their neighbours are gone. It has a parameter in
pixels, which is exactly what the parameter-free Bayesian method avoids; the evaluation
runs it at a few thresholds to show how the choice of ``L`` trades stability against
reconstruction.

Radii come from the exact Euclidean distance transform at the skeleton pixels (the
thinning keeps none of its own), with the project's disk convention ``|p − s|² < r²``, so
RER is measured exactly as for the Bayesian skeleton.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from skimage.morphology import skeletonize

from skelprune.grid.graph import BranchGraph
from skelprune.grid.medial_axis import squared_distance

__all__ = ["BaselineSkeleton", "cut_end_branches", "skeletonize_cut"]


@dataclass(frozen=True)
class BaselineSkeleton:
    """A pruned ``skeletonize`` skeleton in the input mask's frame.

    Attributes
    ----------
    rows, cols : (n,) int64
        Skeleton pixels.
    r2 : (n,) int64
        Squared distance of each pixel to the nearest background pixel.
    endpoints : int
        Free branch ends of the pruned skeleton.
    length : float
        Pixel-path length (1 per axial, √2 per diagonal step), as for the Bayesian skeleton.
    """

    rows: np.ndarray
    cols: np.ndarray
    r2: np.ndarray
    endpoints: int
    length: float


def cut_end_branches(graph: BranchGraph, min_length: float) -> list[int]:
    """Remove end branches shorter than ``min_length``, shortest first, until none is left.

    Shortest first (ties: smaller branch id) so that the result does not depend on the
    order the branches were traced in, and removing one branch can merge two others into
    a longer one before either is judged.

    Parameters
    ----------
    graph : BranchGraph
        Modified in place.
    min_length : float
        Cut threshold ``L`` in pixels (a branch's length: ``graph.branch_length``).

    Returns
    -------
    list of int
        The removed branch ids, in order.

    Examples
    --------
    >>> rows = np.array([5] * 9 + [4, 3]); cols = np.array(list(range(1, 10)) + [5, 5])
    >>> g = BranchGraph(rows, cols, (8, 12))
    >>> cut_end_branches(g, 3.0), g.n_endpoints()
    ([2], 2)
    """
    removed: list[int] = []
    while True:
        ends = graph.end_branches()
        if not ends:
            return removed
        b = min(ends, key=lambda k: (graph.branch_length(k), k))
        if graph.branch_length(b) >= min_length:
            return removed
        graph.remove_end_branch(b)
        removed.append(b)


def skeletonize_cut(mask: np.ndarray, min_length: float) -> BaselineSkeleton:
    """``skeletonize`` then :func:`cut_end_branches` at ``min_length`` pixels.

    Parameters
    ----------
    mask : (H, W) array
        Non-zero pixels are the shape (any number of components).
    min_length : float
        ``L``; 0 keeps the whole ``skeletonize`` output.

    Returns
    -------
    BaselineSkeleton
    """
    # One background pixel around: BranchGraph needs an empty border, and the distance
    # of a shape touching the image border is measured to the outside, as in prune().
    padded = np.pad(np.asarray(mask) != 0, 1)
    r2img = squared_distance(padded)
    rows, cols = np.nonzero(skeletonize(padded))
    graph = BranchGraph(rows, cols, padded.shape)
    cut_end_branches(graph, min_length)
    keep = graph.alive_points()
    rr, cc = graph.rows[keep], graph.cols[keep]
    return BaselineSkeleton(
        rows=rr - 1,
        cols=cc - 1,
        r2=r2img[rr, cc].astype(np.int64),
        endpoints=graph.n_endpoints(),
        length=graph.total_length(),
    )
