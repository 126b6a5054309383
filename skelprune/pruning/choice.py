"""Which skeleton of the sequence is the answer: the choice rules, in one place.

- ``argmin`` (:func:`choose_step`): the paper's answer, the smallest ``λ``;
- ``noise-floor`` (:func:`floor_step`): the same with the area term over the pixels
  deeper than the boundary's one-pixel rim (below);
- ``min_margin`` (:func:`chosen_step`): then the end branches kept by less than the
  margin dropped, one step at a time.

The noise floor. The paper's answer is ``argmin λ`` over the greedy sequence, with
``λ = α·AR + LR`` and ``AR`` counting every pixel of ``D`` the skeleton misses. Pixels on
the boundary are the ones a boundary moved by one pixel adds or takes: a branch that only
reconstructs them reconstructs the noise, and moving the boundary by a pixel moves ``λ``
by as much as such a branch is worth. Choosing with the area term counted only over the
pixels more than one pixel inside the boundary (``D`` less its one-pixel rim) puts the
choice above that noise floor, with no parameter: the same sequence, the same ``λ``
reported, only the step chosen may come later.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ..grid._rowcover import cover_counts, uncover_count
from ..grid.medial_axis import squared_distance
from .bayesian import PruningSequence

if TYPE_CHECKING:
    from ..skeleton import Skeleton

__all__ = ["RIM", "choose_step", "chosen_step", "floor_lost", "floor_step"]

#: Squared distance to the background up to which a pixel is on the rim: the pixels a
#: one-pixel move of the boundary adds or takes (4- and 8-adjacent to the background).
RIM = 2


def choose_step(objectives: np.ndarray) -> int:
    """``argmin λ`` over the sequence; ties go to the later, simpler skeleton."""
    best = 0
    for i, v in enumerate(objectives):
        if v <= objectives[best]:
            best = i
    return best


def chosen_step(seq: PruningSequence[Any], choice: str, min_margin: float | None) -> int:
    """The answer's step: by ``choice`` (``"argmin"`` or ``"noise-floor"``), then moved on
    while the next removal raises ``λ`` by less than ``min_margin`` (the cheapest end
    branch is the sequence's next removal, and its margin that step's rise of ``λ``)."""
    chosen = choose_step(seq.objective) if choice == "argmin" else floor_step(seq)
    if min_margin and min_margin > 0 and seq.alpha is not None:
        lam = seq.objective
        while chosen < len(seq.removed) and lam[chosen + 1] - lam[chosen] < min_margin:
            chosen += 1
    return chosen


def floor_lost(seq: PruningSequence[Skeleton]) -> np.ndarray:
    """Per skeleton ``S(i)`` of the sequence: the pixels deeper than the rim it misses."""
    start = seq.start
    shape = start.mask
    deep = squared_distance(shape) > RIM
    idx = start.points()
    h, w = shape.shape
    c = cover_counts(h, w, start.rows[idx], start.cols[idx], start.r2[idx])
    lost = [int((deep & (c == 0)).sum())]
    for i in range(len(seq.log)):
        pts = seq.log.points(i)
        lost.append(
            lost[-1] + uncover_count(c, deep, start.rows[pts], start.cols[pts], start.r2[pts])
        )
    return np.asarray(lost)


def floor_step(seq: PruningSequence[Skeleton]) -> int:
    """``argmin`` over the sequence of ``λ`` with the area term over the deep pixels only
    (ties to the later skeleton); the plain argmin where ``α`` is undefined."""
    if seq.alpha is None:
        return choose_step(seq.objective)
    lam = seq.alpha * floor_lost(seq) / seq.area + seq.ss
    return choose_step(lam)
