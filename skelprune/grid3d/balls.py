"""Reconstruction of a volume from skeleton balls, and its volume term (docs/volumes.md).

A skeleton voxel ``s`` with squared radius ``r2(s)`` covers voxel ``p`` when
``|p − s|² < r2(s)`` in physical units, ``|(a, b, c)|² = (a·dz)² + (b·dy)² + (c·dx)²``
evaluated as :mod:`skelprune.grid3d.distance` evaluates ``r2``. The union of the balls of
all voxels inside is then exactly the volume. The **lost volume** of a skeleton is the
number of voxels inside that none of its balls covers (``AR`` in voxels); the coverage
counts say how many balls cover each voxel, so the voxels a removal uncovers are those
whose count falls to zero.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .distance import check_spacing

__all__ = ["ball_counts", "exclusive_volume", "lost_volume", "reconstruction"]


def _points(z, y, x, r2) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    return (
        np.asarray(z, np.int64),
        np.asarray(y, np.int64),
        np.asarray(x, np.int64),
        np.asarray(r2, np.float64),
    )


def ball_counts(
    shape: tuple[int, int, int],
    z: np.ndarray,
    y: np.ndarray,
    x: np.ndarray,
    r2: np.ndarray,
    spacing: tuple[float, float, float] = (1.0, 1.0, 1.0),
) -> np.ndarray:
    """How many of the balls ``|p − s|² < r2(s)`` cover each voxel ``p`` of ``shape``.

    Balls are clipped to the array. Returns an int32 array of ``shape``.

    Examples
    --------
    >>> c = ball_counts((3, 3, 3), [1, 1], [1, 1], [1, 2], [2.0, 1.0])
    >>> int(c.sum()), int(c[1, 1, 1]), int(c[1, 1, 2])
    (8, 1, 2)
    """
    out = np.zeros(tuple(int(s) for s in shape), dtype=np.int32)
    pz, py, px, pr = _points(z, y, x, r2)
    if pz.size:
        _paint(out, pz, py, px, pr, np.array(check_spacing(spacing)), 1)
    return out


def reconstruction(
    shape: tuple[int, int, int],
    z: np.ndarray,
    y: np.ndarray,
    x: np.ndarray,
    r2: np.ndarray,
    spacing: tuple[float, float, float] = (1.0, 1.0, 1.0),
) -> np.ndarray:
    """Union of the balls of the given points: a bool array of ``shape``.

    Examples
    --------
    >>> int(reconstruction((5, 5, 5), [2], [2], [2], [3.0]).sum())   # |o|² ≤ 2: centre and 18
    19
    """
    return ball_counts(shape, z, y, x, r2, spacing) > 0


def lost_volume(
    volume: np.ndarray,
    z: np.ndarray,
    y: np.ndarray,
    x: np.ndarray,
    r2: np.ndarray,
    spacing: tuple[float, float, float] = (1.0, 1.0, 1.0),
) -> int:
    """Voxels inside ``volume`` that no ball covers: ``Λ(D \\ R(S))`` in voxels.

    Divide by ``volume.sum()`` for the share ``AR``.

    Examples
    --------
    >>> v = np.ones((3, 3, 3), bool)
    >>> lost_volume(v, [1], [1], [1], [3.0])     # the eight corners
    8
    """
    volume = np.asarray(volume) != 0
    covered = reconstruction(volume.shape, z, y, x, r2, spacing)
    return int(np.count_nonzero(volume & ~covered))


def exclusive_volume(
    counts: np.ndarray,
    volume: np.ndarray,
    z: np.ndarray,
    y: np.ndarray,
    x: np.ndarray,
    r2: np.ndarray,
    spacing: tuple[float, float, float] = (1.0, 1.0, 1.0),
) -> int:
    """Voxels inside ``volume`` covered by the given balls and by no other ball counted
    in ``counts`` (:func:`ball_counts` of a skeleton that includes these points): the
    volume that removing these points would lose.

    Examples
    --------
    >>> v = np.ones((3, 3, 3), bool)
    >>> c = ball_counts(v.shape, [1, 1], [1, 1], [1, 2], [2.0, 1.0])
    >>> exclusive_volume(c, v, [1], [1], [1], [2.0])   # the ball at x = 1 but its centre-right
    6
    """
    own = ball_counts(counts.shape, z, y, x, r2, spacing)
    volume = np.asarray(volume) != 0
    return int(np.count_nonzero(volume & (own > 0) & (counts == own)))


@njit(cache=True, inline="always")
def row_half_width(v, ab2, sx):
    """The largest ``c ≥ 0`` with ``ab2 + (c·dx)² < v``, by the exact test: the half
    width of the row of a ball of squared radius ``v`` whose offsets along ``z`` and
    ``y`` give ``ab2 = (a·dz)² + (b·dy)²``; -1 where the row holds no voxel. Every kernel
    that walks a ball row by row takes its rows from here."""
    rest = v - ab2
    if rest <= 0.0:
        return -1
    c = int(math.sqrt(rest) / sx) + 1
    while c >= 0:  # the last c inside, by the exact test
        cx = c * sx
        if ab2 + cx * cx < v:
            break
        c -= 1
    return c


@njit(cache=True)
def _paint(out, z, y, x, r2, spacing, value) -> None:
    """Add ``value`` to every voxel of every ball, a row of voxels at a time."""
    sz, sy, sx = spacing[0], spacing[1], spacing[2]
    nz, ny, nx = out.shape
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
                c = row_half_width(v, az * az + by * by, sx)
                if c < 0:
                    continue
                row = out[z[k] + a, y[k] + b]
                for q in range(max(x[k] - c, 0), min(x[k] + c, nx - 1) + 1):
                    row[q] += value
