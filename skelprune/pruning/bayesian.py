"""Bayesian skeleton pruning (docs/algorithm.md, eqs. 7 and 9–11 of the paper).

Starting from the medial axis ``M``, end branches are removed one at a time, each
time the one whose removal gives the smallest target ``λ = α·AR + LR``; the
skeleton of the whole sequence with the smallest ``λ`` is the answer.

Each step costs only the owners that change: :class:`~skelprune.grid.coverage.Coverage`
keeps the area each branch alone covers, so the candidates' lost areas are read,
not recomputed, and a removed or merged branch costs the area of the union of its
disks. The naive oracle in ``testkit/oracle.py`` recomputes everything from
scratch and must agree exactly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, Generic, TypeVar

import numpy as np
from numba import njit

from .grid import GridAxis, GridGraph, compiled_length, path_lengths
from .log import RemovalLog

__all__ = [
    "PruningSequence",
    "pruning_sequence",
    "target",
]


def target(lost: int, area: int, length: float, alpha: float, lbar: float) -> float:
    """``λ(S) = α·AR(S) + log(Γ(S) + 1)`` with ``Γ = length / ℓ̄`` (eq. 7), on any grid."""
    return alpha * lost / area + math.log(length / lbar + 1.0)


#: The axis type of one grid: a sequence gives back skeletons of its start's type.
A = TypeVar("A", bound="GridAxis[Any]")


@dataclass
class PruningSequence(Generic[A]):
    """The greedy removal sequence of one component, on any grid (:mod:`.grid`).

    ``log`` holds what each step removed and merged (:class:`~.log.RemovalLog`); the
    per-skeleton lists have one entry per skeleton ``S(0)``, …, ``S(n)``, ``S(0)`` being
    ``start``.
    """

    start: A
    log: RemovalLog
    lost: list[int]
    #: Per skeleton: its steps of each kind (the grid's :attr:`~.grid.GridAxis.step_weights`
    #: turn them into its length).
    steps: list[tuple[int, ...]]
    area: int
    alpha: float | None
    lbar: float
    #: The graph of ``S(n)``, the last skeleton of the sequence.
    end: GridGraph
    #: Flat indices (into the shape) of the elements of ``D`` that ``S(0)`` misses; recorded
    #: only when asked for (``pruning_sequence(..., uncovered=True)``).
    uncovered: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    #: Per step ``i`` before the last: the end branches of ``S(i)`` and the area each alone
    #: covers (what removing it would lose), as read for the choice; for the margins.
    end_areas: list[tuple[np.ndarray, np.ndarray]] = field(default_factory=list)

    @property
    def removed(self) -> list[int]:
        """``removed[i]``: the end branch removed at step ``i + 1``."""
        return self.log.branch

    @cached_property
    def length(self) -> np.ndarray:
        return path_lengths(np.asarray(self.steps, np.int64), self.start.step_weights)

    @cached_property
    def rer(self) -> np.ndarray:
        return np.asarray(self.lost, float) / self.area

    @cached_property
    def ss(self) -> np.ndarray:
        if not self.lbar > 0:
            return np.zeros(len(self.lost))
        return np.log(self.length / self.lbar + 1.0)

    @cached_property
    def objective(self) -> np.ndarray:
        if self.alpha is None:
            return self.ss
        return np.array(
            [
                target(lo, self.area, length, self.alpha, self.lbar)
                for lo, length in zip(self.lost, self.length.tolist(), strict=True)
            ]
        )

    def skeleton_at(self, step: int) -> A:
        """``S(step)``: the start with the first ``step`` removals made (on a copy): the
        answer's graph as a structure, which only the graph's own edits can give."""
        if step == len(self.removed):
            return self.start.with_graph(self.end)
        graph = self.start.working_graph()
        for b in self.removed[:step]:
            graph.remove_end_branch(b)
        return self.start.with_graph(graph)


def pruning_sequence(
    start: A,
    alpha: float | None,
    lbar: float,
    order: list[int] | None = None,
    uncovered: bool = False,
) -> PruningSequence[A]:
    """Remove end branches until none is left; record every step.

    Speaks to the grid only through :mod:`.grid`'s interface, so that one sequence serves
    the pixel and the volume grid.

    Parameters
    ----------
    start : GridAxis
        The skeleton to prune, ``S(0)`` (left as it is: the sequence works on a copy).
    alpha, lbar : float
        ``α`` and ``ℓ̄`` of the medial axis. Bayesian order (eqs. 9–11); with
        ``alpha=None`` (degenerate shapes) nothing is removed.
    order : list of int, optional
        Instead of choosing by λ, remove exactly these end branches in this order
        (e.g. :func:`skelprune.grid.dce.remove_unsupported` run on a twin graph, for
        ``method="dce"``),
        recording every step the same way.
    uncovered : bool
        Also record which elements ``S(0)`` misses (``PruningSequence.uncovered``).
    """
    graph = start.working_graph()
    area = start.area
    coords = graph.coords
    weights = np.ascontiguousarray(start.step_weights, np.float64)
    nb = len(graph.branches)
    # Labels: branch b + 1, junction nb + 1 + j; written in one assignment (one per
    # branch cost more than the rest of the set-up on small shapes).
    owned: list[int] = []
    label_of: list[int] = []
    size: list[int] = []
    for b, br in enumerate(graph.branches):
        if br.alive:
            owned += br.points
            label_of.append(b + 1)
            size.append(len(br.points))
    for j, junc in enumerate(graph.junctions):
        if junc.alive:
            owned += junc.points
            label_of.append(nb + 1 + j)
            size.append(len(junc.points))
    labels = np.zeros(coords[0].size, np.int64)
    labels[np.fromiter(owned, np.int64, len(owned))] = np.repeat(
        np.asarray(label_of, np.int64), np.asarray(size, np.int64)
    )
    cov = start.coverage(graph, labels, nb + len(graph.junctions) + 1)
    seq = PruningSequence(
        start, RemovalLog(), [cov.lost], [graph.total_steps()], area, alpha, lbar, end=graph
    )
    log = seq.log
    if uncovered:
        seq.uncovered = cov.uncovered()
    if alpha is None and order is None:
        return seq
    # Per-branch arrays, so that one compiled call ranks all candidates of a step.
    is_end = np.zeros(nb, np.bool_)
    bsteps = np.array([graph.branch_steps(b) for b in range(nb)], np.int64).reshape(
        nb, weights.size
    )
    ep = np.zeros((nb, len(coords)), np.int64)

    # Limbs are never candidates (docs/algorithm.md, "Limbs"); only the greedy order
    # looks for them.
    guard = start.limb_test(graph) if order is None else None
    follow = getattr(guard, "follow", None)
    if follow is not None:  # a grid's limb test that reads the sequence's own coverage
        follow(cov)

    def mark_end(b: int) -> None:
        end = graph.is_end_branch(b) and not (guard is not None and guard.limb[b])
        is_end[b] = end
        if end:
            p = graph.endpoint(b)
            for k, c in enumerate(coords):  # (element by element: a row from a list costs more)
                ep[b, k] = c[p]

    for b in graph.ends:
        mark_end(b)
    total_steps = seq.steps[0]  # the graph's, kept up to date with each removal
    while graph.ends:
        if order is None:
            assert alpha is not None
            # The best end branch that is not a limb; a limb found is kept for good.
            total = np.asarray(total_steps, np.int64)
            while True:
                pick = _pick(
                    is_end, cov.exclusive, bsteps, ep, cov.lost, area, total, weights, alpha, lbar
                )
                if (
                    pick < 0
                    or guard is None
                    or not guard.is_limb(pick, int(cov.exclusive[pick + 1]))
                ):
                    break
                is_end[pick] = False
            if pick < 0:  # only limbs are left
                break
            # (the limbs found are no longer end branches here; the areas did not move)
            ends = is_end.nonzero()[0]
            seq.end_areas.append((ends, cov.exclusive[ends + 1]))
            if guard is not None:
                guard.removed(pick)
        elif len(seq.removed) < len(order):
            ends = is_end.nonzero()[0]
            seq.end_areas.append((ends, cov.exclusive[ends + 1]))
            pick = order[len(seq.removed)]
        else:
            break
        # Coverage works on labels: a branch's points all carry its label, and a merge
        # moves whole owners (the junction cluster and the absorbed branch).
        cov.remove_label(pick + 1)
        taken = graph.branches[pick].points
        merged = graph.remove_end_branch(pick)
        log.record(pick, taken, merged)
        is_end[pick] = False
        if merged is not None:
            kept, absorbed, jid = merged
            if guard is not None:
                guard.merged(kept, absorbed)
            cov.merge_label(nb + 1 + jid, kept + 1)
            cov.merge_label(absorbed + 1, kept + 1)
            is_end[absorbed] = False
            bsteps[kept] = graph.branch_steps(kept)
            mark_end(kept)
        seq.lost.append(cov.lost)
        total_steps = graph.total_steps()
        seq.steps.append(total_steps)
    return seq


@njit(cache=True)
def _pick(is_end, exclusive, bsteps, ep, lost, area, total, weights, alpha, lbar):
    """The end branch to remove: smallest (λ, lost area, length, endpoint coordinates).

    λ is computed with exactly the operations of :func:`target` and lengths with those
    of :func:`~.grid.path_length`, so that the choice is bit-identical to the oracle's.
    """
    best = -1
    b_lam = b_len = 0.0
    b_d = 0
    rest = np.empty_like(total)
    for b in range(is_end.size):
        if not is_end[b]:
            continue
        d = exclusive[b + 1]
        for k in range(total.size):
            rest[k] = total[k] - bsteps[b, k]
        lam = alpha * (lost + d) / area + math.log(compiled_length(rest, weights) / lbar + 1.0)
        length = compiled_length(bsteps[b], weights)
        better = best < 0
        if not better:
            if lam != b_lam:
                better = lam < b_lam
            elif d != b_d:
                better = d < b_d
            elif length != b_len:
                better = length < b_len
            else:
                for k in range(ep.shape[1]):
                    if ep[b, k] != ep[best, k]:
                        better = ep[b, k] < ep[best, k]
                        break
        if better:
            best, b_lam, b_d, b_len = b, lam, d, length
    return best
