"""Limbs the greedy pruning never removes (docs/algorithm.md, "Limbs").

The trade-off ``λ = α·AR + LR`` weighs a branch's lost area against the whole shape's
area: on a large body a thin limb (a fruit's stem, a neurite) reconstructs little
against its length, and the greedy removes it whole, although it is a part of the shape
anyone sees. A noise spur differs from such a limb by what it alone reconstructs:

* a **limb** has points whose whole maximal disk only the branch covers (beyond the
  body, nothing else reaches into the limb), one after another along the limb, over a
  stretch at least as long as the limb is wide;
* a **spur** into a bump of the boundary reconstructs a sliver of the bump: the disks of
  its points reach into the body, where other branches cover them too; a pimple of the
  boundary's pixel noise has at most a point or two whose disk it alone covers.

So an end branch is a *limb* when at least ``2·r`` of its points (``r`` the largest
radius among them) have their whole disk ``|p − s|² < r(s)²`` covered by that branch
alone, counting only points deeper than the boundary's one-pixel rim (``r(s)² > 2``:
a disk of the rim holds no pixel a one-pixel move of the boundary would keep). No
constant is fitted: ``2·r`` is the limb's own width, the rim the grid's resolution.

The sequence tests the end branch it is about to remove; a limb is marked and never
removed (nor is the branch it later merges into), and the next best end branch goes
instead. The sequence then ends when only limbs are left as end branches.
"""

from __future__ import annotations

import math

import numpy as np

from ..grid.graph import BranchGraph
from ..grid.medial_axis import squared_distance
from ._rowcover import cover_counts, limb_cover, uncover

__all__ = ["MIN_LIMB_AREA", "RIM", "LimbGuard"]

#: Squared radius up to which a disk lies in the boundary's one-pixel rim (as
#: :data:`skelprune.pruning.choice.RIM`).
RIM = 2
#: The fewest pixels a limb alone covers: the whole disks of at least 4 distinct points
#: (``2·r > 2·√2``), each holding the 3 × 3 block around its point (``r² ≥ 4``), cover
#: at least a 4 × 4 block. A branch alone covering fewer is no limb, untested.
MIN_LIMB_AREA = 16


class LimbGuard:
    """The disk counts of the sequence's current skeleton and the limbs found so far.

    Parameters
    ----------
    graph : BranchGraph
        The sequence's working graph (read, never changed here).
    mask : (H, W) bool array
        The padded shape.
    r2 : int array
        Squared radius of every point of ``graph``.

    Examples
    --------
    A disc with three arms 5 px wide: each arm's end branch is a limb.

    >>> from skelprune.skeleton import Skeleton
    >>> yy, xx = np.mgrid[:100, :100]
    >>> m = (yy - 50) ** 2 + (xx - 50) ** 2 < 22**2
    >>> m[48:53, 60:95] = m[60:95, 48:53] = m[5:40, 48:53] = True
    >>> sk = Skeleton.medial_axis(m)
    >>> g = sk.working_graph()
    >>> guard = LimbGuard(g, sk.mask, sk.r2)
    >>> [guard.is_limb(b, exclusive=10**6) for b in g.end_branches()]
    [True, True, True]
    """

    def __init__(self, graph: BranchGraph, mask: np.ndarray, r2: np.ndarray) -> None:
        self.graph, self.mask, self.r2 = graph, mask, r2
        # The disk counts of the current skeleton, made when first needed.
        self.counts: np.ndarray | None = None
        self.limb = np.zeros(len(graph.branches), np.bool_)

    def _points(self, b: int) -> np.ndarray:
        return np.asarray(self.graph.branches[b].points, np.int64)

    def is_limb(self, b: int, exclusive: int) -> bool:
        """Whether end branch ``b``, which alone covers ``exclusive`` pixels, is a limb,
        on the current skeleton; a limb is remembered (:attr:`limb`)."""
        if self.limb[b]:
            return True
        if exclusive < MIN_LIMB_AREA:
            return False
        if self.counts is None:
            g, alive = self.graph, self.graph.alive_points()
            h, w = self.mask.shape
            self.counts = cover_counts(h, w, g.rows[alive], g.cols[alive], self.r2[alive])
        pts = self._points(b)
        # the test below in one compiled call, unless the box has no background
        quick = limb_cover(self.counts, self.graph.rows, self.graph.cols, self.r2, pts, RIM)
        if quick >= 0:
            self.limb[b] = quick == 1
            return quick == 1
        rows, cols, r2 = self.graph.rows[pts], self.graph.cols[pts], self.r2[pts]
        deep = r2 > RIM
        if deep.sum() < 4:  # 2·r > 2·√2: at least 4 points are needed
            return False
        # The box of the branch's disks and one pixel more: what it alone covers lies
        # inside, with a pixel it does not cover all around (for the distances).
        rad = np.ceil(np.sqrt(r2)).astype(np.int64)
        h, w = self.mask.shape
        top, left = max(int((rows - rad).min()), 0), max(int((cols - rad).min()), 0)
        bottom = min(int((rows + rad).max()) + 1, h)
        right = min(int((cols + rad).max()) + 1, w)
        before = self.counts[top:bottom, left:right]
        after = before.copy()
        uncover(after, rows - top, cols - left, r2)
        only = (after == 0) & (before > 0)
        d2 = squared_distance(only)
        whole = d2[rows[deep] - top, cols[deep] - left] >= r2[deep]
        found = bool(whole.any() and whole.sum() >= 2.0 * math.sqrt(float(r2[deep][whole].max())))
        self.limb[b] = found
        return found

    def removed(self, b: int) -> None:
        """Branch ``b`` leaves the skeleton (call before the graph removes it)."""
        if self.counts is None:
            return
        pts = self._points(b)
        uncover(self.counts, self.graph.rows[pts], self.graph.cols[pts], self.r2[pts])

    def merged(self, kept: int, absorbed: int) -> None:
        """``absorbed`` became part of ``kept``: a limb in it keeps ``kept`` a limb."""
        self.limb[kept] |= self.limb[absorbed]
