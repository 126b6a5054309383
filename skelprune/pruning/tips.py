"""Tips cut where the trade-off says: the answer's end branches trimmed point by point.

The greedy pruning removes whole end branches only, so a kept end branch still runs on
to the boundary along whatever digital spur merged into it: a hook at a round end,
length that reconstructs nothing. After the answer ``Ŝ`` is chosen, each of its end
branches (both ends of a single path) is cut back from its endpoint to the cut that
minimises ``λ = α·AR + LR`` along it:

- drop the first ``k`` points of the tip, ``k = 0 … len − 1`` (a branch is never removed
  whole, and a single path keeps two points, so the endpoint count does not change);
- the length falls by the steps between those points, the lost area rises by the pixels
  that only those points' disks covered (exact counts);
- the smallest ``λ`` wins, ties to the shorter tip (the larger ``k``).

Ends are cut one after another, each on the skeleton the earlier cuts left, in a fixed
order: the longest cut first (as measured on ``Ŝ`` alone), then by endpoint (row, col).
``λ`` of the answer can only fall: ``k = 0`` is always a candidate.

The points a cut drops are those of :meth:`~skelprune.graph.BranchGraph.tip`: the branch's
path from the endpoint, each pixel beside the path (a dissolved junction cluster's)
going with the last path point it touches. The naive oracle (``testkit/oracle.py``)
recomputes every candidate's area from scratch and must agree exactly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from ..graph import BranchGraph, step_length
from ..skeleton import Skeleton

__all__ = ["Trim", "trim_tips"]


@dataclass(frozen=True)
class Trim:
    """The trimmed answer and its numbers.

    ``cuts`` lists ``(branch, end, k)`` for every end in the order it was cut (``k = 0``:
    left as it was); ``lost``, ``na`` and ``nd`` are the trimmed skeleton's lost pixels
    and length counts, from which its ``AR``, ``LR`` and ``λ`` follow.
    """

    skeleton: Skeleton
    lost: int
    na: int
    nd: int
    cuts: list[tuple[int, int, int]]
    #: Per end branch of the trimmed skeleton: the pixels only its disks cover (what
    #: removing it whole would lose), for its margin.
    exclusive: dict[int, int]


@njit(cache=True)
def _paint_counts(h, w, rows, cols, r2):
    """How many disks ``|p − s|² < r²`` cover each pixel."""
    c = np.zeros((h, w), np.int32)
    for k in range(rows.size):
        r, q, v = rows[k], cols[k], r2[k]
        rad = int(math.sqrt(v))
        for dy in range(-rad, rad + 1):
            rest = v - dy * dy
            if rest <= 0:
                continue
            dx = int(math.sqrt(rest))
            if dx * dx >= rest:  # strict inside: |dx|² < rest
                dx -= 1
            y = r + dy
            for x in range(q - dx, q + dx + 1):
                c[y, x] += 1
    return c


@njit(cache=True)
def _losses(mask, c, rows, cols, r2, drop, n_drop, scratch, last):
    """Pixels lost when the points with ``drop < k`` go, per ``k`` (index ``k − 1``).

    A pixel is lost once every disk covering it is among the dropped points: all its
    covers are in this list (``scratch`` counts them against ``c``) and the last of them
    (``last``: the largest drop index) is gone. ``scratch`` and ``last`` come in zeroed
    and are left zeroed.
    """
    loss = np.zeros(n_drop + 1, np.int64)
    for pass_ in range(3):
        for k in range(rows.size):
            r, q, v, d = rows[k], cols[k], r2[k], drop[k]
            rad = int(math.sqrt(v))
            for dy in range(-rad, rad + 1):
                rest = v - dy * dy
                if rest <= 0:
                    continue
                dx = int(math.sqrt(rest))
                if dx * dx >= rest:
                    dx -= 1
                y = r + dy
                for x in range(q - dx, q + dx + 1):
                    if pass_ == 0:
                        scratch[y, x] += 1
                        if d + 1 > last[y, x]:
                            last[y, x] = d + 1
                    elif pass_ == 1:
                        if scratch[y, x] == c[y, x] and mask[y, x]:
                            loss[last[y, x] - 1] += 1
                        scratch[y, x] = -1  # counted once
                    else:
                        scratch[y, x] = 0
                        last[y, x] = 0
    return loss


@njit(cache=True)
def _uncover(c, rows, cols, r2):
    """Take the disks of these points off the counts."""
    for k in range(rows.size):
        r, q, v = rows[k], cols[k], r2[k]
        rad = int(math.sqrt(v))
        for dy in range(-rad, rad + 1):
            rest = v - dy * dy
            if rest <= 0:
                continue
            dx = int(math.sqrt(rest))
            if dx * dx >= rest:
                dx -= 1
            y = r + dy
            for x in range(q - dx, q + dx + 1):
                c[y, x] -= 1


class _Tips:
    """The counts and the scratch arrays the cuts share."""

    def __init__(self, sk: Skeleton, graph: BranchGraph) -> None:
        self.sk, self.graph = sk, graph
        idx = graph.alive_points()
        h, w = sk.shape.shape
        self.c = _paint_counts(h, w, sk.rows[idx], sk.cols[idx], sk.r2[idx])
        self.scratch = np.zeros((h, w), np.int32)
        self.last = np.zeros((h, w), np.int64)

    def candidates(self, b: int, e: int) -> tuple[list[int], np.ndarray, np.ndarray, np.ndarray]:
        """The tip's points, their drop indices, and per cut ``k = 0 … len − 1`` of
        the path (``len − 2`` on a single path): pixels lost and (axial, diagonal)
        steps dropped."""
        sk, graph = self.sk, self.graph
        points, drop, steps = graph.tip(b, e)
        n = len(steps) + 1  # path points
        pts = np.asarray(points, np.int64)
        dr = np.asarray(drop, np.int64)
        loss = _losses(
            sk.shape, self.c, sk.rows[pts], sk.cols[pts], sk.r2[pts], dr, n, self.scratch, self.last
        )
        # a single path keeps two points: one would be a single endpoint
        m = n - 1 if graph.branches[b].node[1 - e] is None else n
        lost = np.concatenate(([0], np.cumsum(loss[: m - 1])))
        nd = np.concatenate(([0], np.cumsum(np.asarray(steps[: m - 1], np.int64))))
        na = np.arange(m) - nd
        return points, dr, lost, np.stack([na, nd], axis=1)

    def exclusive(self, b: int) -> int:
        """Pixels only branch ``b``'s disks cover."""
        sk, br = self.sk, self.graph.branches[b]
        pts = np.asarray(br.points, np.int64)
        # every point the same drop index: lost all together
        loss = _losses(
            sk.shape,
            self.c,
            sk.rows[pts],
            sk.cols[pts],
            sk.r2[pts],
            np.zeros(pts.size, np.int64),
            1,
            self.scratch,
            self.last,
        )
        return int(loss[0])


