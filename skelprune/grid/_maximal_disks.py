"""Centres of maximal disks: the anchors of the medial axis's thinning.

A pixel is an anchor when no pixel within the window of :data:`VECTORS` has a disk that
contains its own; containment is read off a table of the smallest squared radius a
pixel at each offset needs (:func:`_domination_table`).
"""

from __future__ import annotations

import functools

import numpy as np
from numba import njit

from ._digital import isqrt

__all__ = ["REACH", "VECTORS", "VECTOR_KIND"]

# Test vectors of the domination test: every offset in a 7 x 7 window. Eight
# neighbours alone see domination only where the distance gradient is axial or
# diagonal; elsewhere nearly every pixel would pass for a centre of a maximal disk.
REACH = 3
# Shortest first: the containing disk is most often a near one (the order does not
# change the result, only how soon the search stops).
VECTORS = np.array(
    sorted(
        (
            (dy, dx)
            for dy in range(-REACH, REACH + 1)
            for dx in range(-REACH, REACH + 1)
            if (dy, dx) != (0, 0)
        ),
        key=lambda v: (v[0] ** 2 + v[1] ** 2, v),
    ),
    dtype=np.int64,
)
# Disks are symmetric, so the table depends on (min, max) of |dy|, |dx| only.
_KINDS = sorted({tuple(sorted((abs(int(a)), abs(int(b))))) for a, b in VECTORS})
VECTOR_KIND = np.array(
    [_KINDS.index(tuple(sorted((abs(int(a)), abs(int(b)))))) for a, b in VECTORS], dtype=np.int64
)


def _domination_table(values: np.ndarray) -> np.ndarray:
    """:func:`_cached_domination_table` sized for the largest of ``values`` (at least 1)."""
    max_r2 = int(values.max()) if values.size else 1
    return _cached_domination_table(1 << max(max_r2, 1).bit_length())


@functools.lru_cache(maxsize=8)
def _cached_domination_table(max_r2: int) -> np.ndarray:
    """For each squared radius ``R`` and each vector kind ``v``: the smallest ``r2`` a
    pixel at offset ``v`` needs for its disk to contain the disk of radius² ``R``.

    That is one more than the largest ``|o − v|²`` over the offsets ``|o|² < R``.
    Entries depend on ``R`` only, so a table sized by a power of two serves every
    smaller shape.
    """
    # int32 while the entries fit (below (√R + 3√2)² + 1 < 2³¹): half the memory of a
    # table that a 4096-px shape makes 4 M rows long
    need = np.full((max_r2 + 1, len(_KINDS)), -1, dtype=np.int32 if max_r2 <= 1 << 30 else np.int64)
    _farthest_points(need, np.array(_KINDS, dtype=np.int64))
    return need


@njit(cache=True)
def _farthest_points(need: np.ndarray, kinds: np.ndarray) -> None:
    """Fill ``need`` (``max_r2 + 1`` rows of -1, one column per kind) in place."""
    # Bucketed by |o|² instead of sorting the offsets by it: a running maximum over the
    # buckets is then the maximum over each disk (1.4 s → 0.16 s for a 4096-px shape).
    nk = kinds.shape[0]
    max_r2 = need.shape[0] - 1  # row L + 1: offsets |o|² = L
    reach = isqrt(max_r2 - 1)  # the largest |dy| with dy² < max_r2
    # kinds have no negative coordinate, so of the offsets ±dy, ±dx (same |o|²) the
    # one with both coordinates ≤ 0 is the farthest: one quadrant is enough
    for dy in range(-reach, 1):
        for dx in range(-reach, 1):
            length = dy * dy + dx * dx
            if length >= max_r2:
                continue
            for j in range(nk):
                a, b = dy - kinds[j, 0], dx - kinds[j, 1]
                if a * a + b * b > need[length + 1, j]:
                    need[length + 1, j] = a * a + b * b
    run = np.full(nk, -1, dtype=np.int64)
    need[0, :] = 0
    for big_r in range(1, max_r2 + 1):
        for j in range(nk):
            run[j] = max(run[j], need[big_r, j])
            need[big_r, j] = run[j] + 1


@njit(cache=True, inline="always")
def _dominated_by(r2, need, vectors, kind, r, c, v, i) -> bool:
    """Whether the disk at ``(r, c)`` + ``vectors[i]`` contains the one at ``(r, c)``."""
    rr, cc = r + vectors[i, 0], c + vectors[i, 1]
    if rr < 0 or cc < 0 or rr >= r2.shape[0] or cc >= r2.shape[1]:
        return False
    return r2[rr, cc] >= need[v, kind[i]]


# inline="always": called from the medial axis's compiled pass and, in tests, from
# Python (see skelprune.grid._disk_counts.coverage on returned arrays).
@njit(cache=True, inline="always")
def _anchors(r2: np.ndarray, need: np.ndarray, vectors: np.ndarray, kind: np.ndarray) -> np.ndarray:
    """Centres of maximal disks: pixels whose disk no nearby pixel's disk contains.

    Exact on the discrete disks, within the window of ``vectors``; a pixel whose
    disk is contained only by a farther one stays an anchor, which costs a spur the
    redundancy pass removes, never reconstruction.
    """
    h, w = r2.shape
    anchor = np.zeros((h, w), dtype=np.bool_)
    last = 0  # the vector that found the previous pixel dominated: tried first
    for r in range(1, h - 1):
        for c in range(1, w - 1):
            v = r2[r, c]
            if v == 0:
                continue
            if _dominated_by(r2, need, vectors, kind, r, c, v, last):
                continue
            dominated = False
            for i in range(vectors.shape[0]):
                if _dominated_by(r2, need, vectors, kind, r, c, v, i):
                    dominated = True
                    last = i
                    break
            anchor[r, c] = not dominated
    return anchor
