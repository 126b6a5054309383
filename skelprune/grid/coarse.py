"""The coarse stage of ``prune(coarse="dce")``: DCE contour-partition pruning made robust.

The paper ran its Bayesian pruning from a skeleton first pruned to a coarse level with
the DCE method of its ref. [10] (paper §7.4, docs/algorithm.md). This module is that stage, with
two additions, both measured in ``docs/stability-findings.md``:

* **The DCE stop follows the boundary's own roughness.** DCE stops when the least
  relevance ``β·l1·l2/(l1 + l2)`` (lengths in pixels) exceeds a threshold. A bump's
  relevance is about its height in pixels, so the threshold is a height: 2.5 px for a
  clean digital boundary, raised in proportion to the measured boundary roughness
  (:func:`boundary_roughness`) so that noise bumps, whose height grows with the noise,
  do not become convex DCE vertices that protect noise spurs.
* **At most** :data:`COARSE_VERTICES` **vertices per boundary polygon.** The authors'
  own code keeps a fixed DCE budget of 50 vertices instead of a stop in pixels; a count
  is scale-free and bounds the number of convex vertices, and so of end branches the
  stage can pass, whatever the boundary does. Here it is a cap on top of the stop (so a
  shape with few relevant vertices keeps few; a polygon with fewer than two convex
  vertices is one segment, and one with fewer than three claims no corner: never an
  error, where the authors' code fails below three).
* **One end branch per convex vertex.** End branches generated only by the two
  segments that meet at one convex vertex all describe that vertex (a corner, or a
  tip): only the one that ends nearest to the vertex is kept. Noise near a true corner
  otherwise leaves a fork of two or three such branches.

None of these rules is a user parameter: all are fixed once, here.
"""

from __future__ import annotations

from itertools import chain

import numba
import numpy as np

from ..skeleton import Skeleton
from ._generating import SegmentRaster, rim_label_set, rim_labels
from ._roughness import boundary_roughness
from .dce import (
    COARSE_PIXEL_THRESHOLD,
    BoundaryPartition,
    boundary_partition,
    remove_unsupported,
)
from .graph import BranchGraph

__all__ = [
    "COARSE_VERTICES",
    "ROUGHNESS_FLOOR",
    "ROUGHNESS_GAIN",
    "boundary_roughness",
    "coarse_dce",
    "coarse_partition",
    "coarse_removals",
    "coarse_threshold",
]

#: The most vertices DCE leaves on one boundary polygon in the coarse stage: the budget
#: of the authors' code (``DSE(bw, 50, ...)``). On clean kimia shapes the relevance stop
#: leaves fewer (median 20, 99th percentile 54: the cap binds on 4 of 303); it binds
#: where the stop alone would let a boundary keep more and more vertices (large or rough
#: shapes).
COARSE_VERTICES: int = 50
#: Roughness (see :func:`boundary_roughness`) of a clean digital boundary: 0.08 median on
#: kimia216 + kimia99, below this for 94 % of them (the rest, up to 0.23, are shapes with
#: many small corners); only the excess raises the DCE threshold ...
ROUGHNESS_FLOOR: float = 0.15
#: ... by this many pixels of relevance per unit of roughness (boundary noise N(0, 1)
#: measures about 0.44, so its threshold is about 8.3 px; U(-1, 1) about 0.32, 5.9 px).
ROUGHNESS_GAIN: float = 20.0


def coarse_threshold(mask: np.ndarray) -> float:
    """DCE stop of the coarse stage, in pixels of relevance, for this shape.

    ``COARSE_PIXEL_THRESHOLD + ROUGHNESS_GAIN·max(0, roughness − ROUGHNESS_FLOOR)``.

    Examples
    --------
    >>> m = np.zeros((40, 40), bool); m[5:35, 5:35] = True
    >>> coarse_threshold(m)
    2.5
    """
    excess = max(0.0, boundary_roughness(mask) - ROUGHNESS_FLOOR)
    return COARSE_PIXEL_THRESHOLD + ROUGHNESS_GAIN * excess


