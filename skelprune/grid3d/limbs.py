"""Limbs the greedy pruning never removes, on the volume grid (docs/volumes.md, "Limbs").

The rule of the image grid (docs/algorithm.md, "Limbs") with balls for disks: an end
branch is a **limb** when at least ``2·r / h`` of its voxels (``h`` the finest voxel side,
``r`` the largest ball radius among them) have their whole ball ``|p − s|² < r2(s)``
covered by that branch alone, counting only voxels deeper than the boundary's one-voxel
rim (``r2(s)`` above the squared length of the longest step between 26-neighbours,
``dz² + dy² + dx²``: the image grid's ``r² > 2``). No constant is fitted: ``2·r`` is the
limb's own width, ``h`` and the rim the grid's resolution.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..pruning.limb_memory import LimbMemory
from .balls import _paint, ball_counts, row_half_width
from .distance import squared_distance
from .graph import VolumeBranchGraph

__all__ = ["VolumeLimbs", "limb_rule"]


def limb_rule(whole_r2: list[float], spacing: tuple[float, float, float]) -> bool:
    """Whether the squared radii of a branch's whole-ball voxels deeper than the rim make
    it a limb: at least ``2·r / h`` of them."""
    return bool(whole_r2) and len(whole_r2) * min(spacing) >= 2.0 * math.sqrt(max(whole_r2))


def rim(spacing: tuple[float, float, float]) -> float:
    """Squared radius up to which a ball lies in the boundary's one-voxel rim."""
    dz, dy, dx = spacing
    return dz * dz + dy * dy + dx * dx


class VolumeLimbs(LimbMemory):
    """The ball counts of the sequence's current skeleton and the limbs found so far
    (the volume grid's :class:`~skelprune.pruning.grid.LimbTest`).

    Parameters
    ----------
    graph : VolumeBranchGraph
        The sequence's working graph (read, never changed here).
    volume : (Z, Y, X) bool array
    z, y, x, r2 : arrays
        Every skeleton voxel and its squared radius.
    spacing : (dz, dy, dx)
    """

    def __init__(
        self,
        graph: VolumeBranchGraph,
        volume: np.ndarray,
        z: np.ndarray,
        y: np.ndarray,
        x: np.ndarray,
        r2: np.ndarray,
        spacing: tuple[float, float, float],
    ) -> None:
        super().__init__(graph)
        self.volume = volume
        self.z, self.y, self.x, self.r2 = z, y, x, r2
        self.spacing = spacing

    def is_limb(self, b: int, exclusive: int) -> bool:
        """Whether end branch ``b`` (alone covering ``exclusive`` voxels) is a limb on the
        current skeleton; a limb is remembered (:attr:`limb`)."""
        if self.limb[b]:
            return True
        if exclusive == 0:  # a whole ball holds its centre voxel at least
            return False
        pts = self._points(b)
        r2 = self.r2[pts]
        deep = r2 > rim(self.spacing)
        if not deep.any():
            return False
        if self.counts is None:
            alive = self.graph.alive_points()
            self.counts = ball_counts(
                self.volume.shape,
                self.z[alive],
                self.y[alive],
                self.x[alive],
                self.r2[alive],
                self.spacing,
            )
        z, y, x = self.z[pts], self.y[pts], self.x[pts]
        root = np.sqrt(r2)
        lo, hi = [], []
        for c, s, n in zip((z, y, x), self.spacing, self.volume.shape, strict=True):
            reach = (root / s).astype(np.int64) + 2  # the balls' reach and one voxel more
            lo.append(max(int((c - reach).min()), 0))
            hi.append(min(int((c + reach).max()) + 1, n))
        box = tuple(slice(a, b_) for a, b_ in zip(lo, hi, strict=True))
        before = self.counts[box]
        after = before.copy()
        _paint(after, z - lo[0], y - lo[1], x - lo[2], r2, np.array(self.spacing), -1)
        zd, yd, xd = z[deep] - lo[0], y[deep] - lo[1], x[deep] - lo[2]
        if all(float(s).is_integer() for s in self.spacing):
            # exact squared distances: a ball is whole when none of its voxels is
            # covered by another branch or lies outside, read ball by ball
            whole = np.zeros(zd.size, np.bool_)
            _whole_balls(after, before, zd, yd, xd, r2[deep], np.array(self.spacing), whole)
        else:  # the distance to the nearest voxel not only this branch's, as measured
            d2 = squared_distance((after == 0) & (before > 0), self.spacing)
            whole = d2[zd, yd, xd] >= r2[deep]
        found = limb_rule(r2[deep][whole].tolist(), self.spacing)
        self.limb[b] = found
        return found

    def _uncover(self, points: np.ndarray) -> None:
        z, y, x, r2 = self.z[points], self.y[points], self.x[points], self.r2[points]
        assert self.counts is not None
        _paint(self.counts, z, y, x, r2, np.array(self.spacing), -1)


@njit(cache=True)
def _whole_balls(after, before, z, y, x, r2, spacing, whole) -> None:
    """``whole[k]``: every voxel of ball ``k`` (``|p − s|² < r2``, as :func:`_paint`
    paints it) is covered (``before > 0``) and by no ball but the branch's (``after ==
    0``); a ball reaching past the arrays is not. The test ``d2(s) ≥ r2(s)`` of the
    distance to the nearest voxel not so covered, without the distance transform."""
    sz, sy, sx = spacing[0], spacing[1], spacing[2]
    nz, ny, nx = after.shape
    for k in range(z.size):
        v = r2[k]
        reach_a = int(math.sqrt(v) / sz) + 1
        reach_b = int(math.sqrt(v) / sy) + 1
        ok = True
        for a in range(-reach_a, reach_a + 1):
            az = a * sz
            for b in range(-reach_b, reach_b + 1):
                by = b * sy
                c = row_half_width(v, az * az + by * by, sx)
                if c < 0:
                    continue
                zz, yy = z[k] + a, y[k] + b
                if zz < 0 or zz >= nz or yy < 0 or yy >= ny or x[k] - c < 0 or x[k] + c >= nx:
                    ok = False
                    break
                for q in range(x[k] - c, x[k] + c + 1):
                    if after[zz, yy, q] != 0 or before[zz, yy, q] <= 0:
                        ok = False
                        break
                if not ok:
                    break
            if not ok:
                break
        whole[k] = ok
