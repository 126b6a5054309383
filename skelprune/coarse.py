"""The coarse stage of ``prune(coarse="dce")``: DCE contour-partition pruning made robust.

The paper ran its Bayesian pruning from a skeleton first pruned to a coarse level with
the DCE method of its ref. [10] (paper §7.4, SPEC §2.5). This module is that stage, with
two additions, both measured in ``docs/stability-findings.md``:

* **The DCE stop follows the boundary's own roughness.** DCE stops when the least
  relevance ``β·l1·l2/(l1 + l2)`` (lengths in pixels) exceeds a threshold. A bump's
  relevance is about its height in pixels, so the threshold is a height: 3 px for a
  clean digital boundary, raised in proportion to the measured boundary roughness
  (:func:`boundary_roughness`) so that noise bumps, whose height grows with the noise,
  do not become convex DCE vertices that protect noise spurs.
* **One end branch per convex vertex.** End branches generated only by the two
  segments that meet at one convex vertex all describe that vertex (a corner, or a
  tip): only the one that ends nearest to the vertex is kept. Noise near a true corner
  otherwise leaves a fork of two or three such branches.

Neither rule is a user parameter: both are fixed once, here.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from .dce import (
    COARSE_PIXEL_THRESHOLD,
    BoundaryPartition,
    boundary_partition,
    generating_segments,
)
from .graph import BranchGraph
from .pruning import remove_unsupported

__all__ = [
    "ROUGHNESS_FLOOR",
    "ROUGHNESS_GAIN",
    "boundary_roughness",
    "coarse_dce",
    "coarse_threshold",
]

#: Roughness (see :func:`boundary_roughness`) of a clean digital boundary stays below
#: this (0.01–0.14 on kimia216 and kimia99); only the excess raises the DCE threshold ...
ROUGHNESS_FLOOR: float = 0.15
#: ... by this many pixels of relevance per unit of roughness (boundary noise N(0, 1)
#: measures about 0.44, so its threshold is about 9 px).
ROUGHNESS_GAIN: float = 20.0

_CROSS = ndimage.generate_binary_structure(2, 1)


def boundary_roughness(mask: np.ndarray) -> float:
    """Pixels a one-pixel opening and closing change, per boundary pixel.

    A clean digital boundary only loses its corner pixels to a 3×3-cross opening and
    closing; a boundary with pixel-scale noise loses its spikes and gets its notches
    filled all along. The ratio is scale-free in the sense that matters here: it counts
    per boundary pixel, not per shape.

    Parameters
    ----------
    mask : (H, W) bool array

    Returns
    -------
    float
        0 for a shape no opening or closing changes; typically 0.01–0.14 for a clean
        silhouette and 0.3–0.7 under boundary noise of one pixel or more.

    Examples
    --------
    >>> m = np.zeros((40, 40), bool); m[5:35, 5:35] = True
    >>> round(boundary_roughness(m), 3)  # only the 4 corner pixels change
    0.034
    >>> from skelprune.perturb import boundary_noise
    >>> boundary_roughness(boundary_noise(m, "gaussian", 1.0, rng=0)) > 0.3
    True
    """
    m = np.pad(np.asarray(mask, dtype=bool), 2)
    perimeter = np.count_nonzero(m & ~ndimage.binary_erosion(m, _CROSS))
    if perimeter == 0:
        return 0.0
    opened = ndimage.binary_opening(m, _CROSS)
    closed = ndimage.binary_closing(m, _CROSS)
    changed = np.count_nonzero(m & ~opened) + np.count_nonzero(closed & ~m)
    return float(changed / perimeter)


def coarse_threshold(mask: np.ndarray) -> float:
    """DCE stop of the coarse stage, in pixels of relevance, for this shape.

    ``COARSE_PIXEL_THRESHOLD + ROUGHNESS_GAIN·max(0, roughness − ROUGHNESS_FLOOR)``.

    Examples
    --------
    >>> m = np.zeros((40, 40), bool); m[5:35, 5:35] = True
    >>> coarse_threshold(m)
    3.0
    """
    excess = max(0.0, boundary_roughness(mask) - ROUGHNESS_FLOOR)
    return COARSE_PIXEL_THRESHOLD + ROUGHNESS_GAIN * excess


def _vertex_keys(partition: BoundaryPartition) -> tuple[dict[tuple[int, int], int],
                                                        np.ndarray]:
    """Adjacent segment pairs → the convex vertex between them, and vertex positions.

    Segment ``j`` of a polygon starts at its ``j``-th convex vertex, so the vertex
    between segments ``j − 1`` and ``j`` is the start of ``j``. Polygons with fewer than
    three segments are left out: with two, the pair meets at two vertices.
    """
    keys: dict[tuple[int, int], int] = {}
    positions = []
    base = 0
    for v, convex in zip(partition.vertices, partition.convex, strict=True):
        cuts = v[convex]
        n = len(cuts) if len(cuts) >= 2 else 1
        if n >= 3:
            for j in range(n):
                a, b = base + (j - 1) % n, base + j
                keys[(min(a, b), max(a, b))] = len(positions) + j
        positions.extend(cuts if len(cuts) >= 2 else [])
        base += n
    return keys, np.asarray(positions, np.float64).reshape(-1, 2)


def _forks(graph: BranchGraph, labels: np.ndarray, keys: dict[tuple[int, int], int],
           positions: np.ndarray) -> list[int]:
    """End branches that describe a convex vertex another end branch describes better.

    Returns every such branch but the one ending nearest the vertex (ties: lower
    branch id), for every vertex claimed by two or more end branches.
    """
    claims: dict[int, list[tuple[float, int]]] = {}
    for b in graph.end_branches():
        lab = labels[graph.branches[b].points]
        if (lab[:, 2] != -1).any():
            continue  # some point is generated by three or more segments
        seen = np.unique(lab[lab >= 0])
        if len(seen) != 2:
            continue
        vertex = keys.get((int(seen[0]), int(seen[1])))
        if vertex is None:
            continue
        p = graph.endpoint(b)
        dr = graph.rows[p] - positions[vertex, 0]
        dc = graph.cols[p] - positions[vertex, 1]
        claims.setdefault(vertex, []).append((float(dr * dr + dc * dc), b))
    return [b for c in claims.values() if len(c) > 1 for _, b in sorted(c)[1:]]


def coarse_dce(graph: BranchGraph, mask: np.ndarray, r2: np.ndarray) -> list[int]:
    """Prune ``graph`` (the medial axis of ``mask``) to the coarse level, in place.

    End branches none of whose points two DCE segments generate are removed
    (:func:`~skelprune.pruning.remove_unsupported`), then surplus branches at one
    convex vertex (see the module docstring), repeating until neither rule applies.
    Whole end branches only: the topology of the skeleton never changes.

    Parameters
    ----------
    graph : BranchGraph
        The medial axis; modified in place.
    mask : (H, W) bool array
        The shape, in the frame of ``graph``'s coordinates.
    r2 : (n,) int array
        Squared radius of each point of ``graph``.

    Returns
    -------
    list of int
        The removed branch ids, in order (replayable on a fresh graph).
    """
    partition = boundary_partition(mask, pixel_threshold=coarse_threshold(mask))
    labels = generating_segments(np.stack([graph.rows, graph.cols], axis=1), r2, partition)
    supported = labels[:, 1] != -1
    keys, positions = _vertex_keys(partition)
    removed = remove_unsupported(graph, supported)
    while True:
        forks = _forks(graph, labels, keys, positions)
        if not forks:
            return removed
        # one at a time: a removal can merge branches and change every other claim
        graph.remove_end_branch(forks[0])
        removed.append(forks[0])
        removed += remove_unsupported(graph, supported)
