"""Naive references for the volume grid, from scratch and slow: what the compiled
kernels of :mod:`skelprune.grid3d` must equal on small volumes.

Distances and balls use the expression of docs/volumes.md, ``(a·dz)² + (b·dy)² + (c·dx)²``
for integer offsets ``(a, b, c)``, evaluated in that order, so equality is exact.
"""

from __future__ import annotations

import numpy as np

__all__ = ["ball_counts", "lost_volume", "squared_distance"]


def _squared(offsets: np.ndarray, spacing) -> np.ndarray:
    a = offsets[..., 0] * float(spacing[0])
    b = offsets[..., 1] * float(spacing[1])
    c = offsets[..., 2] * float(spacing[2])
    return a * a + b * b + c * c


def squared_distance(volume: np.ndarray, spacing=(1.0, 1.0, 1.0)) -> np.ndarray:
    """Brute force: for every voxel inside, the least squared distance to a background
    voxel of the volume padded by one background voxel."""
    padded = np.pad(np.asarray(volume) != 0, 1)
    background = np.argwhere(~padded)
    out = np.zeros(padded.shape, dtype=np.float64)
    for p in np.argwhere(padded):
        out[tuple(p)] = _squared(background - p, spacing).min()
    return out[1:-1, 1:-1, 1:-1]


def ball_counts(shape, z, y, x, r2, spacing=(1.0, 1.0, 1.0)) -> np.ndarray:
    """Paint every ball ``|p − s|² < r2(s)`` over the whole array and add them up."""
    grid = np.indices(shape).transpose(1, 2, 3, 0)
    out = np.zeros(shape, dtype=np.int64)
    for s in zip(z, y, x, r2, strict=True):
        out += _squared(grid - np.array(s[:3]), spacing) < s[3]
    return out


def lost_volume(volume, z, y, x, r2, spacing=(1.0, 1.0, 1.0)) -> int:
    """Voxels inside that no ball covers, from :func:`ball_counts`."""
    volume = np.asarray(volume) != 0
    return int((volume & (ball_counts(volume.shape, z, y, x, r2, spacing) == 0)).sum())
