"""Tips cut where the trade-off says, on any grid (docs/algorithm.md, "Tips").

After the answer ``Ŝ`` is chosen, each of its free ends is cut back from its endpoint to
the cut ``k`` (the first ``k`` points of the tip dropped) that minimises
``λ = α·AR + LR`` among those that drop a *remnant* only; the smallest ``λ`` wins, ties
to the shorter tip (the larger ``k``). Ends are cut one after another, each on the
skeleton the earlier cuts left, in a fixed order: the longest cut first (as measured on
``Ŝ`` alone), then by the free end's coordinates in the grid's order.

The rule and the order are written once, here (:func:`trim_ends`); what a grid counts
for it, the elements each cut loses, which cuts drop a remnant, and the box each tip's
disks (balls) reach, is its :class:`TipCounts`. A tip is counted again only when an
earlier cut changed what its disks share (a cut's box meets its box) or its own branch;
otherwise its counts stand and only its best cut is chosen again, on the current length
and lost elements.
"""

from __future__ import annotations

import math
from typing import NamedTuple, Protocol

import numpy as np
from numba import njit

from .branch_graph import PointGraph
from .grid import compiled_length, path_length

__all__ = ["Box", "Tip", "TipCounts", "best_cut", "trim_ends"]

#: A box of grid elements, closed: the lowest index along each axis, then the highest.
Box = tuple[int, ...]


class Tip(NamedTuple):
    """One tip's candidate cuts (:meth:`TipCounts.candidates`).

    ``points`` and their ``drop`` indices (cut ``k`` drops the points whose index is
    below ``k``), per cut the elements it loses (``lost``), its steps of each kind
    (``cut``, an ``(m, kinds)`` array) and whether it drops a remnant only
    (``allowed``); the box the tip's disks reach and the elements only they cover.
    """

    points: np.ndarray
    drop: np.ndarray
    lost: np.ndarray
    cut: np.ndarray
    allowed: np.ndarray
    box: Box
    only: int


class TipCounts(Protocol):
    """What a grid counts for the tips' cut: the disk (ball) counts of the skeleton left
    so far, kept up to date as cuts are made."""

    def candidates(self, ends: list[tuple[int, int]]) -> list[Tip]:
        """Each end's tip, counted on the skeleton left so far."""
        ...

    def cut(self, points: np.ndarray, drop: np.ndarray, k: int) -> tuple[list[int], Box]:
        """Make cut ``k`` of a tip: its dropped points' disks taken off the counts;
        returns those points and the box the counts changed in."""
        ...

    def exclusive(self, b: int) -> int:
        """Elements only branch ``b``'s disks cover."""
        ...


@njit(cache=True)
def best_cut(lost0, total, cand_lost, cand_steps, allowed, area, alpha, lbar, weights):
    """``argmin λ`` over the allowed cuts, ties to the larger ``k``; λ with exactly the
    operations of :func:`~skelprune.pruning.bayesian.target` and lengths with those of
    :func:`~.grid.path_length`, so that the choice is bit-identical to the oracles'."""
    best, best_lam = 0, math.inf
    rest = np.empty(total.size, np.int64)
    for k in range(cand_lost.size):
        if not allowed[k]:
            continue
        for i in range(total.size):
            rest[i] = total[i] - cand_steps[k, i]
        length = compiled_length(rest, weights)
        lam = alpha * (lost0 + cand_lost[k]) / area + math.log(length / lbar + 1.0)
        if lam <= best_lam:
            best, best_lam = k, lam
    return best


def _meet(a: Box, b: Box) -> bool:
    d = len(a) // 2
    return all(a[i] <= b[d + i] and b[i] <= a[d + i] for i in range(d))


def trim_ends(
    graph: PointGraph,
    coords: tuple[np.ndarray, ...],
    counts: TipCounts,
    ends: list[tuple[int, int]],
    lost: int,
    area: int,
    alpha: float,
    lbar: float,
) -> tuple[int, list[tuple[int, int, int]], dict[int, int]]:
    """Cut each of ``ends`` (``(branch, end)``, free ends of ``graph``, whose points
    have ``coords``) back to the remnant cut of least ``λ``, changing ``graph`` and
    ``counts``.

    Returns the lost elements of the trimmed skeleton, ``(branch, end, k)`` for every
    end in the order it was cut (``k = 0``: left as it was), and per end branch of the
    trimmed skeleton the elements only its disks cover (for its margin).
    """
    weights = np.ascontiguousarray(graph.weights, np.float64)

    def best(tip: Tip) -> int:
        """The tip's cut of least ``λ`` on the skeleton left so far."""
        steps = np.asarray(graph.total_steps(), np.int64)
        return int(
            best_cut(lost, steps, tip.lost, tip.cut, tip.allowed, area, alpha, lbar, weights)
        )

    # The order: longest cut on Ŝ alone first, then the free end's coordinates.
    keyed: list[tuple[tuple[float, ...], int, int]] = []
    first = {}
    for (b, e), tip in zip(ends, counts.candidates(ends), strict=True):
        p = graph.free_end_point(b, e)
        first[b, e] = tip
        key = (-path_length(tip.cut[best(tip)], weights), *(int(c[p]) for c in coords))
        keyed.append((key, b, e))
    keyed.sort()
    cuts: list[tuple[int, int, int]] = []
    changed: list[Box] = []  # where earlier cuts changed the counts
    cut_branches: set[int] = set()
    # per branch, from its last count: what only its kept points cover, the box, and
    # how many changes that count has seen
    kept: dict[int, tuple[int, Box, int]] = {}
    for _, b, e in keyed:
        tip = first[b, e]
        if b in cut_branches or any(_meet(tip.box, c) for c in changed):
            # an earlier cut changed what this tip's disks share: count again
            (tip,) = counts.candidates([(b, e)])
        # (on the length and lost elements earlier cuts left)
        k = best(tip)
        cuts.append((b, e, k))
        # an element only the kept points cover had all its disks in the tip, one kept
        kept[b] = (tip.only - int(tip.lost[k]), tip.box, len(changed) + (k > 0))
        if k == 0:
            continue
        # Only the dropped points' disks changed the counts: their box, not the whole
        # tip's (whose large disks near the junction reach most of a small shape), so
        # that fewer later tips are counted again.
        gone, dropped_box = counts.cut(tip.points, tip.drop, k)
        changed.append(dropped_box)
        cut_branches.add(b)
        lost += int(tip.lost[k])
        graph.cut_tip(b, e, gone, tuple(int(s) for s in tip.cut[k]))
    exclusive = {}
    for b in graph.end_branches():
        if b in kept and not any(_meet(kept[b][1], c) for c in changed[kept[b][2] :]):
            exclusive[b] = kept[b][0]  # no later cut reached its disks
        else:
            exclusive[b] = counts.exclusive(b)
    return lost, cuts, exclusive
