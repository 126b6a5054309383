"""Which skeleton of the sequence is the answer: the choice rules, in one place.

- ``noise-floor`` (:func:`floor_step`, the default): the smallest ``λ`` with the area
  term counted beyond the boundary's own noise (below);
- ``argmin`` (:func:`choose_step`): the paper's answer, the smallest ``λ``;
- ``min_margin`` (:func:`chosen_step`): then the end branches kept by less than the
  margin dropped, one step at a time.

The noise floor. The paper's answer is ``argmin λ`` over the greedy sequence, with
``λ = α·AR + LR`` and ``AR`` counting every element of ``D`` the skeleton misses. A spur
that a bump of the boundary made reconstructs only that bump: elements within the bump's
height of what the rest of the skeleton covers. A real branch, however thin, reaches
beyond the rest by its whole length. So the choice counts an element as lost only when
no disk (ball), grown by the boundary's **noise depth**, covers it: a spur no higher than
the noise costs nothing and goes; a branch that reaches further stays, whatever its
width or length. The noise depth is measured on the shape itself: one grid step (the
digitisation) on a clean boundary, more where the boundary is rough
(:func:`noise_depth`). One rule for both grids, written here; the grids only count
(``lost_along``). The sequence and the ``λ`` reported are the paper's; only the step
chosen differs.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .bayesian import PruningSequence

__all__ = [
    "DIGITAL_DEPTH",
    "ROUGHNESS_DEPTH",
    "ROUGHNESS_FLOOR",
    "choose_step",
    "chosen_step",
    "floor_lost",
    "floor_objective",
    "floor_step",
    "noise_depth",
]

#: The noise depth of a clean digital boundary, in grid steps: half a pixel's diagonal,
#: the farthest a pixel centre lies from the outline it digitises.
DIGITAL_DEPTH = 0.5 * 2.0**0.5
#: Boundary roughness (:meth:`GridAxis.boundary_roughness`) up to which a boundary is
#: clean: a clean silhouette measures 0.01-0.14 ...
ROUGHNESS_FLOOR = 0.15
#: ... and each unit of roughness above it deepens the noise by this many grid steps
#: (boundary noise of one pixel measures about 0.4: a depth of about 2.2 px).
ROUGHNESS_DEPTH = 6.0


def noise_depth(roughness: float, grid_step: float) -> float:
    """How deep the boundary's noise reaches, in the unit of the radii.

    >>> round(noise_depth(0.05, 1.0), 3), round(noise_depth(0.4, 1.0), 3)
    (0.707, 2.207)
    """
    excess = max(0.0, roughness - ROUGHNESS_FLOOR)
    return grid_step * (DIGITAL_DEPTH + ROUGHNESS_DEPTH * excess)


def choose_step(objectives: np.ndarray) -> int:
    """``argmin λ`` over the sequence; ties go to the later, simpler skeleton."""
    best = 0
    for i, v in enumerate(objectives):
        if v <= objectives[best]:
            best = i
    return best


def chosen_step(seq: PruningSequence[Any], choice: str, min_margin: float | None) -> int:
    """The answer's step: the least of the choice's ``λ`` (``"argmin"``: the paper's;
    ``"noise-floor"``: :func:`floor_objective`), then moved on while the next removal
    raises that ``λ`` by less than ``min_margin`` (the cheapest end branch is the
    sequence's next removal, and its margin that step's rise of ``λ``)."""
    lam = seq.objective if choice == "argmin" or seq.alpha is None else floor_objective(seq)
    chosen = choose_step(lam)
    if min_margin and min_margin > 0 and seq.alpha is not None:
        while chosen < len(seq.removed) and lam[chosen + 1] - lam[chosen] < min_margin:
            chosen += 1
    return chosen


def floor_lost(seq: PruningSequence[Any]) -> np.ndarray:
    """Per skeleton ``S(i)`` of the sequence: the elements of ``D`` its disks (balls),
    grown by the shape's noise depth, miss."""
    start = seq.start
    depth = noise_depth(start.boundary_roughness(), start.grid_step)
    return start.lost_along(depth, [seq.log.points(i) for i in range(len(seq.log))])


def floor_objective(seq: PruningSequence[Any]) -> np.ndarray:
    """``λ`` of every skeleton of the sequence with the area term beyond the noise
    depth (``α`` defined)."""
    assert seq.alpha is not None
    return seq.alpha * floor_lost(seq) / seq.area + seq.ss


def floor_step(seq: PruningSequence[Any]) -> int:
    """``argmin`` over the sequence of ``λ`` with the area term beyond the noise depth
    (ties to the later skeleton); the plain argmin where ``α`` is undefined."""
    if seq.alpha is None:
        return choose_step(seq.objective)
    return choose_step(floor_objective(seq))
