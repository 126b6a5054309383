"""The answer chosen above the trade-off's noise floor.

The paper's answer is ``argmin λ`` over the greedy sequence, with ``λ = α·AR + LR`` and
``AR`` counting every pixel of ``D`` the skeleton misses. Pixels on the boundary are the
ones a boundary moved by one pixel adds or takes: a branch that only reconstructs them
reconstructs the noise, and moving the boundary by a pixel moves ``λ`` by as much as such
a branch is worth. Choosing with the area term counted only over the pixels more than one
pixel inside the boundary (``D`` less its one-pixel rim) puts the choice above that
noise floor, with no parameter: the same sequence, the same ``λ`` reported, only the
step chosen may come later.
"""

from __future__ import annotations

import numpy as np

from ..grid.medial_axis import squared_distance
from ._rowcover import cover_counts, uncover_count
from .bayesian import PruningSequence, choose_step

__all__ = ["floor_lost", "floor_step"]

#: Squared distance to the background up to which a pixel is on the rim: the pixels a
#: one-pixel move of the boundary adds or takes (4- and 8-adjacent to the background).
RIM = 2


def floor_lost(seq: PruningSequence) -> np.ndarray:
    """Per skeleton ``S(i)`` of the sequence: the pixels deeper than the rim it misses."""
    start = seq.start
    shape = start.mask
    deep = squared_distance(shape) > RIM
    idx = start.points()
    h, w = shape.shape
    c = cover_counts(h, w, start.rows[idx], start.cols[idx], start.r2[idx])
    lost = [int((deep & (c == 0)).sum())]
    graph = start.working_graph()
    for b in seq.removed:
        pts = np.asarray(graph.branches[b].points, np.int64)
        graph.remove_end_branch(b)
        lost.append(
            lost[-1] + uncover_count(c, deep, start.rows[pts], start.cols[pts], start.r2[pts])
        )
    return np.asarray(lost)


def floor_step(seq: PruningSequence) -> int:
    """``argmin`` over the sequence of ``λ`` with the area term over the deep pixels only
    (ties to the later skeleton); the plain argmin where ``α`` is undefined."""
    if seq.alpha is None:
        return choose_step(seq.objective)
    lam = seq.alpha * floor_lost(seq) / seq.area + seq.ss
    return choose_step(lam)
