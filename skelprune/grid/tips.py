"""Tips cut where the trade-off says: the answer's end branches trimmed point by point.

The greedy pruning removes whole end branches only, so a kept end branch still runs on
to the boundary along whatever digital spur merged into it: a hook at a round end, a
staircase into a corner, length that reconstructs nothing. After the answer ``Ŝ`` is
chosen, each of its end branches (both ends of a single path) is cut back from its
endpoint to the cut that minimises ``λ = α·AR + LR`` among those that drop a *remnant*
only:

- drop the first ``k`` points of the tip, ``k = 0 … len − 1`` (a branch is never removed
  whole, and a single path keeps two points, so the endpoint count does not change);
- the length falls by the steps between those points, the lost area rises by the pixels
  that only those points' disks covered (exact counts);
- a remnant: every dropped point lies within one pixel of the new end's disk, and the
  cut loses at most one pixel per point it drops (:func:`remnant_cuts`); a limb is more
  than that, so the trade-off can never cut one off;
- the smallest ``λ`` wins, ties to the shorter tip (the larger ``k``).

Ends are cut one after another, each on the skeleton the earlier cuts left, in a fixed
order: the longest cut first (as measured on ``Ŝ`` alone), then by endpoint (row, col).
``λ`` of the answer can only fall: ``k = 0`` is always a candidate.

The points a cut drops are those of :meth:`~skelprune.grid.graph.BranchGraph.tip`: the branch's
path from the endpoint, each pixel beside the path (a dissolved junction cluster's)
going with the last path point it touches. The naive oracle (``testkit/oracle.py``)
recomputes every candidate's area from scratch, applies the remnant rule again, and must
agree exactly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from ..pruning.tip_cuts import Box, Tip, trim_ends
from ..skeleton import Skeleton
from ._rowcover import cover_counts, cut_counts, exclusive_losses, uncover
from .graph import BranchGraph

__all__ = ["RULES", "Trim", "trim_tips"]

#: The remnant rules: which cuts a tip may take (docs/algorithm.md, "Tips"). ``"both"``
#: (the default): the dropped points lie within one pixel of the new end's disk
#: (``"reach"``) and the cut loses at most one pixel per point it drops (``"area"``);
#: ``"disk"``: inside that disk; ``"none"``: any cut (the trade-off alone, which cuts
#: whole limbs). Not an option of the library: ``python -m benchmarks limbs`` compares
#: them by setting :data:`RULE`.
RULES = ("both", "reach", "disk", "area", "none")
RULE = "both"


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

    @property
    def steps(self) -> tuple[int, int]:
        """The trimmed skeleton's steps of each kind (the grid interface's counts)."""
        return self.na, self.nd


class _Tips:
    """The disk counts the cuts share (``c``: per pixel, how many disks of the skeleton
    left so far cover it): the pixel grid's :class:`~skelprune.pruning.tip_cuts.TipCounts`."""

    def __init__(self, sk: Skeleton, graph: BranchGraph) -> None:
        self.sk, self.graph = sk, graph
        idx = graph.alive_points()
        h, w = sk.mask.shape
        self.c = cover_counts(h, w, sk.rows[idx], sk.cols[idx], sk.r2[idx])

    def candidates(self, ends: list[tuple[int, int]]) -> list[Tip]:
        """Each tip's points, their drop indices, per cut ``k = 0 … len − 1`` of the path
        (``len − 2`` on a single path) the pixels lost and the (axial, diagonal) steps
        dropped, whether it cuts a remnant only (:data:`RULE`), the box the tip's disks
        can reach and the pixels only they cover."""
        sk, graph = self.sk, self.graph
        rule = RULES.index(RULE)
        out = []
        for b, e in ends:
            points, drop, steps = graph.tip(b, e)
            # a single path keeps two points: one would be a single endpoint
            m = len(steps) + (0 if graph.branches[b].node[1 - e] is None else 1)
            pts = np.asarray(points, np.int64)
            dr = np.asarray(drop, np.int64)
            cl, cs, box, only = cut_counts(
                sk.mask, self.c, sk.rows, sk.cols, sk.r2, pts, dr, np.asarray(steps, np.int64), m
            )
            allowed = remnant_cuts(sk.rows, sk.cols, sk.r2, pts, dr, cl, rule)
            b0, b1, b2, b3 = box.tolist()
            out.append(Tip(pts, dr, cl, cs, allowed, (b0, b1, b2, b3), int(only)))
        return out

    def cut(self, points: np.ndarray, drop: np.ndarray, k: int) -> tuple[list[int], Box]:
        """Cut ``k`` of a tip: its dropped points' disks taken off the counts ``c``;
        returns those points and the box (top, left, bottom, right) their disks can
        reach, as :func:`~skelprune.grid._rowcover.cut_counts` bounds a tip's."""
        sk = self.sk
        gone, box = _cut_kernel(self.c, sk.rows, sk.cols, sk.r2, points, drop, k)
        b = box.tolist()
        return gone.tolist(), (b[0], b[1], b[2], b[3])

    def exclusive(self, b: int) -> int:
        """Pixels only branch ``b``'s disks cover."""
        sk, br = self.sk, self.graph.branches[b]
        pts = np.asarray(br.points, np.int64)
        # every point the same drop index: lost all together
        loss = exclusive_losses(
            sk.mask,
            self.c,
            sk.rows[pts],
            sk.cols[pts],
            sk.r2[pts],
            np.zeros(pts.size, np.int64),
            1,
        )
        return int(loss[0])


