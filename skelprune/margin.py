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
- a branch the sequence never removes (the last path of a tree, the cycles of a shape
  with holes) has no margin (``None``): nothing in the trade-off would take it.

``removed_at`` is that step ``j`` for every branch (``None``: never removed). Both are
computed from the sequence already run, plus one coverage of ``Ŝ`` for the areas of
its end branches.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .graph import BranchGraph
from .pruning import PruningSequence, objective
from .reconstruction import Coverage

__all__ = ["Margins", "branch_margins"]


@dataclass(frozen=True)
class Margins:
    """Per branch id of the answer's graph: margin and the step that removes it."""

    margin: dict[int, float | None] = field(default_factory=dict)
    removed_at: dict[int, int | None] = field(default_factory=dict)


def branch_margins(graph: BranchGraph, mask: np.ndarray, r2: np.ndarray,
                   seq: PruningSequence, chosen: int) -> Margins:
    """Margins of the branches of ``graph``, which is ``S(chosen)`` of ``seq``.

    Parameters
    ----------
    graph : BranchGraph
        The answer's graph (not modified).
    mask : (H, W) bool array
        The shape in the graph's frame.
    r2 : (n,) int array
        Squared radius of each graph point.
    seq : PruningSequence
        The sequence ``graph`` is step ``chosen`` of.
    chosen : int
        The answer's step.
    """
    alive = [b for b, br in enumerate(graph.branches) if br.alive]
    removed_at = _removal_steps(graph, seq, chosen, alive)
    if seq.alpha is None or not seq.lbar > 0:
        return Margins({b: None for b in alive}, removed_at)
    lam = seq.objective
    base = float(lam[chosen])
    margin: dict[int, float | None] = {}
    for b in alive:
        j = removed_at[b]
        margin[b] = None if j is None else float(lam[j]) - base
    ends = graph.end_branches()
    if ends:
        nb = len(graph.branches)
        labels = np.zeros(graph.rows.size, np.int64)
        for b in alive:
            labels[graph.branches[b].points] = b + 1
        for j, junc in enumerate(graph.junctions):
            if junc.alive:
                labels[junc.points] = nb + 1 + j
        pts = graph.alive_points()
        cov = Coverage(mask, graph.rows[pts], graph.cols[pts], r2[pts], labels[pts],
                       nb + len(graph.junctions) + 1)
        for b in ends:
            g = graph.copy()
            g.remove_end_branch(b)
            lost = cov.lost + int(cov.exclusive[b + 1])
            margin[b] = objective(lost, seq.area, g.na, g.nd, seq.alpha, seq.lbar) - base
    return Margins(margin, removed_at)


def _removal_steps(graph: BranchGraph, seq: PruningSequence, chosen: int,
                   alive: list[int]) -> dict[int, int | None]:
    """The step at which the sequence, continued from ``graph``, removes each branch."""
    owner = {b: b for b in alive}  # the branch of the running graph that holds b's points
    steps: dict[int, int | None] = {b: None for b in alive}
    rest = seq.removed[chosen:]
    if not rest:
        return steps
    g = graph.copy()
    for i, pick in enumerate(rest, start=chosen + 1):
        merged = g.remove_end_branch(pick)
        for b in alive:
            if steps[b] is None and owner[b] == pick:
                steps[b] = i
        if merged is not None:
            kept, absorbed, _ = merged
            for b in alive:
                if owner[b] == absorbed:
                    owner[b] = kept
    return steps
