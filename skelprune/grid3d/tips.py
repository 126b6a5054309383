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
  end's ``(z, y, x)`` (the rule and the order of every grid:
  :func:`skelprune.pruning.tip_cuts.trim_ends`; here, the counts).

The naive oracle (``testkit/volume_oracle.py``) repaints every candidate from scratch.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..pruning.branch_graph import Steps
from ..pruning.tip_cuts import Box, Tip, trim_ends
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
    """The ball counts of the skeleton left so far (``c``), and each tip's candidate
    cuts: the volume grid's :class:`~skelprune.pruning.tip_cuts.TipCounts`."""

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

    def _reach(self, pts: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        """Per axis, the lowest and highest voxel the balls of ``pts`` reach (unclipped)."""
        sk = self.sk
        root = np.sqrt(sk.r2[pts])
        out = []
        for coord, s in zip((sk.z, sk.y, sk.x), sk.spacing, strict=True):
            reach = (root / s).astype(np.int64) + 1
            out.append((coord[pts] - reach, coord[pts] + reach))
        return out

    def candidates(self, ends: list[tuple[int, int]]) -> list[Tip]:
        """Each tip's points and their drop indices; per cut ``k`` its lost voxels, its
        dropped steps and whether it drops a remnant only; the box its balls reach and
        the voxels only they cover."""
        return [self._candidate(b, e) for b, e in ends]

    def _candidate(self, b: int, e: int) -> Tip:
        sk, g = self.sk, self.graph
        points, drop, kinds = g.tip(b, e)
        m = len(kinds) + (0 if g.branches[b].node[1 - e] is None else 1)
        pts = np.asarray(points, np.int64)
        # the box the tip's balls reach
        lo, hi = [], []
        for (low, high), n in zip(self._reach(pts), self.c.shape, strict=True):
            lo.append(max(int(low.min()), 0))
            hi.append(min(int(high.max()) + 1, n))
        box = tuple(slice(a, z) for a, z in zip(lo, hi, strict=True))
        c = self.c[box]
        inside = sk.volume[box] & (c > 0)
        spacing = np.array(sk.spacing)
        mine = np.zeros(c.shape, np.int32)
        _paint(
            mine, sk.z[pts] - lo[0], sk.y[pts] - lo[1], sk.x[pts] - lo[2], sk.r2[pts], spacing, 1
        )
        only = int(np.count_nonzero(inside & (mine == c)))
        t = np.zeros(c.shape, np.int32)
        order = np.argsort(np.asarray(drop), kind="stable")
        lost = np.zeros(m, np.int64)
        steps = np.zeros((m, 7), np.int64)
        j = 0
        for k in range(1, m):
            while j < len(order) and drop[order[j]] < k:
                one = pts[order[j] : order[j] + 1]
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
            lost[k] = np.count_nonzero(inside & (t == c))
            steps[k] = steps[k - 1]
            steps[k, kinds[k - 1]] += 1
        allowed = np.ones(m, np.bool_)
        for k in range(1, m):
            s = points[k]
            reach = math.sqrt(float(sk.r2[s])) + self.h
            allowed[k] = lost[k] <= k and not any(
                math.sqrt(self._d2(p, s)) >= reach
                for p, d in zip(points, drop, strict=True)
                if d < k
            )
        # the box as the driver compares boxes: closed, lowest then highest voxel
        closed = (*lo, *(z - 1 for z in hi))
        return Tip(pts, np.asarray(drop, np.int64), lost, steps, allowed, closed, only)

    def cut(self, points: np.ndarray, drop: np.ndarray, k: int) -> tuple[list[int], Box]:
        """Cut ``k`` of a tip: its dropped points' balls taken off the counts; returns
        those points and the box their balls reach."""
        sk = self.sk
        gone = points[drop < k]
        _paint(self.c, sk.z[gone], sk.y[gone], sk.x[gone], sk.r2[gone], np.array(sk.spacing), -1)
        reach = self._reach(gone)
        box = (*(int(low.min()) for low, _ in reach), *(int(high.max()) for _, high in reach))
        return gone.tolist(), box

    def exclusive(self, b: int) -> int:
        """Voxels only branch ``b``'s balls cover."""
        sk = self.sk
        pts = np.asarray(self.graph.branches[b].points, np.int64)
        own = ball_counts(sk.volume.shape, sk.z[pts], sk.y[pts], sk.x[pts], sk.r2[pts], sk.spacing)
        return int(np.count_nonzero(sk.volume & (own > 0) & (own == self.c)))


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
    tips = _Tips(answer, graph)
    lost, cuts, exclusive = trim_ends(
        graph, graph.coords, tips, graph.free_ends(), lost, answer.area, alpha, lbar
    )
    return VolumeTrim(answer.with_graph(graph), lost, graph.total_steps(), cuts, exclusive)
