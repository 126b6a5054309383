"""How clearly the trade-off keeps each branch of the answer: its margin.

For the answer ``Ŝ = S(k)`` of the greedy sequence and ``λ`` its target (eq. 7):

- an **end branch** ``E`` of ``Ŝ`` has margin ``λ(Ŝ − E) − λ(Ŝ)``: how much the target
  rises if ``E`` alone is removed (with the junction it leaves dissolved, exactly as the
  pruning would). The end branch the sequence removes next has the smallest one, and
  since ``Ŝ`` is the argmin (ties to the later skeleton) it is > 0; the others are at
  least as large, up to the length a dissolved junction adds.
- an **inner branch** (both ends at junctions, or a cycle) cannot be removed on its own;
  its margin is ``λ(S(j)) − λ(Ŝ)`` for the first step ``j > k`` at which the sequence
  removes any of its points (it first becomes part of an end branch, then goes). It is
  > 0 by the argmin.
- a branch the sequence never removes (the last path of a tree, a limb, the cycles of a
  shape with holes) has no margin (``None``): nothing in the pruning would take it.

``removed_at`` is that step ``j`` for every branch (``None``: never removed). Both come
from the sequence already run: it records, at each step, the area each end branch alone
covers (what the choice reads anyway), and its log which branches merged.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

from .bayesian import PruningSequence, target
from .grid import GridGraph, path_length

__all__ = ["Margins", "branch_margins"]


@dataclass(frozen=True)
class Margins:
    """Per branch id of the answer's graph: margin and the step that removes it."""

    margin: dict[int, float | None] = field(default_factory=dict)
    removed_at: dict[int, int | None] = field(default_factory=dict)


class TrimmedAnswer(Protocol):
    """The tips cut from an answer, on any grid (:class:`~.tips.Trim`, the volume's
    :class:`~skelprune.grid3d.tips.VolumeTrim`)."""

    @property
    def lost(self) -> int: ...

    @property
    def steps(self) -> Sequence[int]: ...

    @property
    def exclusive(self) -> dict[int, int]: ...


def branch_margins(
    graph: GridGraph,
    seq: PruningSequence[Any],
    chosen: int,
    trim: TrimmedAnswer | None = None,
) -> Margins:
    """Margins of the branches of ``graph``, which is ``S(chosen)`` of ``seq``, or its
    tips cut (``trim``): then ``λ(Ŝ)`` and the end branches' areas are the trimmed
    skeleton's.

    Parameters
    ----------
    graph : GridGraph
        The answer's graph (not modified).
    seq : PruningSequence
        The sequence ``graph`` is step ``chosen`` of; its recorded end-branch areas and
        its removal log are all the margins need.
    chosen : int
        The answer's step.
    trim : TrimmedAnswer, optional
        The tips cut from ``S(chosen)``, when ``graph`` is the trimmed skeleton.
    """
    alive = [b for b, br in enumerate(graph.branches) if br.alive]
    removed_at = seq.log.removal_steps(alive, chosen)
    alpha = seq.alpha
    if alpha is None or not seq.lbar > 0:
        return Margins({b: None for b in alive}, removed_at)
    lam = seq.objective
    base = float(lam[chosen])
    weights = seq.start.step_weights

    def without(lost: int, b: int) -> float:
        length = path_length(graph.counts_without(b), weights)
        return target(lost, seq.area, length, alpha, seq.lbar) - base

    if trim is not None:
        length = path_length(trim.steps, weights)
        base = target(trim.lost, seq.area, length, alpha, seq.lbar)
    margin: dict[int, float | None] = {}
    for b in alive:
        j = removed_at[b]
        margin[b] = None if j is None else float(lam[j]) - base
    if trim is not None:
        for b, d in trim.exclusive.items():
            if removed_at.get(b, 0) is None:  # a limb: never removed
                continue
            margin[b] = without(trim.lost + d, b)
    elif chosen < len(seq.end_areas):
        lost = seq.lost[chosen]
        ends, areas = seq.end_areas[chosen]
        for b, d in zip(ends.tolist(), areas.tolist(), strict=True):
            if removed_at.get(b, 0) is None:  # a limb found later: never removed
                continue
            margin[b] = without(lost + d, b)
    return Margins(margin, removed_at)
