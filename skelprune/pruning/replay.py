"""Replaying a pruning sequence on its start, for a viewer of the whole sequence.

:func:`replay` repeats a sequence's removals on a copy of ``S(0)``'s graph and records,
for each branch and junction of ``S(0)``, the step that takes its pixels and the merges
it takes part in; :func:`start_repaint` gives what ``S(0)`` leaves of the shape (the
error of step 0) and the medial axis's pixels the coarse stage took before step 0.
With them, every ``S(k)`` and its reconstruction follow from ``S(0)``'s disks alone.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..grid.reconstruction import reconstruction
from ..skeleton import Skeleton

__all__ = ["SequenceEvents", "replay", "start_repaint"]


@dataclass(frozen=True)
class SequenceEvents:
    """What a sequence does to ``S(0)``, by the graph's own branch and junction ids
    (-1: never, or not a live branch or junction of ``S(0)``).

    ``removed_at[b]``: the step whose removal takes branch ``b``'s pixels (its own, or
    that of the branch it became part of); ``absorbed_at[b]`` and ``absorbed_into[b]``:
    the step at which ``b`` became part of another branch, and that branch (a junction
    dissolved between them). For junction ``j``: ``junction_removed_at[j]``,
    ``dissolved_at[j]`` (the step at which two branch ends were left) and
    ``dissolved_into[j]`` (the branch its pixels then joined).
    """

    removed_at: np.ndarray
    absorbed_at: np.ndarray
    absorbed_into: np.ndarray
    junction_removed_at: np.ndarray
    dissolved_at: np.ndarray
    dissolved_into: np.ndarray


def replay(start: Skeleton, removed: list[int]) -> SequenceEvents:
    """The events of removing ``removed`` (one branch per step, from step 1) from
    ``start``, replayed on a copy of its graph, so that they are exactly the
    sequence's."""
    graph = start.working_graph()
    nb, nj = len(graph.branches), len(graph.junctions)
    removed_at, absorbed_at, absorbed_into = (np.full(nb, -1, np.int64) for _ in range(3))
    j_removed, dissolved_at, dissolved_into = (np.full(nj, -1, np.int64) for _ in range(3))
    # Owners as the sequence goes: a graph branch holds the S(0) branches and
    # junctions merged into it.
    held: dict[int, tuple[list[int], list[int]]] = {
        b: ([b], []) for b, br in enumerate(graph.branches) if br.alive
    }
    for step, pick in enumerate(removed, start=1):
        merged = graph.remove_end_branch(pick)
        own_b, own_j = held.pop(pick)
        removed_at[own_b] = step
        j_removed[own_j] = step
        if merged is None:
            continue
        kept, absorbed, jid = merged
        dissolved_at[jid] = step
        dissolved_into[jid] = kept
        held[kept][1].append(jid)
        if absorbed != kept:
            absorbed_at[absorbed] = step
            absorbed_into[absorbed] = kept
            more_b, more_j = held.pop(absorbed)
            held[kept][0].extend(more_b)
            held[kept][1].extend(more_j)
    return SequenceEvents(
        removed_at, absorbed_at, absorbed_into, j_removed, dissolved_at, dissolved_into
    )


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
