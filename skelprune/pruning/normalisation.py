"""The sequence's normalisation on any grid: seed, ``ℓ̄`` and ``α`` (docs/algorithm.md,
"Length term and normalisation")."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .branch_graph import PointGraph
from .grid import path_length

__all__ = ["Normalisation", "normalisation"]


@dataclass(frozen=True)
class Normalisation:
    """Seed point, mean end-path length ``ℓ̄`` and ``α`` of a medial axis."""

    seed: int
    lbar: float
    alpha: float | None


def normalisation(
    graph: PointGraph,
    coords: tuple[np.ndarray, ...],
    r2: np.ndarray,
    path_lengths: Callable[[int], np.ndarray],
    beta: float,
) -> Normalisation:
    """Seed ``o`` (largest radius; ties: smallest ``coords``, in their order), ``ℓ̄`` and
    ``α = β·log(L/ℓ̄)``.

    The end paths run to the endpoints of the end branches; a single path has none, and
    its end paths run to its two ends (so that its tips can be cut by the trade-off).
    ``path_lengths(seed)`` gives the grid's shortest path lengths along the skeleton from
    the seed to every point. ``α`` is ``None`` where it is undefined: a single point, a
    cycle, or ``ℓ̄ = 0``.
    """
    seed = int(np.lexsort((*coords[::-1], -r2))[0])
    ends = sorted({graph.endpoint(b) for b in range(len(graph.branches)) if graph.is_end_branch(b)})
    if not ends:
        ends = sorted({graph.free_end_point(b, e) for b, e in graph.free_ends()})
    if not ends:
        return Normalisation(seed, 0.0, None)
    dist = path_lengths(seed)
    lbar = float(np.mean(dist[ends]))
    length = path_length(graph.total_steps(), graph.weights)
    if not lbar > 0 or not length > 0:
        return Normalisation(seed, lbar, None)
    return Normalisation(seed, lbar, beta * math.log(length / lbar))
