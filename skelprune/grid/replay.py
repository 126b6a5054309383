"""A pruning sequence seen from its start, for a viewer of the whole sequence.

:func:`replay` gives, for each branch and junction of ``S(0)``, the step that takes its
pixels and the merges it takes part in (read from the sequence's log);
:func:`start_repaint` gives what ``S(0)`` leaves of the shape (the error of step 0) and
the medial axis's pixels the coarse stage took before step 0. With them, every ``S(k)``
and its reconstruction follow from ``S(0)``'s disks alone.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..pruning.log import SequenceEvents
from ..skeleton import Skeleton
from .reconstruction import reconstruction

if TYPE_CHECKING:
    from ..pruning.bayesian import PruningSequence

__all__ = ["SequenceEvents", "replay", "start_repaint"]


def replay(seq: PruningSequence[Skeleton]) -> SequenceEvents:
    """What ``seq``'s removals do to each branch and junction of its start's graph."""
    graph = seq.start.graph
    alive = [b for b, br in enumerate(graph.branches) if br.alive]
    return seq.log.events(alive, len(graph.branches), len(graph.junctions))


def start_repaint(start: Skeleton) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rows and columns (in ``start``'s own frame) of the shape's pixels that ``S(0)``
    does not reconstruct, and the indices of the graph's points not in ``S(0)`` (the
    medial axis's pixels a coarse stage removed before step 0)."""
    idx = start.points()
    covered = reconstruction(start.mask.shape, start.rows[idx], start.cols[idx], start.r2[idx])
    miss_r, miss_c = np.nonzero(start.mask & ~covered)
    gone = np.ones(start.rows.size, bool)
    gone[idx] = False
    return miss_r, miss_c, np.flatnonzero(gone)
