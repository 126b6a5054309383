"""Disk coverage counts with cheap whole-disk queries and removals.

The thinning of the medial axis keeps, for every pixel, how many disks of a set
cover it, and asks of one disk at a time: how many of its pixels are covered exactly
once (by the disk alone), and removes the disk. Walking every pixel of a disk costs
its area, which dominates on large shapes (radii of 100 px and more). Here each row
of the count array is cut into blocks of ``BLOCK`` pixels carrying their minimum, the
number of pixels at that minimum, and a pending addend for the whole block: a disk
row then costs its two partial end blocks plus one step per full block in between.

:func:`drop_redundant_anchors`, a pass of the medial axis, uses :func:`last_cover`
instead (:mod:`skelprune.grid._last_cover`).

The true count of pixel ``(y, x)`` is ``cover[y, x] + lazy[y, x // BLOCK]``;
``bmin`` and ``bcnt`` describe ``cover`` alone (the addend shifts a whole block).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._digital import disk_half_width, isqrt

__all__ = [
    "BLOCK",
    "DiskCounts",
    "coverage",
    "disk_loss",
    "disk_remove",
    "with_blocks",
]

BLOCK = 16

# (cover, bmin, bcnt, lazy): the arrays of one coverage count, see the module docstring.
DiskCounts = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]


# inline="always": the thinning calls this inside compiled code and tests call it from
# Python. As a separately compiled callee loaded from numba's cache, its Python entry
# fails to box the returned arrays ("NRT_adapt_ndarray_to_python: 'descr' is NULL");
# inlined, the dispatcher only ever compiles for Python callers.
@njit(cache=True, inline="always")
def coverage(shape_h: int, shape_w: int, rows, cols, r2s):
    """Counts of the disks ``(rows[k], cols[k], r2s[k])`` over an ``(h, w)`` grid.

    Painted as +1/-1 at the ends of every disk row and summed along the rows, so
    the cost is the disks' heights, not their areas. The disks are painted in raster
    order of their centres: neighbours' disks write to the same cache lines, where an
    order by radius scatters the writes over the whole array (3× slower on a blob).

    Returns
    -------
    cover : (h, nb * BLOCK) int32, bmin, bcnt, lazy : (h, nb) int32
    """
    nb = (shape_w + BLOCK - 1) // BLOCK
    wide = nb * BLOCK
    cover = np.zeros((shape_h, wide + 1), dtype=np.int32)
    for k in np.argsort((rows >> 4) * (wide + 1) + (cols >> 4)):
        r, c, v = rows[k], cols[k], r2s[k]
        h = isqrt(v - 1)
        w = h  # the half width, walked down from the middle row: no square root a row
        for dy in range(h + 1):
            while w * w > v - 1 - dy * dy:
                w -= 1
            cover[r + dy, c - w] += 1
            cover[r + dy, c + w + 1] -= 1
            if dy:
                cover[r - dy, c - w] += 1
                cover[r - dy, c + w + 1] -= 1
    for y in range(shape_h):
        run = 0
        for x in range(wide):
            run += cover[y, x]
            cover[y, x] = run
    cover = cover[:, :wide].copy()
    return with_blocks(cover)


@njit(cache=True, inline="always")
def with_blocks(cover) -> DiskCounts:
    """``cover`` (``h × nb · BLOCK`` counts) with its per-block minima and their counts,
    and no lazy decrement yet: one coverage count (see the module docstring)."""
    shape_h, nb = cover.shape[0], cover.shape[1] // BLOCK
    bmin = np.empty((shape_h, nb), dtype=np.int32)
    bcnt = np.empty((shape_h, nb), dtype=np.int32)
    lazy = np.zeros((shape_h, nb), dtype=np.int32)
    for y in range(shape_h):
        for b in range(nb):
            _block_stats(cover, bmin, bcnt, y, b)
    return cover, bmin, bcnt, lazy


@njit(cache=True, inline="always")
def _block_stats(cover, bmin, bcnt, y, b) -> None:
    row = cover[y]
    m = row[b * BLOCK]
    n = 0
    for x in range(b * BLOCK, (b + 1) * BLOCK):
        if row[x] < m:
            m = row[x]
            n = 1
        elif row[x] == m:
            n += 1
    bmin[y, b] = m
    bcnt[y, b] = n


@njit(cache=True, inline="always")
def _row_ones(cover, bmin, bcnt, lazy, y, a, e) -> int:
    """Pixels of ``cover[y, a:e+1]`` whose true count is 1 (counts must be >= 1)."""
    row = cover[y]
    ba, be = a // BLOCK, e // BLOCK
    n = 0
    if ba == be:
        one = 1 - lazy[y, ba]
        for x in range(a, e + 1):
            n += row[x] == one
        return n
    one = 1 - lazy[y, ba]
    for x in range(a, (ba + 1) * BLOCK):
        n += row[x] == one
    for b in range(ba + 1, be):
        m = bmin[y, b] + lazy[y, b]
        if m == 1:
            n += bcnt[y, b]
        elif m < 1:  # not expected: counted pixel by pixel all the same
            one_b = 1 - lazy[y, b]
            for x in range(b * BLOCK, (b + 1) * BLOCK):
                n += row[x] == one_b
    one = 1 - lazy[y, be]
    for x in range(be * BLOCK, e + 1):
        n += row[x] == one
    return n


@njit(cache=True, inline="always")
def _row_decrement(cover, bmin, bcnt, lazy, y, a, e) -> None:
    """Subtract 1 from the true counts of ``cover[y, a:e+1]``."""
    row = cover[y]
    ba, be = a // BLOCK, e // BLOCK
    if ba == be and (a > ba * BLOCK or e < (be + 1) * BLOCK - 1):
        for x in range(a, e + 1):
            row[x] -= 1
        _block_stats(cover, bmin, bcnt, y, ba)
        return
    first, last = ba, be
    if a > ba * BLOCK:  # partial first block
        for x in range(a, (ba + 1) * BLOCK):
            row[x] -= 1
        _block_stats(cover, bmin, bcnt, y, ba)
        first = ba + 1
    if e < (be + 1) * BLOCK - 1:  # partial last block
        for x in range(be * BLOCK, e + 1):
            row[x] -= 1
        _block_stats(cover, bmin, bcnt, y, be)
        last = be - 1
    for b in range(first, last + 1):
        lazy[y, b] -= 1


@njit(cache=True)
def disk_loss(cover, bmin, bcnt, lazy, r, c, v) -> int:
    """Pixels of the disk at ``(r, c)`` covered exactly once, by the disk itself.

    The disk must be counted in ``cover`` (every count on it is then at least 1).
    """
    n = 0
    h = isqrt(v - 1)
    for dy in range(-h, h + 1):
        w = disk_half_width(v, dy)
        n += _row_ones(cover, bmin, bcnt, lazy, r + dy, c - w, c + w)
    return n


@njit(cache=True)
def disk_remove(cover, bmin, bcnt, lazy, r, c, v) -> None:
    """Take the disk at ``(r, c)``, ``r2 = v`` out of the counts."""
    h = isqrt(v - 1)
    for dy in range(-h, h + 1):
        w = disk_half_width(v, dy)
        _row_decrement(cover, bmin, bcnt, lazy, r + dy, c - w, c + w)
