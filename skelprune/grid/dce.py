"""Discrete Curve Evolution and the contour partition of Bai, Latecki & Liu (2007).

The pruning method of Bai, Latecki & Liu (TPAMI 2007, ref. [10] of the paper, docs/algorithm.md)
simplifies every boundary polygon of a shape with Discrete Curve Evolution (DCE,
Latecki & Lakämper), cuts the boundary at the *convex* vertices of the evolved polygon,
and keeps a skeleton point only if its maximal disk touches at least two of these
boundary segments.

Conventions (see ``docs/dce.md``):

* **Boundary polygon.** Each boundary (the outer one and one per hole) is the closed
  crack curve between the shape and the background, traced by marching squares at level
  0.5 with the shape 8-connected (the polygons of :func:`skimage.measure.find_contours`,
  replayed in numba by :func:`trace_boundaries`). Every vertex is
  the midpoint of a 4-adjacent (shape pixel, background pixel) pair. The shape is always
  on the left of the curve (image view), so outer boundaries and holes share one
  orientation and "convex w.r.t. the shape" is one turn sign for all of them.
* **Boundary points.** The point attached to a vertex is its *background* pixel, i.e. the
  boundary points are the background pixels 4-adjacent to the shape. The nearest
  background pixel of any shape pixel is always one of them, so the points a maximal disk
  of radius ``r(s)`` (distance to the nearest background pixel) touches are exactly the
  boundary points at distance ``r(s)`` - up to digitisation, hence :data:`TOUCH_TOLERANCE`.
* **Relevance.** ``K = β·l1·l2/(l1 + l2)`` with ``l1, l2`` divided by the perimeter of the
  *original* polygon, so that thresholds are scale-free (dividing by the current perimeter
  instead would not change the deletion order, only the meaning of a threshold).
"""

from __future__ import annotations

import heapq
from collections.abc import Callable
from itertools import pairwise

import numba
import numpy as np

from ..options import DEFAULT_DCE_THRESHOLD
from ._contours import trace_boundaries
from ._generating import TOUCH_TOLERANCE, generated_in_several_segments, generating_segments
from ._partition import BoundaryPartition
from .graph import BranchGraph

__all__ = [
    "COARSE_PIXEL_THRESHOLD",
    "DCE_THRESHOLD",
    "DCE_VERTICES",
    "TOUCH_TOLERANCE",
    "BoundaryPartition",
    "boundary_partition",
    "evolve_polygon",
    "generated_in_several_segments",
    "generating_segments",
    "remove_unsupported",
]

#: Default stop of DCE for ``method="dce"`` (and when no rule is given): delete every
#: vertex whose relevance (lengths over the perimeter, angle in radians) is at most this,
#: scale-free ... (see ``docs/dce.md`` for the evidence)
DCE_THRESHOLD: float = DEFAULT_DCE_THRESHOLD  # defined with the option it defaults
#: ... and keep no more than this many vertices per boundary polygon, so that boundary
#: noise (whose relevance grows as the shape gets smaller) cannot add vertices without end.
DCE_VERTICES: int = 16
#: The coarse stage of ``prune(coarse="dce")`` on a clean boundary: DCE stops when the
#: least relevance, measured in pixels (``β·l1·l2/(l1 + l2)``, lengths in pixels), exceeds
#: this; :func:`skelprune.grid.coarse.coarse_threshold` raises it with the boundary's roughness.
#: The largest stop, in steps of 0.25 px, that keeps the median RER within 1 % on
#: kimia216 (2.5 px: 0.99 %; 3 px: 1.03 %); a higher stop is steadier under noise. See
#: docs/stability-findings.md.
COARSE_PIXEL_THRESHOLD: float = 2.5


@numba.njit(cache=True)
def _relevance(xy: np.ndarray, p: int, i: int, q: int, perimeter: float) -> float:
    a0 = xy[i, 0] - xy[p, 0]
    a1 = xy[i, 1] - xy[p, 1]
    b0 = xy[q, 0] - xy[i, 0]
    b1 = xy[q, 1] - xy[i, 1]
    l1 = np.sqrt(a0 * a0 + a1 * a1)
    l2 = np.sqrt(b0 * b0 + b1 * b1)
    if l1 == 0.0 or l2 == 0.0:
        return 0.0
    beta = np.arctan2(abs(a0 * b1 - a1 * b0), a0 * b0 + a1 * b1)
    return beta * l1 * l2 / ((l1 + l2) * perimeter)