@njit(cache=True)
def remnant_cuts(rows, cols, r2, pts, drop, lost, rule):
    """Per cut ``k`` of a tip (its points ``pts`` and their ``drop`` indices, the path's
    ``k``-th point from the end being ``pts[k]``; ``lost[k]`` its lost pixels): whether it
    drops a remnant only, under rule ``RULES[rule]`` (docs/algorithm.md, "Tips"):

    - *reach*: every dropped point ``p`` lies within one pixel of the disk of the new
      end ``s = pts[k]``: ``|p − s| < r(s) + 1``;
    - *area*: the cut loses at most one pixel per point of the path it drops:
      ``lost[k] ≤ k``;
    - *both* (the default): both; *disk*: ``|p − s| < r(s)``; *none*: any cut.
    """
    m = lost.size
    ok = np.ones(m, np.bool_)
    if rule == 4:
        return ok
    for k in range(1, m):
        if rule in (0, 3) and lost[k] > k:
            ok[k] = False
            continue
        if rule == 3:
            continue
        s = pts[k]
        for j in range(pts.size):
            if drop[j] < k:
                dy, dx = rows[pts[j]] - rows[s], cols[pts[j]] - cols[s]
                d2 = dy * dy + dx * dx
                if rule == 2:
                    inside = d2 < r2[s]
                else:
                    # |p − s| < r + 1 in integers (d ≥ 1): d − 1 < r, d² + 1 − r² < 2d
                    a = d2 + 1 - r2[s]
                    inside = a < 0 or a * a < 4 * d2
                if not inside:
                    ok[k] = False
                    break
    return ok


@njit(cache=True)
def _cut_kernel(c, rows, cols, r2, points, drop, k):
    """:meth:`_Tips.cut` in one compiled call."""
    n = 0
    for j in range(points.size):
        if drop[j] < k:
            n += 1
    gone = np.empty(n, np.int64)
    n = 0
    for j in range(points.size):
        if drop[j] < k:
            gone[n] = points[j]
            n += 1
    gr, gc, g2 = rows[gone], cols[gone], r2[gone]
    uncover(c, gr, gc, g2)
    box = np.empty(4, np.int64)
    box[0] = box[1] = np.iinfo(np.int64).max
    box[2] = box[3] = np.iinfo(np.int64).min
    for j in range(n):
        rad = int(math.sqrt(g2[j])) + 1
        box[0] = min(box[0], gr[j] - rad)
        box[1] = min(box[1], gc[j] - rad)
        box[2] = max(box[2], gr[j] + rad)
        box[3] = max(box[3], gc[j] + rad)
    return gone, box


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
    >>> lost = int((sk.mask & ~sk.reconstruction()).sum())
    >>> t = trim_tips(sk, lost, norm.alpha, norm.lbar)
    >>> t.skeleton.n_endpoints == sk.n_endpoints, t.skeleton.n_points < sk.n_points
    (True, True)
    """
    graph = answer.working_graph()
    tips = _Tips(answer, graph)
    # an end where the shape runs off the image is no tip: never cut
    free = graph.free_ends()
    off = answer.open_ends([graph.free_end_point(b, e) for b, e in free])
    ends = [(b, e) for b, e in free if graph.free_end_point(b, e) not in off]
    # the order: longest cut on Ŝ alone first, then endpoint (row, col)
    lost, cuts, exclusive = trim_ends(
        graph, graph.coords, tips, ends, lost, answer.area, alpha, lbar
    )
    na, nd = graph.total_steps()
    return Trim(answer.with_graph(graph), lost, na, nd, cuts, exclusive)
