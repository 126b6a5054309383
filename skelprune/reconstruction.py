"""Reconstruction of a shape from skeleton disks, and its area term (SPEC §2.2).

Besides the plain reconstruction, :class:`Coverage` keeps, for every pixel, how many
skeleton disks cover it and the sum and the sum of squares of their owners' labels.
A pixel is covered by one owner ``b`` only iff ``s1 == c*b`` and ``s2 == c*b*b``
(equality in the Cauchy–Schwarz inequality), so the area each end branch alone
covers, the area its removal would lose, is kept up to date exactly with work
proportional to the disks that change.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._digital import disk_half_width, isqrt

__all__ = ["Coverage", "count_covered", "reconstruction", "reconstruction_error"]


@njit(cache=True)
def _paint_bool(out, rows, cols, r2):
    for k in range(rows.size):
        v = r2[k]
        h = isqrt(v - 1)
        for dy in range(-h, h + 1):
            w = disk_half_width(v, dy)
            row = out[rows[k] + dy]
            for q in range(cols[k] - w, cols[k] + w + 1):
                row[q] = True


def reconstruction(
    shape: tuple[int, int], rows: np.ndarray, cols: np.ndarray, r2: np.ndarray
) -> np.ndarray:
    """Union of the disks ``|p - s|**2 < r2(s)`` of the given points.

    The disks must lie inside the array (true for radii taken from the shape's
    distance transform when the shape has a background border).

    Examples
    --------
    >>> reconstruction((5, 5), np.array([2]), np.array([2]), np.array([2])).sum()
    np.int64(5)
    """
    out = np.zeros(shape, dtype=np.bool_)
    if len(rows):
        _paint_bool(out, np.asarray(rows, np.int64), np.asarray(cols, np.int64),
                    np.asarray(r2, np.int64))
    return out


def reconstruction_error(
    mask: np.ndarray, rows: np.ndarray, cols: np.ndarray, r2: np.ndarray
) -> float:
    """``AR(S) = Λ(D \\ R(S)) / Λ(D)``: the share of the shape the disks miss."""
    area = int(mask.sum())
    if area == 0:
        return 0.0
    rec = reconstruction(mask.shape, rows, cols, r2)
    return float((mask & ~rec).sum()) / area


def count_covered(pixels: np.ndarray, width: int, rows: np.ndarray, cols: np.ndarray,
                  r2: np.ndarray) -> int:
    """How many of ``pixels`` (flat indices, row length ``width``) the disks cover.

    For a few pixels and many disks: a test per pair, no painting.

    Examples
    --------
    >>> count_covered(np.array([0, 7, 24]), 5, np.array([1]), np.array([1]), np.array([2]))
    1
    """
    if len(pixels) == 0 or len(rows) == 0:
        return 0
    return int(_count_covered(np.asarray(pixels, np.int64) // width,
                              np.asarray(pixels, np.int64) % width,
                              np.asarray(rows, np.int64), np.asarray(cols, np.int64),
                              np.asarray(r2, np.int64)))


@njit(cache=True)
def _count_covered(py, px, rows, cols, r2):
    n = 0
    for i in range(py.size):
        for k in range(rows.size):
            dy = py[i] - rows[k]
            dx = px[i] - cols[k]
            if dy * dy + dx * dx < r2[k]:
                n += 1
                break
    return n


# Kernels index a 1-D view of each disk row: measured faster than both slice updates
# and 2-D indexing (no per-row slice objects, no 2-D address arithmetic).


@njit(cache=True)
def _paint_labels(c, s1, s2, rows, cols, r2, lab):
    for k in range(rows.size):
        lb = lab[k]
        lb2 = lb * lb
        v = r2[k]
        h = isqrt(v - 1)
        for dy in range(-h, h + 1):
            w = disk_half_width(v, dy)
            r = rows[k] + dy
            cr, s1r, s2r = c[r], s1[r], s2[r]
            for q in range(cols[k] - w, cols[k] + w + 1):
                cr[q] += 1
                s1r[q] += lb
                s2r[q] += lb2


@njit(cache=True)
def _remove(c, s1, s2, stamp, tick, excl, pts, rows, cols, r2, lab):
    """Remove the disks of ``pts``; return the pixels left uncovered.

    A pixel's remaining owners are all one label ``b`` iff ``c·s2 == s1²``
    (Cauchy–Schwarz), a test without division; labels and counts stay far below
    2**31, so the products cannot overflow.
    """
    for k in pts:
        lb = lab[k]
        lb2 = lb * lb
        v = r2[k]
        h = isqrt(v - 1)
        for dy in range(-h, h + 1):
            w = disk_half_width(v, dy)
            r = rows[k] + dy
            cr, s1r, s2r = c[r], s1[r], s2[r]
            for q in range(cols[k] - w, cols[k] + w + 1):
                cr[q] -= 1
                s1r[q] -= lb
                s2r[q] -= lb2
    lost = 0
    for k in pts:
        v = r2[k]
        h = isqrt(v - 1)
        for dy in range(-h, h + 1):
            w = disk_half_width(v, dy)
            r = rows[k] + dy
            cr, s1r, s2r, st = c[r], s1[r], s2[r], stamp[r]
            for q in range(cols[k] - w, cols[k] + w + 1):
                # The cheap owner test first: most pixels keep several owners.
                n = cr[q]
                x = s1r[q]
                if n == 0:
                    if st[q] != tick:
                        st[q] = tick
                        lost += 1
                elif n * s2r[q] == x * x and st[q] != tick:
                    st[q] = tick
                    excl[x // n] += 1
    return lost


@njit(cache=True)
def _relabel(c, s1, s2, stamp, tick, excl, pts, rows, cols, r2, lab, new):
    """Give the points ``pts`` the label ``new``, updating single-owner areas."""
    for k in pts:
        old = lab[k]
        d1 = new - old
        d2 = new * new - old * old
        v = r2[k]
        h = isqrt(v - 1)
        for dy in range(-h, h + 1):
            w = disk_half_width(v, dy)
            r = rows[k] + dy
            s1r, s2r = s1[r], s2[r]
            for q in range(cols[k] - w, cols[k] + w + 1):
                s1r[q] += d1
                s2r[q] += d2
        lab[k] = new
    nn = new * new
    for k in pts:
        v = r2[k]
        h = isqrt(v - 1)
        for dy in range(-h, h + 1):
            w = disk_half_width(v, dy)
            r = rows[k] + dy
            cr, s1r, s2r, st = c[r], s1[r], s2[r], stamp[r]
            for q in range(cols[k] - w, cols[k] + w + 1):
                n = cr[q]
                if s1r[q] == n * new and s2r[q] == n * nn and st[q] != tick:
                    st[q] = tick
                    excl[new] += 1


class Coverage:
    """Incremental coverage of a shape by labelled skeleton disks.

    Parameters
    ----------
    mask : (H, W) bool array
        The shape ``D``, with a background border.
    rows, cols, r2 : (n,) int arrays
        Skeleton points and squared radii.
    labels : (n,) int array
        Owner label of each point, in ``1 .. n_labels - 1``.
    n_labels : int
        Size of the label space.

    Attributes
    ----------
    lost : int
        Pixels of ``D`` no disk covers, ``Λ(D \\ R(S))``.
    exclusive : (n_labels,) int64
        Pixels covered by the disks of one label only: what removing it would lose.
    """

    def __init__(self, mask, rows, cols, r2, labels, n_labels: int) -> None:
        self.rows = np.asarray(rows, np.int64)
        self.cols = np.asarray(cols, np.int64)
        self.r2 = np.asarray(r2, np.int64)
        self.labels = np.asarray(labels, np.int64).copy()
        shape = mask.shape
        self.c = np.zeros(shape, np.int32)
        self.s1 = np.zeros(shape, np.int64)
        self.s2 = np.zeros(shape, np.int64)
        self.stamp = np.zeros(shape, np.int32)
        self.tick = 0
        _paint_labels(self.c, self.s1, self.s2, self.rows, self.cols, self.r2, self.labels)
        n = self.c.astype(np.int64)
        covered = n > 0
        owner = np.where(covered, self.s1 // np.maximum(n, 1), -1)
        single = covered & (self.s1 == n * owner) & (self.s2 == n * owner * owner)
        self.exclusive = np.bincount(owner[single], minlength=n_labels).astype(np.int64)
        self.lost = int((mask & ~covered).sum())

    def remove(self, points: np.ndarray) -> int:
        """Remove the disks of ``points``; returns the newly uncovered area."""
        self.tick += 1
        lost = _remove(self.c, self.s1, self.s2, self.stamp, self.tick, self.exclusive,
                       np.asarray(points, np.int64), self.rows, self.cols, self.r2,
                       self.labels)
        self.lost += lost
        return lost

    def relabel(self, points: np.ndarray, new: int) -> None:
        """Move ``points`` to owner ``new`` (two branches merged into one)."""
        self.tick += 1
        _relabel(self.c, self.s1, self.s2, self.stamp, self.tick, self.exclusive,
                 np.asarray(points, np.int64), self.rows, self.cols, self.r2, self.labels,
                 new)