@numba.njit(cache=True)
def _before(key: np.ndarray, a: int, b: int) -> bool:
    # the heap order: relevance, then vertex index (ties go to the smaller index)
    return key[a] < key[b] or (key[a] == key[b] and a < b)


@numba.njit(cache=True)
def _sift_up(heap: np.ndarray, pos: np.ndarray, key: np.ndarray, j: int) -> None:
    v = heap[j]
    while j > 0:
        up = (j - 1) >> 1
        if not _before(key, v, heap[up]):
            break
        heap[j] = heap[up]
        pos[heap[j]] = j
        j = up
    heap[j] = v
    pos[v] = j


@numba.njit(cache=True)
def _sift_down(heap: np.ndarray, pos: np.ndarray, key: np.ndarray, j: int, size: int) -> None:
    v = heap[j]
    while True:
        child = 2 * j + 1
        if child >= size:
            break
        if child + 1 < size and _before(key, heap[child + 1], heap[child]):
            child += 1
        if not _before(key, heap[child], v):
            break
        heap[j] = heap[child]
        pos[heap[j]] = j
        j = child
    heap[j] = v
    pos[v] = j


@numba.njit(cache=True)
def _evolve(xy: np.ndarray, n_keep: int, threshold: float) -> np.ndarray:
    # An indexed binary heap over the live vertices keyed by (relevance, index): a deletion
    # re-keys its two neighbours in place. The live vertex of least (relevance, index) is
    # the same one a lazily invalidated heap of tuples would pop, so is the result.
    n = xy.shape[0]
    prev = np.empty(n, np.int64)
    nxt = np.empty(n, np.int64)
    for i in range(n):
        prev[i] = (i - 1) % n
        nxt[i] = (i + 1) % n
    perimeter = 0.0
    for i in range(n):
        d0 = xy[nxt[i], 0] - xy[i, 0]
        d1 = xy[nxt[i], 1] - xy[i, 1]
        perimeter += np.sqrt(d0 * d0 + d1 * d1)
    if perimeter == 0.0:
        perimeter = 1.0
    alive = np.ones(n, np.bool_)
    key = np.empty(n, np.float64)
    for i in range(n):
        key[i] = _relevance(xy, prev[i], i, nxt[i], perimeter)
    heap = np.arange(n)
    pos = np.arange(n)
    size = n
    count = n
    if threshold >= 0.0:
        # Vertices on a straight run (relevance exactly 0: crack coordinates are halves,
        # so the cross products are exact) go first whatever the stop, and removing one
        # leaves every other key at 0 or at its value with the nearest non-zero
        # neighbours. So drop them all at once, unless fewer than 3 would be left.
        size = 0
        for i in range(n):
            if key[i] > 0.0:
                heap[size] = i
                size += 1
        if size >= 3:
            for t in range(size):
                i = heap[t]
                prev[i] = heap[(t - 1) % size]
                nxt[i] = heap[(t + 1) % size]
                pos[i] = t
            for i in range(n):
                alive[i] = key[i] > 0.0
            for t in range(size):
                i = heap[t]
                key[i] = _relevance(xy, prev[i], i, nxt[i], perimeter)
            count = size
        else:
            heap = np.arange(n)
            size = n
    for j in range(size // 2 - 1, -1, -1):
        _sift_down(heap, pos, key, j, size)
    while count > 3:
        i = heap[0]
        if count <= n_keep and key[i] > threshold:
            break
        size -= 1
        if size > 0:
            heap[0] = heap[size]
            pos[heap[0]] = 0
            _sift_down(heap, pos, key, 0, size)
        p = prev[i]
        q = nxt[i]
        nxt[p] = q
        prev[q] = p
        alive[i] = False
        count -= 1
        key[p] = _relevance(xy, prev[p], p, q, perimeter)
        _sift_up(heap, pos, key, pos[p])
        _sift_down(heap, pos, key, pos[p], size)
        key[q] = _relevance(xy, p, q, nxt[q], perimeter)
        _sift_up(heap, pos, key, pos[q])
        _sift_down(heap, pos, key, pos[q], size)
    return np.nonzero(alive)[0]


def evolve_polygon(
    vertices: np.ndarray,
    n_vertices: int | None = None,
    threshold: float | None = None,
) -> np.ndarray:
    """Discrete Curve Evolution of a closed polygon.

    Repeatedly deletes the vertex of least relevance ``K = β·l1·l2/(l1 + l2)`` (``β`` the
    turn angle in radians, ``l1, l2`` the lengths of its two current edges divided by the
    perimeter of the input polygon) until ``n_vertices`` are left, or until the least
    relevance exceeds ``threshold``. Given both, ``n_vertices`` is a cap and ``threshold``
    a floor: evolution goes on while more than ``n_vertices`` are left *or* some vertex
    has a relevance ``<= threshold``. With neither given, the defaults
    :data:`DCE_VERTICES` and :data:`DCE_THRESHOLD` (together). At least 3 vertices are
    always kept. Ties go to the smaller
    index, so the result is deterministic. Runs in O(n log n) (indexed binary heap).

    Parameters
    ----------
    vertices : (n, 2) array of float
        The polygon, closed implicitly (do not repeat the first vertex).
    n_vertices : int, optional
        Stop when this many vertices are left.
    threshold : float, optional
        Stop when the least relevance is larger than this.

    Returns
    -------
    (m,) array of int
        Indices of the kept vertices, in increasing (= polygon) order.

    Examples
    --------
    >>> square = [(0, 0), (0, 1), (0, 2), (1, 2), (2, 2), (2, 1), (2, 0), (1, 0)]
    >>> evolve_polygon(np.array(square, float), n_vertices=4).tolist()
    [0, 2, 4, 6]
    """
    xy = np.ascontiguousarray(vertices, dtype=np.float64)
    if xy.ndim != 2 or xy.shape[1] != 2:
        raise ValueError(f"vertices must have shape (n, 2), got {xy.shape}")
    if n_vertices is None and threshold is None:
        n_vertices, threshold = DCE_VERTICES, DCE_THRESHOLD
    n = xy.shape[0]
    n_keep = n if n_vertices is None else max(3, int(n_vertices))
    thr = -np.inf if threshold is None else float(threshold)
    if n <= 3 or (n <= n_keep and threshold is None):
        return np.arange(n, dtype=np.int64)
    return _evolve(xy, n_keep, thr)


def boundary_partition(
    mask: np.ndarray,
    n_vertices: int | None = None,
    threshold: float | None = None,
    pixel_threshold: float | None = None,
) -> BoundaryPartition:
    """Cut every boundary of a shape at the convex vertices of its evolved polygon.

    Each boundary polygon (outer and holes) is evolved with :func:`evolve_polygon`
    (same stop rules and defaults), and split into
    segments that run from one convex vertex (w.r.t. the shape) up to, not including,
    the next. A boundary with fewer than two convex vertices is a single segment.

    Parameters
    ----------
    mask : (H, W) bool array
        The shape (one 8-connected component; several are handled the same way).
    n_vertices, threshold
        DCE stop rules, per boundary polygon.
    pixel_threshold : float, optional
        Instead of ``threshold``: a stop on relevance in pixels, ``β·l1·l2/(l1 + l2)``
        with the edge lengths in pixels (the threshold of each polygon is this over its
        perimeter). Digitisation noise has a relevance of about a pixel whatever the
        size of the shape, so this removes noise vertices at every scale.

    Returns
    -------
    BoundaryPartition

    Examples
    --------
    >>> m = np.zeros((30, 50), bool)
    >>> m[5:25, 5:45] = True
    >>> part = boundary_partition(m)
    >>> part.n_segments, part.points.shape
    (4, (120, 2))
    """
    xy, bg, bounds = trace_boundaries(np.ascontiguousarray(mask, dtype=np.bool_))
    if len(bounds) < 2:
        raise ValueError("mask has no foreground pixel")
    seg = np.empty(len(xy), np.int64)
    pid = np.empty(len(xy), np.int64)
    verts, convex = [], []
    next_id = 0
    for k, (a, b) in enumerate(pairwise(bounds.tolist())):
        poly = xy[a:b]
        if pixel_threshold is not None:
            d = np.diff(poly, axis=0, append=poly[:1])  # edge i runs from vertex i to i + 1
            perimeter = float(np.hypot(d[:, 0], d[:, 1]).sum())
            threshold = pixel_threshold / max(perimeter, 1.0)
        idx = evolve_polygon(poly, n_vertices=n_vertices, threshold=threshold)
        is_convex, n_seg = _cut_at_convex(poly, idx, seg[a:b], next_id)
        pid[a:b] = k
        verts.append(poly[idx])
        convex.append(is_convex)
        next_id += n_seg
    return BoundaryPartition(
        points=bg,
        segment=seg,
        polygon_id=pid,
        vertices=verts,
        convex=convex,
        n_segments=next_id,
    )


@numba.njit(cache=True)
def _cut_at_convex(
    poly: np.ndarray, idx: np.ndarray, labels: np.ndarray, first_id: int
) -> tuple[np.ndarray, int]:
    """Convex flags of the kept vertices ``idx``; fills ``labels`` with segment ids.

    Point ``j`` gets ``first_id`` plus the rank of the last convex vertex at or before it
    (cyclically); with fewer than two convex vertices the whole polygon is one segment.
    Returns the flags and the number of segments.
    """
    m = idx.shape[0]
    is_convex = np.empty(m, np.bool_)
    n_cuts = 0
    for t in range(m):
        a, b, c = idx[(t - 1) % m], idx[t], idx[(t + 1) % m]
        in0, in1 = poly[b, 0] - poly[a, 0], poly[b, 1] - poly[a, 1]
        out0, out1 = poly[c, 0] - poly[b, 0], poly[c, 1] - poly[b, 1]
        # (row, col) frame with the shape on the left: convex turns have cross > 0
        is_convex[t] = in0 * out1 - in1 * out0 > 0
        n_cuts += is_convex[t]
    if n_cuts < 2:
        labels[:] = first_id
        return is_convex, 1
    cuts = idx[is_convex]
    rank = n_cuts - 1  # before the first cut: still the segment of the last one
    nxt = 0
    for j in range(labels.shape[0]):
        while nxt < n_cuts and cuts[nxt] <= j:
            rank = nxt
            nxt += 1
        labels[j] = first_id + rank
    return is_convex, n_cuts


def remove_unsupported(
    graph: BranchGraph,
    supported: np.ndarray | Callable[[int], bool],
    candidates: list[int] | None = None,
) -> list[int]:
    """DCE pruning on the graph alone: remove, smallest endpoint (row, col) first,
    every end branch none of whose points is supported, until each has one.

    Used as the coarse stage, whose steps are not part of the Bayesian curve, so no
    reconstruction is kept up to date. A branch's support only changes when it
    absorbs another, so candidates wait in a heap and only merged branches are
    looked at again. ``supported`` is a per-point bool array, or a function that tells
    whether branch ``b`` (as it is now) is supported, for a caller that works the
    answer out lazily. ``candidates`` restricts the first look to those branches (when
    the caller knows no other end branch can be unsupported).
    """
    if callable(supported):
        is_supported = supported
    else:

        def is_supported(b: int) -> bool:
            return bool(supported[graph.branches[b].points].any())

    def push(b: int) -> None:
        if graph.is_end_branch(b) and not is_supported(b):
            p = graph.endpoint(b)
            heapq.heappush(heap, (int(graph.rows[p]), int(graph.cols[p]), b, p))

    heap: list[tuple[int, int, int, int]] = []
    for b in graph.end_branches() if candidates is None else candidates:
        push(b)
    removed: list[int] = []
    while heap:
        _, _, b, p = heapq.heappop(heap)
        # stale: removed, absorbed, or grown by a merge since it was pushed
        if not graph.is_end_branch(b) or graph.endpoint(b) != p or is_supported(b):
            continue
        merged = graph.remove_end_branch(b)
        removed.append(b)
        if merged is not None:
            push(merged[0])
    return removed
