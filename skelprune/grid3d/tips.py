"""Tips cut where the trade-off says, on the volume grid (docs/volumes.md, "Tips").

The image grid's rule (docs/algorithm.md, "Tips") with balls for disks: after the answer
``Ŝ`` is chosen, each free end is cut back to the cut of least ``λ`` among those that
drop a *remnant* only:

- cut ``k`` drops the first ``k`` points of the path from the free end (``k = 0 … len − 1``;
  a single path keeps two points); voxels beside the path go with the last path point
  they touch; the length falls by the dropped steps, the lost volume rises by exactly the
  voxels only the dropped points' balls covered (``lost(k)``);
- a remnant: every dropped point ``p`` lies within one voxel (``h``, the finest voxel
  side) of the new end's ball, ``|p − s| < r(s) + h``, and ``lost(k) ≤ k``;
- the smallest ``λ`` wins, ties to the shorter tip; ends are cut one after another, each
  on what the earlier cuts left, the longest cut on ``Ŝ`` alone first, then by the free
  end's ``(z, y, x)``.

The naive oracle (``testkit/volume_oracle.py``) repaints every candidate from scratch.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..pruning.branch_graph import Steps, add_steps
from ..pruning.grid import path_length
from .balls import _paint, ball_counts
from .graph import VolumeBranchGraph

if TYPE_CHECKING:
    from .skeleton import VolumeSkeleton

__all__ = ["VolumeTrim", "trim_volume_tips"]


@dataclass(frozen=True)
class VolumeTrim:
    """The trimmed answer: its skeleton, lost voxels and steps, the cuts ``(branch, end,
    k)`` in the order made, and per end branch the voxels only its balls cover."""

    skeleton: VolumeSkeleton
    lost: int
    steps: Steps
    cuts: list[tuple[int, int, int]]
    exclusive: dict[int, int]


class _Tips:
    """The ball counts of the skeleton left so far, and each tip's candidate cuts."""

    def __init__(self, sk: VolumeSkeleton, graph: VolumeBranchGraph) -> None:
        self.sk, self.graph = sk, graph
        alive = graph.alive_points()
        self.c = ball_counts(
            sk.volume.shape, sk.z[alive], sk.y[alive], sk.x[alive], sk.r2[alive], sk.spacing
        )
        self.h = min(sk.spacing)

    def _d2(self, p: int, s: int) -> float:
        sk = self.sk
        a = float(sk.z[p] - sk.z[s]) * sk.spacing[0]
        b = float(sk.y[p] - sk.y[s]) * sk.spacing[1]
        c = float(sk.x[p] - sk.x[s]) * sk.spacing[2]
        return a * a + b * b + c * c

    def candidates(self, b: int, e: int) -> tuple[list[int], list[int], list[int], list[Steps]]:
        """The tip's points and their drop indices; per cut ``k`` its lost voxels and
        dropped steps, for the cuts that drop a remnant only (others: ``lost = -1``)."""
        sk, g = self.sk, self.graph
        points, drop, kinds = g.tip(b, e)
        m = len(kinds) + (0 if g.branches[b].node[1 - e] is None else 1)
        pts = np.asarray(points, np.int64)
        # the box the tip's balls reach
        lo, hi = [], []
        root = np.sqrt(sk.r2[pts])
        for coord, s, n in zip((sk.z, sk.y, sk.x), sk.spacing, self.c.shape, strict=True):
            reach = (root / s).astype(np.int64) + 1
            lo.append(max(int((coord[pts] - reach).min()), 0))
            hi.append(min(int((coord[pts] + reach).max()) + 1, n))
        box = tuple(slice(a, z) for a, z in zip(lo, hi, strict=True))
        c = self.c[box]
        inside = sk.volume[box] & (c > 0)
        t = np.zeros(c.shape, np.int32)
        spacing = np.array(sk.spacing)
        order = np.argsort(np.asarray(drop), kind="stable")
        lost = [0]
        steps: list[Steps] = [(0, 0, 0, 0, 0, 0, 0)]
        j = 0
        for k in range(1, m):
            while j < len(order) and drop[order[j]] < k:
                p = int(pts[order[j]])
                one = np.array([p])
                _paint(
                    t,
                    sk.z[one] - lo[0],
                    sk.y[one] - lo[1],
                    sk.x[one] - lo[2],
                    sk.r2[one],
                    spacing,
                    1,
                )
                j += 1
            lost.append(int(np.count_nonzero(inside & (t == c))))
            step = [0] * 7
            step[kinds[k - 1]] = 1
            steps.append(add_steps(steps[-1], tuple(step)))  # type: ignore[arg-type]
        for k in range(1, m):
            s = points[k]
            reach = math.sqrt(float(sk.r2[s])) + self.h
            if lost[k] > k or any(
                math.sqrt(self._d2(p, s)) >= reach
                for p, d in zip(points, drop, strict=True)
                if d < k
            ):
                lost[k] = -1
        return points, drop, lost, steps

    def exclusive(self, b: int) -> int:
        """Voxels only branch ``b``'s balls cover."""
        sk = self.sk
        pts = np.asarray(self.graph.branches[b].points, np.int64)
        own = ball_counts(sk.volume.shape, sk.z[pts], sk.y[pts], sk.x[pts], sk.r2[pts], sk.spacing)
        return int(np.count_nonzero(sk.volume & (own > 0) & (own == self.c)))


