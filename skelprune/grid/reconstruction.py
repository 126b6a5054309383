"""Reconstruction of a shape from skeleton disks, and its area term (docs/algorithm.md).

The area each owner alone covers, kept up to date as the pruning removes and merges
owners, is :class:`~skelprune.grid.coverage.Coverage`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._digital import disk_half_width, isqrt
from ._last_cover import last_cover

__all__ = [
    "count_covered",
    "reconstruction",
    "reconstruction_error",
]


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
        _paint_bool(
            out, np.asarray(rows, np.int64), np.asarray(cols, np.int64), np.asarray(r2, np.int64)
        )
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


def count_covered(
    pixels: np.ndarray, width: int, rows: np.ndarray, cols: np.ndarray, r2: np.ndarray
) -> int:
    """How many of ``pixels`` (flat indices, row length ``width``) the disks cover.

    For a few pixels and many disks: the pixels are a bitmap in tiles that each disk
    walks a row of tiles at a time, skipping the tiles with no pixel left to find
    (:func:`~skelprune.grid._last_cover.last_cover`), so a disk costs about its height in
    tiles, not its area nor a test per pixel.

    Examples
    --------
    >>> count_covered(np.array([0, 7, 24]), 5, np.array([1]), np.array([1]), np.array([2]))
    1
    """
    if len(pixels) == 0 or len(rows) == 0:
        return 0
    return int(
        _count_covered(
            np.asarray(pixels, np.int64),
            int(width),
            np.asarray(rows, np.int64),
            np.asarray(cols, np.int64),
            np.asarray(r2, np.int64),
        )
    )


@njit(cache=True)
def _count_covered(pixels, width, rows, cols, r2):
    height = pixels.max() // width + 1
    for k in range(rows.size):
        height = max(height, rows[k] + isqrt(r2[k] - 1) + 1)
    inside = np.zeros((height, width), np.bool_)
    for p in pixels:
        inside[p // width, p % width] = True
    last = last_cover(inside, rows, cols, r2).ravel()
    n = 0
    for p in pixels:
        n += last[p] >= 0
    return n