def coarse_partition(mask: np.ndarray) -> BoundaryPartition:
    """The DCE partition of the coarse stage: the roughness-raised stop
    (:func:`coarse_threshold`), at most :data:`COARSE_VERTICES` vertices a polygon."""
    return boundary_partition(
        mask, n_vertices=COARSE_VERTICES, pixel_threshold=coarse_threshold(mask)
    )


def _convex_vertices(partition: BoundaryPartition) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each convex vertex: the segments before and after it, and its position.

    Segment ``j`` of a polygon starts at its ``j``-th convex vertex, so the vertex
    between segments ``j − 1`` and ``j`` (cyclically) is the start of ``j``. Polygons
    with fewer than three segments are left out: with two, the pair meets twice.
    """
    before, after, positions = [], [], []
    base = 0
    for v, convex in zip(partition.vertices, partition.convex, strict=True):
        cuts = v[convex]
        n = len(cuts) if len(cuts) >= 2 else 1
        if n >= 3:
            before.extend(base + (j - 1) % n for j in range(n))
            after.extend(range(base, base + n))
            positions.extend(cuts)
        base += n
    return (
        np.asarray(before, np.int64),
        np.asarray(after, np.int64),
        np.asarray(positions, np.float64).reshape(-1, 2),
    )


def _flatten(graph: BranchGraph, branches: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """The points of end ``branches``, each from its junction end, and the offsets."""
    lists = [
        br.points[::-1] if br.node[0] is None else br.points
        for br in (graph.branches[b] for b in branches)
    ]
    if len(lists) == 1:  # (most calls: one branch that a merge changed)
        return np.asarray(lists[0], np.int64), np.array([0, len(lists[0])], np.int64)
    offsets = np.zeros(len(lists) + 1, np.int64)
    np.cumsum(np.fromiter(map(len, lists), np.int64, len(lists)), out=offsets[1:])
    return np.fromiter(chain.from_iterable(lists), np.int64, int(offsets[-1])), offsets


class _EndBranches:
    """Support and corner claim of end branches, from rims scanned only when needed.

    A branch is *supported* when two or more segments generate one of its points. It
    *claims* convex vertex ``v`` when its generating segments are exactly the two that
    meet at ``v``. Both are answered in one compiled pass per batch of branches, which
    scans a point's disk rim only when the answer still depends on it: from the
    junction end, where a third segment usually settles both at once, so the large
    interior disks are mostly never scanned. Only merges change a branch, and a merge
    changes its point count: that is the cache key.
    """

    def __init__(
        self,
        graph: BranchGraph,
        r2: np.ndarray,
        partition: BoundaryPartition,
        before: np.ndarray,
        after: np.ndarray,
        positions: np.ndarray,
    ) -> None:
        self.graph = graph
        self.raster = SegmentRaster(partition, np.stack([graph.rows, graph.cols], axis=1), r2)
        n = graph.rows.size
        self.known = np.zeros(n, np.bool_)
        self.supported = np.zeros(n, np.bool_)
        self.first = np.full(n, -1, np.int64)
        self.vertex = np.full(n, -1, np.int64)
        # The convex vertex each segment starts at (-1: none): two segments meet at a
        # vertex only if one starts where the other ends, so this and ``before`` answer
        # "where do a and b meet" in memory linear in the segments (a pair table would
        # be quadratic, and a noisy boundary has as many segments as pixels).
        self.starts_at = np.full(partition.n_segments, -1, np.int64)
        self.starts_at[after] = np.arange(len(after))
        self.before, self.after, self.positions = before, after, positions
        self.cache: dict[int, tuple[int, bool, int, float]] = {}  # b -> (n, sup, v, d2)
        # _branch_states' arguments after the points (the same arrays every call; made
        # on the first, which builds the raster's cells)
        self.shared: tuple | None = None

    def update(self, branches: list[int]) -> None:
        """Bring the cached answers of ``branches`` up to date (one compiled call)."""
        graph = self.graph
        stale = [b for b in branches if self._cached(b) is None]
        if not stale:
            return
        flat, offsets = _flatten(graph, stale)
        if self.shared is None:
            cells = self.raster.cells()
            self.shared = (
                self.raster.seg_lo,
                self.raster.seg_hi,
                cells.start,
                cells.row,
                cells.col,
                cells.lo,
                cells.hi,
                cells.nxt,
                cells.width,
                self.raster.local,
                self.raster.r2,
                self.raster.tolerance,
                self.known,
                self.first,
                self.supported,
                self.vertex,
                self.starts_at,
                self.before,
                self.after,
            )
        sup, claimed = _branch_states(flat, offsets, *self.shared)
        for b, ok, v in zip(stale, sup.tolist(), claimed.tolist(), strict=True):
            d2 = 0.0
            if v >= 0:
                p = graph.endpoint(b)
                dr = graph.rows[p] - self.positions[v, 0]
                dc = graph.cols[p] - self.positions[v, 1]
                d2 = float(dr * dr + dc * dc)
            self.cache[b] = (len(graph.branches[b].points), ok, v, d2)

    def _cached(self, b: int) -> tuple[int, bool, int, float] | None:
        """Branch ``b``'s cached answer, None when there is none or a merge has changed
        the branch since (only a merge changes a branch, and always its length)."""
        hit = self.cache.get(b)
        return None if hit is None or hit[0] != len(self.graph.branches[b].points) else hit

    def is_supported(self, b: int) -> bool:
        hit = self._cached(b)
        if hit is None:
            self.update([b])
            hit = self.cache[b]
        return hit[1]

    def unsupported(self, branches: list[int]) -> list[int]:
        self.update(branches)
        return [b for b in branches if not self.cache[b][1]]

    def surplus(self) -> list[int]:
        """Every claimant but the one ending nearest its vertex (ties: lower id)."""
        ends = self.graph.end_branches()
        self.update(ends)
        by_vertex: dict[int, list[tuple[float, int]]] = {}
        for b in ends:
            _, _, v, d2 = self.cache[b]
            if v >= 0:
                by_vertex.setdefault(v, []).append((d2, b))
        return [b for c in by_vertex.values() if len(c) > 1 for _, b in sorted(c)[1:]]


@numba.njit(cache=True)
def _branch_states(
    flat: np.ndarray,
    offsets: np.ndarray,
    seg_lo: np.ndarray,
    seg_hi: np.ndarray,
    cell_start: np.ndarray,
    cell_row: np.ndarray,
    cell_col: np.ndarray,
    cell_lo: np.ndarray,
    cell_hi: np.ndarray,
    cell_nxt: np.ndarray,
    cell_width: int,
    local: np.ndarray,
    r2: np.ndarray,
    tolerance: float,
    known: np.ndarray,
    first: np.ndarray,
    supported: np.ndarray,
    vertex: np.ndarray,
    starts_at: np.ndarray,
    before: np.ndarray,
    after: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Per branch (points ``flat[offsets[k]:offsets[k + 1]]``): supported, claimed vertex.

    Scans (and records in ``known``/``first``/``supported``/``vertex``) each point
    not scanned yet, until both answers are settled: a supported point and a point
    that rules out every claim (three segments, or two that meet at no convex vertex
    or at another vertex than the branch's).

    A rim's labels are found from the boundary pixels near it (:func:`rim_label_set`),
    which gives the same set of labels (up to three) as the rim scan in another order.
    The answers depend on that set only, except where two segments meet at two convex
    vertices (a closed curve of two segments): then the scan's order picks the vertex,
    and the rim is scanned as before.
    """
    nb = offsets.size - 1
    sup = np.zeros(nb, np.bool_)
    claimed = np.full(nb, -1, np.int64)
    labels = np.empty(3, np.int64)
    for k in range(nb):
        v = -1
        can_claim = True
        for t in range(offsets[k], offsets[k + 1]):
            p = flat[t]
            if not known[p]:
                labels[:] = -1
                rim_label_set(
                    cell_start,
                    cell_row,
                    cell_col,
                    cell_lo,
                    cell_hi,
                    cell_nxt,
                    cell_width,
                    local[p, 0],
                    local[p, 1],
                    r2[p],
                    tolerance,
                    labels,
                )
                if (
                    labels[1] != -1
                    and labels[2] == -1
                    and _meeting_vertex(starts_at, before, labels[0], labels[1])
                    != _meeting_vertex(starts_at, before, labels[1], labels[0])
                ):
                    labels[:] = -1
                    rim_labels(seg_lo, seg_hi, local[p, 0], local[p, 1], r2[p], tolerance, labels)
                known[p] = True
                first[p] = labels[0]
                supported[p] = labels[1] != -1
                if labels[2] != -1:
                    vertex[p] = -2
                elif labels[1] != -1:
                    vertex[p] = _meeting_vertex(starts_at, before, labels[0], labels[1])
            sup[k] |= supported[p]
            if vertex[p] == -2 or (v >= 0 and vertex[p] >= 0 and vertex[p] != v):
                can_claim = False
            elif vertex[p] >= 0:
                v = vertex[p]
            if sup[k] and not can_claim:
                break
        if not can_claim or v < 0:
            continue
        # every point was scanned: those of one segment must lie on one of v's two
        for t in range(offsets[k], offsets[k + 1]):
            p = flat[t]
            if vertex[p] == -1 and first[p] >= 0 and first[p] != before[v] and first[p] != after[v]:
                v = -1
                break
        claimed[k] = v
    return sup, claimed