def _best(
    lost0: int,
    total: Steps,
    lost: list[int],
    steps: list[Steps],
    area: int,
    alpha: float,
    lbar: float,
    weights: np.ndarray,
) -> int:
    best, best_lam = 0, math.inf
    for k, (lo, st) in enumerate(zip(lost, steps, strict=True)):
        if lo < 0:
            continue
        length = path_length(add_steps(total, st, -1), weights)
        lam = alpha * (lost0 + lo) / area + math.log(length / lbar + 1.0)
        if lam <= best_lam:
            best, best_lam = k, lam
    return best


def trim_volume_tips(answer: VolumeSkeleton, lost: int, alpha: float, lbar: float) -> VolumeTrim:
    """Cut every free end of ``answer`` back to the remnant cut of least ``λ``.

    Parameters
    ----------
    answer : VolumeSkeleton
        The chosen skeleton (left as it is: the cuts work on a copy of its graph).
    lost : int
        Voxels the answer's balls miss.
    alpha, lbar : float
        ``α`` and ``ℓ̄`` of the sequence it was chosen from.
    """
    graph = answer.working_graph()
    weights = answer.step_weights
    tips = _Tips(answer, graph)
    keyed = []
    for b, e in graph.free_ends():
        _, _, cl, cs = tips.candidates(b, e)
        k = _best(lost, graph.total_steps(), cl, cs, answer.area, alpha, lbar, weights)
        p = graph.free_end_point(b, e)
        key = (-path_length(cs[k], weights), int(answer.z[p]), int(answer.y[p]), int(answer.x[p]))
        keyed.append((*key, b, e))
    keyed.sort()
    cuts = []
    for *_, b, e in keyed:
        points, drop, cl, cs = tips.candidates(b, e)
        k = _best(lost, graph.total_steps(), cl, cs, answer.area, alpha, lbar, weights)
        cuts.append((b, e, k))
        if k == 0:
            continue
        gone = np.asarray([p for p, d in zip(points, drop, strict=True) if d < k], np.int64)
        _paint(
            tips.c,
            answer.z[gone],
            answer.y[gone],
            answer.x[gone],
            answer.r2[gone],
            np.array(answer.spacing),
            -1,
        )
        lost += cl[k]
        graph.cut_tip(b, e, gone.tolist(), cs[k])
    exclusive = {b: tips.exclusive(b) for b in graph.end_branches()}
    return VolumeTrim(answer.with_graph(graph), lost, graph.total_steps(), cuts, exclusive)
