"""What every grid's limb test keeps (docs/algorithm.md, "Limbs").

The rule is one on every grid: an end branch is a *limb* when enough of its points
deeper than the boundary's rim have their whole disk (ball) covered by that branch
alone; a limb is remembered and never removed, nor is the branch it later merges into.
Each grid counts the disks or balls its own way (:class:`skelprune.grid.limbs.LimbGuard`,
:class:`skelprune.grid3d.limbs.VolumeLimbs`); :class:`LimbMemory` holds what they share:
the limbs found so far, the counts of the current skeleton, kept up to date as branches
leave it, and the limbs carried through merges.
"""

from __future__ import annotations

import numpy as np

from .grid import GridGraph

__all__ = ["LimbMemory"]


class LimbMemory:
    """The limbs found so far on a sequence's working graph, and the disk (ball) counts
    of its current skeleton (``None`` until a test first needs them).

    A grid's test subclasses it with ``is_limb`` and :meth:`_uncover`.

    Parameters
    ----------
    graph : GridGraph
        The sequence's working graph (read, never changed here).
    """

    def __init__(self, graph: GridGraph) -> None:
        self.graph = graph
        self.counts: np.ndarray | None = None
        self.limb = np.zeros(len(graph.branches), np.bool_)

    def _points(self, b: int) -> np.ndarray:
        return np.asarray(self.graph.branches[b].points, np.int64)

    def _uncover(self, points: np.ndarray) -> None:
        """Take the disks (balls) of ``points`` off :attr:`counts`."""
        raise NotImplementedError

    def removed(self, b: int) -> None:
        """Branch ``b`` leaves the skeleton (call before the graph removes it)."""
        if self.counts is None:
            return
        self._uncover(self._points(b))

    def merged(self, kept: int, absorbed: int) -> None:
        """``absorbed`` became part of ``kept``: a limb in it keeps ``kept`` a limb."""
        self.limb[kept] |= self.limb[absorbed]