@numba.njit(cache=True)
def _meeting_vertex(starts_at: np.ndarray, before: np.ndarray, a: int, b: int) -> int:
    """The convex vertex between segments ``a`` and ``b`` (either order), or -2."""
    v = starts_at[b]
    if v >= 0 and before[v] == a:
        return v
    v = starts_at[a]
    if v >= 0 and before[v] == b:
        return v
    return -2


def coarse_dce(skeleton: Skeleton) -> Skeleton:
    """The coarse skeleton: ``skeleton`` (a medial axis) pruned by :func:`coarse_removals`.

    Examples
    --------
    >>> from scipy import ndimage
    >>> m = np.zeros((44, 64), bool); m[4:40, 4:60] = True
    >>> rim = ndimage.binary_dilation(m) & ~m  # one-pixel bumps on half the rim
    >>> bumpy = m | (rim & (np.random.default_rng(0).random(m.shape) < 0.5))
    >>> axis = Skeleton.medial_axis(bumpy)
    >>> coarse = coarse_dce(axis)
    >>> axis.n_endpoints > coarse.n_endpoints == 4
    True
    """
    graph = skeleton.working_graph()
    coarse_removals(graph, skeleton.mask, skeleton.r2)
    return skeleton.with_graph(graph)


def coarse_removals(graph: BranchGraph, mask: np.ndarray, r2: np.ndarray) -> list[int]:
    """Prune ``graph`` (the medial axis of ``mask``) to the coarse level, in place.

    End branches none of whose points two DCE segments generate are removed
    (:func:`~.dce.remove_unsupported`), then surplus branches at one
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
    partition = coarse_partition(mask)
    ends = _EndBranches(graph, r2, partition, *_convex_vertices(partition))
    removed = remove_unsupported(
        graph, ends.is_supported, candidates=ends.unsupported(graph.end_branches())
    )
    while surplus := ends.surplus():
        # one at a time: a removal can merge branches and change other claims
        merged = graph.remove_end_branch(surplus[0])
        removed.append(surplus[0])
        if merged is not None:  # only the merged branch can have lost its support
            removed += remove_unsupported(graph, ends.is_supported, candidates=[merged[0]])
    return removed
