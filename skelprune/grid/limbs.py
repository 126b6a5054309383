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

import numpy as np

from ..pruning.limb_memory import LimbMemory
from ._limb_counts import is_limb_on_tiles
from .coverage import Coverage
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
    """The limbs found so far, tested on the coverage of the sequence's current skeleton.

    Parameters
    ----------
    graph : BranchGraph
        The sequence's working graph (read, never changed here).
    mask : (H, W) bool array
        The padded shape.
    r2 : int array
        Squared radius of every point of ``graph``.

    Attributes
    ----------
    coverage : Coverage or None
        The coverage of the current skeleton, one owner per branch and per junction
        cluster: a pixel of a branch's disk that no other point's disk reaches is one
        with a single owner. Made from ``graph`` when first needed and then kept up to
        date by :meth:`removed` and :meth:`merged`; or given (:meth:`follow`) by a
        sequence that keeps its own up to date, the branch ``b`` as owner ``b + 1``.

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
        self.coverage: Coverage | None = None
        # Whether this guard made the coverage (and so keeps it up to date), the label
        # of the first junction in it, and the junction of the branch last removed.
        self._own, self._junction0, self._junction = False, 0, -1

    def follow(self, coverage: Coverage) -> None:
        """Test on ``coverage``, which its owner keeps up to date (branch ``b`` labelled
        ``b + 1``, as :func:`~skelprune.pruning.bayesian.pruning_sequence` does)."""
        self.coverage, self._own = coverage, False

    def _coverage(self) -> Coverage:
        if self.coverage is None:
            g = self.graph
            nb = len(g.branches)
            labels = np.zeros(g.rows.size, np.int64)
            for b, br in enumerate(g.branches):
                if br.alive:
                    labels[br.points] = b + 1
            for j, junc in enumerate(g.junctions):
                if junc.alive:
                    labels[junc.points] = nb + 1 + j
            alive = g.alive_points()
            self.coverage = Coverage(
                self.mask,
                g.rows[alive],
                g.cols[alive],
                self.r2[alive],
                labels[alive],
                nb + len(g.junctions) + 1,
            )
            self._own, self._junction0 = True, nb + 1
        return self.coverage

    def is_limb(self, b: int, exclusive: int) -> bool:
        """Whether end branch ``b``, which alone covers ``exclusive`` pixels, is a limb,
        on the current skeleton; a limb is remembered (:attr:`limb`)."""
        if self.limb[b]:
            return True
        if exclusive < MIN_LIMB_AREA:
            return False
        cov = self._coverage()
        pts = np.asarray(self.graph.branches[b].points, np.int64)
        g = self.graph
        found = bool(
            is_limb_on_tiles(
                cov.c, cov.opened, cov.tile, cov.tw, g.rows[pts], g.cols[pts], self.r2[pts], RIM
            )
        )
        self.limb[b] = found
        return found

    def removed(self, b: int) -> None:
        """Branch ``b`` leaves the skeleton (call before the graph removes it)."""
        if self.coverage is None or not self._own:
            return
        node = self.graph.branches[b].node
        jid = node[0] if node[0] is not None else node[1]
        self._junction = -1 if jid is None else jid
        self.coverage.remove_label(b + 1)

    def merged(self, kept: int, absorbed: int) -> None:
        """``absorbed`` became part of ``kept`` (with the junction of the branch last
        removed): a limb in it keeps ``kept`` a limb."""
        super().merged(kept, absorbed)
        if self.coverage is not None and self._own:
            self.coverage.merge_label(self._junction0 + self._junction, kept + 1)
            self.coverage.merge_label(absorbed + 1, kept + 1)
