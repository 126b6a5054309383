"""The volume each owner alone covers, exactly up to date (the pruning's volume term).

:class:`VolumeCoverage` is the volume grid's counterpart of
:class:`skelprune.grid.coverage.Coverage`: skeleton voxels carry owner labels (a branch
or a junction cluster), and for every label it keeps the voxels inside that only that
label's balls cover, the volume removing it would lose, as owners are removed and merged.

Each voxel inside keeps three sums over the balls that cover it: their number ``c``, the
sum ``s`` of their labels and the sum ``q`` of the labels' squares. All the balls carry
one label ``L`` exactly when ``c·q = s²`` (equality in Cauchy–Schwarz), and then
``L = s / c``; so a ball's removal or relabelling updates its voxels in constant time
each, and the per-label counts follow each voxel's owner before and after. The counts
live only on the voxels inside (an index volume maps a voxel to its slot), so memory is
four bytes per voxel of the array and twenty per voxel inside.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .balls import row_half_width
from .distance import check_spacing

__all__ = ["VolumeCoverage"]


class VolumeCoverage:
    """Incremental coverage of a volume by labelled skeleton balls.

    Parameters
    ----------
    volume : (Z, Y, X) bool array
        The shape ``D``.
    z, y, x : (n,) int arrays
        Skeleton voxels.
    r2 : (n,) float array
        Their squared ball radii, in physical units (a ball ``|p − s|² < r2``).
    labels : (n,) int array
        Owner label of each point, in ``1 .. n_labels - 1``.
    n_labels : int
        Size of the label space.
    spacing : (dz, dy, dx)
        Physical size of a voxel.

    Attributes
    ----------
    lost : int
        Voxels inside no ball covers.
    exclusive : (n_labels,) int64
        Voxels inside covered by the balls of one label only: what removing it would
        lose. Exact for the labels still in use.

    Examples
    --------
    Two balls of 7 voxels (``r2 = 2``: centre and six faces), far apart, labels 1 and 2:

    >>> v = np.ones((3, 3, 9), bool)
    >>> cov = VolumeCoverage(v, [1, 1], [1, 1], [1, 6], [1.5, 1.5], [1, 2], 3)
    >>> cov.exclusive.tolist(), cov.lost
    ([0, 7, 7], 67)
    >>> cov.merge_label(2, 1)
    >>> int(cov.exclusive[1]), cov.remove_label(1), cov.lost
    (14, 14, 81)
    """

    def __init__(
        self,
        volume: np.ndarray,
        z: np.ndarray,
        y: np.ndarray,
        x: np.ndarray,
        r2: np.ndarray,
        labels: np.ndarray,
        n_labels: int,
        spacing: tuple[float, float, float] = (1.0, 1.0, 1.0),
    ) -> None:
        inside = np.asarray(volume) != 0
        self.shape = inside.shape
        self.flat_inside = np.flatnonzero(inside)
        self.index = np.full(self.shape, -1, np.int32)
        self.index.ravel()[self.flat_inside] = np.arange(self.flat_inside.size, dtype=np.int32)
        n = self.flat_inside.size
        self.c = np.zeros(n, np.int32)
        self.s = np.zeros(n, np.int64)
        self.q = np.zeros(n, np.int64)
        self.spacing = np.array(check_spacing(spacing))
        self.z = np.asarray(z, np.int64)
        self.y = np.asarray(y, np.int64)
        self.x = np.asarray(x, np.int64)
        self.r2 = np.asarray(r2, np.float64)
        labels = np.asarray(labels, np.int64)
        self.exclusive = np.zeros(int(n_labels), np.int64)
        # every voxel inside starts uncovered, then each ball is added
        self.lost = int(n)
        order = np.argsort(labels, kind="stable")
        bounds = np.searchsorted(labels[order], np.arange(int(n_labels) + 1))
        self.members: dict[int, list[np.ndarray]] = {}
        for label in np.unique(labels).tolist():
            pts = order[bounds[label] : bounds[label + 1]]
            self.members[label] = [pts]
            self.lost -= self._apply(pts, 1, label, label * label)

    def _apply(self, pts: np.ndarray, dc: int, ds: int, dq: int) -> int:
        """Add ``(dc, ds, dq)`` to every voxel of every ball of ``pts``; returns how
        many voxels became covered (negative: uncovered)."""
        return int(
            _update(
                self.index,
                self.c,
                self.s,
                self.q,
                self.exclusive,
                self.z[pts],
                self.y[pts],
                self.x[pts],
                self.r2[pts],
                self.spacing,
                dc,
                ds,
                dq,
            )
        )

    def remove_label(self, old: int) -> int:
        """Remove the balls of all points labelled ``old``; returns the newly uncovered
        volume (voxels)."""
        lost = 0
        for pts in self.members.pop(old, []):
            lost -= self._apply(pts, -1, -old, -old * old)
        self.lost += lost
        return lost

    def merge_label(self, old: int, new: int) -> None:
        """Give all points labelled ``old`` the label ``new``."""
        if old == new or old not in self.members:
            return
        moved = self.members.pop(old)
        for pts in moved:
            self._apply(pts, 0, new - old, new * new - old * old)
        self.members.setdefault(new, []).extend(moved)

    def uncovered(self) -> np.ndarray:
        """Flat indices (raster order) of the voxels inside no ball covers."""
        return self.flat_inside[self.c == 0]


@njit(cache=True, inline="always")
def _owner(c, s, q):
    """The one label of a voxel's balls; 0 when none covers it, -1 when several labels do."""
    if c == 0:
        return 0
    if c * q == s * s:
        return s // c
    return -1


@njit(cache=True)
def _update(index, c, s, q, exclusive, z, y, x, r2, spacing, dc, ds, dq):
    """Add ``(dc, ds, dq)`` to the sums of every voxel inside of every ball, a row of
    voxels at a time (the rows of :func:`skelprune.grid3d.balls._paint`), keeping the
    per-label exclusive counts; returns covered-after minus covered-before voxels."""
    sz, sy, sx = spacing[0], spacing[1], spacing[2]
    nz, ny, nx = index.shape
    gained = 0
    for k in range(z.size):
        v = r2[k]
        if v <= 0.0:
            continue
        reach_a = int(math.sqrt(v) / sz) + 1
        reach_b = int(math.sqrt(v) / sy) + 1
        for a in range(max(-reach_a, -z[k]), min(reach_a, nz - 1 - z[k]) + 1):
            az = a * sz
            for b in range(max(-reach_b, -y[k]), min(reach_b, ny - 1 - y[k]) + 1):
                by = b * sy
                w = row_half_width(v, az * az + by * by, sx)
                if w < 0:
                    continue
                row = index[z[k] + a, y[k] + b]
                for col in range(max(x[k] - w, 0), min(x[k] + w, nx - 1) + 1):
                    i = row[col]
                    if i < 0:
                        continue
                    before = _owner(c[i], s[i], q[i])
                    was = c[i] > 0
                    c[i] += dc
                    s[i] += ds
                    q[i] += dq
                    after = _owner(c[i], s[i], q[i])
                    if before != after:
                        if before > 0:
                            exclusive[before] -= 1
                        if after > 0:
                            exclusive[after] += 1
                    gained += (c[i] > 0) - was
    return gained