def _best(lost0: int, na0: int, nd0: int, cand_lost, cand_steps, area, alpha, lbar) -> int:
    """``argmin λ`` over the cuts, ties to the larger ``k``; λ as
    :func:`~skelprune.pruning.bayesian.objective` computes it."""
    best, best_lam = 0, math.inf
    for k in range(len(cand_lost)):
        lam = alpha * (lost0 + int(cand_lost[k])) / area + math.log(
            step_length(na0 - int(cand_steps[k, 0]), nd0 - int(cand_steps[k, 1])) / lbar + 1.0
        )
        if lam <= best_lam:
            best, best_lam = k, lam
    return best


def trim_tips(answer: Skeleton, lost: int, alpha: float, lbar: float) -> Trim:
    """Cut every end of ``answer`` back to the point that minimises ``λ`` along it.

    Parameters
    ----------
    answer : Skeleton
        The chosen skeleton ``Ŝ`` (left as it is: the cuts work on a copy).
    lost : int
        ``Λ(D \\ R(Ŝ))``, the pixels ``Ŝ`` misses.
    alpha, lbar : float
        ``α`` and ``ℓ̄`` of the sequence ``Ŝ`` was chosen from.

    Returns
    -------
    Trim

    Examples
    --------
    A disc on a stick: the stick's axis ends in the disc, near its centre, instead of
    turning to the boundary.

    >>> yy, xx = np.mgrid[:40, :80]
    >>> m = ((yy - 20) ** 2 + (xx - 58) ** 2 < 15**2) | ((abs(yy - 20) < 4) & (xx > 3) & (xx < 60))
    >>> sk = Skeleton.medial_axis(np.pad(m, 1))
    >>> norm = sk.normalisation(9.0)
    >>> lost = int((sk.shape & ~sk.reconstruction()).sum())
    >>> t = trim_tips(sk, lost, norm.alpha, norm.lbar)
    >>> t.skeleton.n_endpoints == sk.n_endpoints, t.skeleton.n_points < sk.n_points
    (True, True)
    """
    graph = answer.working_graph()
    area = answer.area
    tips = _Tips(answer, graph)
    ends = graph.free_ends()
    # The order: longest cut on Ŝ alone first, then endpoint (row, col).
    keyed = []
    for b, e in ends:
        _, _, cl, cs = tips.candidates(b, e)
        k = _best(lost, graph.na, graph.nd, cl, cs, area, alpha, lbar)
        p = graph.free_end_point(b, e)
        keyed.append(
            (
                -step_length(int(cs[k, 0]), int(cs[k, 1])),
                int(graph.rows[p]),
                int(graph.cols[p]),
                b,
                e,
            )
        )
    keyed.sort()
    cuts: list[tuple[int, int, int]] = []
    for *_, b, e in keyed:
        points, drop, cl, cs = tips.candidates(b, e)
        k = _best(lost, graph.na, graph.nd, cl, cs, area, alpha, lbar)
        cuts.append((b, e, k))
        if k == 0:
            continue
        gone = np.asarray(
            [p for p, d in zip(points, drop.tolist(), strict=True) if d < k], np.int64
        )
        _uncover(tips.c, answer.rows[gone], answer.cols[gone], answer.r2[gone])
        lost += int(cl[k])
        graph.cut_tip(b, e, gone.tolist(), int(cs[k, 0]), int(cs[k, 1]))
    exclusive = {b: tips.exclusive(b) for b in graph.end_branches()}
    return Trim(answer.with_graph(graph), lost, graph.na, graph.nd, cuts, exclusive)
