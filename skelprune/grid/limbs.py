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
from numba import njit

from ..pruning.limb_memory import LimbMemory
from ._edt import _squared_edt
from ._rowcover import cover_counts, uncover
from .graph import BranchGraph

__all__ = ["MIN_LIMB_AREA", "RIM", "LimbGuard"]

#: Squared radius up to which a disk lies in the boundary's one-pixel rim (as
#: :data:`skelprune.pruning.choice.RIM`).
RIM = 2
#: The fewest pixels a limb alone covers: the whole disks of at least 4 distinct points
#: (``2·r > 2·√2``), each holding the 3 × 3 block around its point (``r² ≥ 4``), cover
#: at least a 4 × 4 block. A branch alone covering fewer is no limb, untested.
MIN_LIMB_AREA = 16


class LimbGuard(LimbMemory):
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
        super().__init__(graph)
        self.graph: BranchGraph = graph
        self.mask, self.r2 = mask, r2

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
        g = self.graph
        whole, widest = _whole_disks(self.counts, g.rows[pts], g.cols[pts], self.r2[pts])
        found = whole > 0 and whole >= 2.0 * math.sqrt(float(widest))
        self.limb[b] = found
        return found

    def _uncover(self, points: np.ndarray) -> None:
        g = self.graph
        assert self.counts is not None
        uncover(self.counts, g.rows[points], g.cols[points], self.r2[points])


@njit(cache=True)
def _whole_disks(counts, rows, cols, r2):
    """How many of a branch's points deeper than the rim have their whole disk covered
    by the branch alone, and the largest squared radius among them (0, 0 when fewer than
    4 points are deeper than the rim: ``2·r > 2·√2`` needs at least 4).

    ``counts``: the disk counts of the current skeleton, the branch's disks included.
    """
    deep = 0
    for k in range(r2.size):
        if r2[k] > RIM:
            deep += 1
    if deep < 4:
        return 0, 0
    # The box of the branch's disks and one pixel more: what it alone covers lies
    # inside, with a pixel it does not cover all around (for the distances).
    h, w = counts.shape
    top, left, bottom, right = h, w, 0, 0
    for k in range(rows.size):
        rad = math.ceil(math.sqrt(r2[k]))
        top = min(top, rows[k] - rad)
        left = min(left, cols[k] - rad)
        bottom = max(bottom, rows[k] + rad + 1)
        right = max(right, cols[k] + rad + 1)
    top, left = max(top, 0), max(left, 0)
    bottom, right = min(bottom, h), min(right, w)
    before = counts[top:bottom, left:right]
    after = before.copy()
    uncover(after, rows - top, cols - left, r2)
    d2 = _squared_edt((after == 0) & (before > 0))
    whole = widest = 0
    for k in range(rows.size):
        if r2[k] > RIM and d2[rows[k] - top, cols[k] - left] >= r2[k]:
            whole += 1
            widest = max(widest, r2[k])
    return whole, widest
