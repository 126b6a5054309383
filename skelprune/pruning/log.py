"""The removals of a pruning sequence, recorded once, on any grid.

The greedy sequence (:func:`~.bayesian.pruning_sequence`) edits its graph and writes, for
every step, what the edit did: which end branch went, with which points, and whether the
junction it left dissolved, merging two branches. Everything that needs the removals
after the sequence reads this log: the margins' removal steps, the noise floor's counts,
and a viewer's per-branch events (:meth:`RemovalLog.events`); none of them edits a graph
or works the removals out again.

Examples
--------
>>> log = RemovalLog()
>>> log.record(3, [7, 8], None)
>>> log.record(1, [4, 5, 6], (0, 2, 1))
>>> log.points(1).tolist(), log.merge(1), log.removal_steps([0, 2])
([4, 5, 6], (0, 2, 1), {0: None, 2: None})
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

__all__ = ["RemovalLog", "SequenceEvents"]


@dataclass(frozen=True)
class SequenceEvents:
    """What a sequence does to its start ``S(0)``, by the graph's own branch and junction
    ids (-1: never, or not a live branch or junction of ``S(0)``).

    ``removed_at[b]``: the step whose removal takes branch ``b``'s points (its own, or
    that of the branch it became part of); ``absorbed_at[b]`` and ``absorbed_into[b]``:
    the step at which ``b`` became part of another branch, and that branch (a junction
    dissolved between them). For junction ``j``: ``junction_removed_at[j]``,
    ``dissolved_at[j]`` (the step at which two branch ends were left) and
    ``dissolved_into[j]`` (the branch its points then joined).
    """

    removed_at: np.ndarray
    absorbed_at: np.ndarray
    absorbed_into: np.ndarray
    junction_removed_at: np.ndarray
    dissolved_at: np.ndarray
    dissolved_into: np.ndarray


@dataclass
class RemovalLog:
    """Step ``i + 1`` of a sequence, for ``i`` from 0: end branch ``branch[i]`` removed,
    taking ``points(i)`` (its own points and those of everything it had absorbed); when
    the junction it left was left with two branch ends, that junction ``junction[i]``
    dissolved and branch ``absorbed[i]`` became part of ``kept[i]`` (equal for a loop
    closing on itself); otherwise the three are -1."""

    branch: list[int] = field(default_factory=list)
    kept: list[int] = field(default_factory=list)
    absorbed: list[int] = field(default_factory=list)
    junction: list[int] = field(default_factory=list)
    #: The steps' points, one after the other: step ``i``'s are
    #: ``_points[_offsets[i]:_offsets[i + 1]]``.
    _points: list[int] = field(default_factory=list)
    _offsets: list[int] = field(default_factory=lambda: [0])

    def __len__(self) -> int:
        return len(self.branch)

    def record(
        self, branch: int, points: Iterable[int], merged: tuple[int, int, int] | None
    ) -> None:
        """Write one step: the branch removed, its points, and the graph's answer to the
        removal (``(kept, absorbed, junction)`` or None)."""
        self.branch.append(branch)
        self._points.extend(points)
        self._offsets.append(len(self._points))
        kept, absorbed, junction = (-1, -1, -1) if merged is None else merged
        self.kept.append(kept)
        self.absorbed.append(absorbed)
        self.junction.append(junction)

    def points(self, i: int) -> np.ndarray:
        """The points step ``i + 1`` took."""
        return np.asarray(self._points[self._offsets[i] : self._offsets[i + 1]], np.int64)

    def merge(self, i: int) -> tuple[int, int, int] | None:
        """``(kept, absorbed, junction)`` of step ``i + 1``'s merge, or None."""
        if self.kept[i] < 0:
            return None
        return self.kept[i], self.absorbed[i], self.junction[i]

    def removal_steps(self, owners: Sequence[int], start: int = 0) -> dict[int, int | None]:
        """The step at which the log, from step ``start + 1`` on, takes each of the
        branches ``owners`` of ``S(start)`` (None: never)."""
        held = {b: [b] for b in owners}  # running branch -> the owners it holds
        steps: dict[int, int | None] = dict.fromkeys(owners)
        for i in range(start, len(self.branch)):
            for b in held.pop(self.branch[i], []):
                steps[b] = i + 1
            kept, absorbed = self.kept[i], self.absorbed[i]
            if kept != absorbed:  # (a loop closing keeps its id)
                held.setdefault(kept, []).extend(held.pop(absorbed, []))
        return steps

    def events(self, alive: Sequence[int], n_branches: int, n_junctions: int) -> SequenceEvents:
        """Per branch and junction of the start (whose live branches are ``alive``, of
        ``n_branches`` and ``n_junctions`` ids), what the logged steps did to it."""
        removed_at, absorbed_at, absorbed_into = (
            np.full(n_branches, -1, np.int64) for _ in range(3)
        )
        j_removed, dissolved_at, dissolved_into = (
            np.full(n_junctions, -1, np.int64) for _ in range(3)
        )
        # Owners as the sequence goes: a running branch holds the start's branches and
        # junctions merged into it.
        held: dict[int, tuple[list[int], list[int]]] = {b: ([b], []) for b in alive}
        for i, pick in enumerate(self.branch):
            step = i + 1
            own_b, own_j = held.pop(pick)
            removed_at[own_b] = step
            j_removed[own_j] = step
            kept, absorbed, jid = self.kept[i], self.absorbed[i], self.junction[i]
            if kept < 0:
                continue
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
