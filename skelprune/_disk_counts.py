"""Disk coverage counts with cheap whole-disk queries and removals.

The thinning of the medial axis keeps, for every pixel, how many disks of a set
cover it, and asks of one disk at a time: how many of its pixels are covered exactly
once (by the disk alone), and removes the disk. Walking every pixel of a disk costs
its area, which dominates on large shapes (radii of 100 px and more). Here each row
of the count array is cut into blocks of ``BLOCK`` pixels carrying their minimum, the
number of pixels at that minimum, and a pending addend for the whole block: a disk
row then costs its two partial end blocks plus one step per full block in between.

:func:`drop_redundant_anchors`, a pass of the medial axis, uses :func:`last_cover`
instead.

The true count of pixel ``(y, x)`` is ``cover[y, x] + lazy[y, x // BLOCK]``;
``bmin`` and ``bcnt`` describe ``cover`` alone (the addend shifts a whole block).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._digital import disk_half_width, isqrt

__all__ = ["BLOCK", "TILE", "DiskCounts", "coverage", "disk_loss", "disk_remove",
           "drop_redundant_anchors", "last_cover"]

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
    the cost is the disks' heights, not their areas.

    Returns
    -------
    cover : (h, nb * BLOCK) int32, bmin, bcnt, lazy : (h, nb) int32
    """
    nb = (shape_w + BLOCK - 1) // BLOCK
    wide = nb * BLOCK
    cover = np.zeros((shape_h, wide + 1), dtype=np.int32)
    for k in range(rows.size):
        r, c, v = rows[k], cols[k], r2s[k]
        h = isqrt(v - 1)
        for dy in range(-h, h + 1):
            w = disk_half_width(v, dy)
            cover[r + dy, c - w] += 1
            cover[r + dy, c + w + 1] -= 1
    for y in range(shape_h):
        run = 0
        for x in range(wide):
            run += cover[y, x]
            cover[y, x] = run
    cover = cover[:, :wide].copy()
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


@njit(cache=True)
def true_counts(cover, lazy) -> np.ndarray:
    """The plain count array (for tests)."""
    out = cover.copy()
    for y in range(cover.shape[0]):
        for x in range(cover.shape[1]):
            out[y, x] += lazy[y, x // BLOCK]
    return out


@njit(cache=True, inline="always")
def _find(nxt, x) -> int:
    """First unpainted pixel at or after ``x`` in a row (union-find, path compression)."""
    root = x
    while nxt[root] != root:
        root = nxt[root]
    while nxt[x] != root:
        nxt[x], x = root, nxt[x]
    return root


# Side of the square tiles :func:`last_cover` skips once they are all painted.
TILE = 32


@njit(cache=True, inline="always")  # called from compiled code and from tests: see coverage
def last_cover(inside, rows, cols, r2s) -> np.ndarray:
    """For every pixel, the largest ``k`` whose disk ``(rows[k], cols[k], r2s[k])``
    covers it, -1 where none does.

    ``inside`` (bool, the grid's shape) must hold every pixel a disk covers: the shape,
    for its own maximal disks.

    Disks are painted last to first, each onto the pixels no later disk took. Most disks
    of a large shape lie where later (larger) disks have painted everything already, so
    the grid is cut into ``TILE`` × ``TILE`` tiles that count their unpainted pixels: a
    disk visits only the tiles still unpainted somewhere (a union-find per row of tiles
    skips the full ones), and in them, a union-find per pixel row skips the painted
    runs. A disk thus costs the pixels it paints, the partly painted tiles it meets and
    one step per row of tiles, instead of one step for each of its pixel rows. A tile
    is full when its pixels of ``inside`` are painted: the background never is.
    """
    shape_h, shape_w = inside.shape
    last = np.full((shape_h, shape_w), -1, dtype=np.int32)
    nxt = np.empty((shape_h, shape_w + 1), dtype=np.int32)
    for y in range(shape_h):
        for x in range(shape_w + 1):
            nxt[y, x] = x
    th, tw = (shape_h + TILE - 1) // TILE, (shape_w + TILE - 1) // TILE
    left = np.zeros((th, tw), dtype=np.int32)  # unpainted pixels of each tile
    for y in range(shape_h):
        for x in range(shape_w):
            if inside[y, x]:
                left[y // TILE, x // TILE] += 1
    tnxt = np.empty((th, tw + 1), dtype=np.int32)  # next tile with a pixel left
    for ty in range(th):
        for tx in range(tw + 1):
            tnxt[ty, tx] = tx
    for k in range(rows.size - 1, -1, -1):
        r, c, v = rows[k], cols[k], r2s[k]
        h = isqrt(v - 1)
        for ty in range((r - h) // TILE, (r + h) // TILE + 1):
            y0, y1 = max(r - h, ty * TILE), min(r + h, ty * TILE + TILE - 1)
            # the widest row of the disk within this row of tiles
            near = min(max(r, y0), y1)
            wide = disk_half_width(v, near - r)
            trow = tnxt[ty]
            tx = _find(trow, (c - wide) // TILE)
            while tx <= (c + wide) // TILE:
                x0, x1 = tx * TILE, tx * TILE + TILE - 1
                for y in range(y0, y1 + 1):
                    w = disk_half_width(v, y - r)
                    a, e = max(c - w, x0), min(c + w, x1)
                    if a > e:
                        continue
                    row = nxt[y]
                    x = _find(row, a)
                    while x <= e:
                        last[y, x] = k
                        row[x] = x + 1
                        left[ty, tx] -= 1
                        x = _find(row, x + 1)
                if left[ty, tx] == 0:
                    trow[tx] = tx + 1
                tx = _find(trow, tx + 1)
    return last


@njit(cache=True)
def drop_redundant_anchors(anchor, r2, rows, cols) -> None:
    """Un-anchor centres whose disk the other anchors' disks already cover.

    Visited smallest radius first (boundary noise makes many small, redundant
    maximal disks, each of which would otherwise pull a spur into the axis). The union
    of the remaining anchors' disks is unchanged: still the whole shape.

    Anchor ``k`` goes iff each pixel of its disk has another live cover: a later
    anchor (all still live) or an earlier one that stayed. The first holds exactly
    where a later disk covers the pixel, so only the pixels whose last cover is ``k``
    need a look, each pixel of the shape once in all, and only the kept disks are
    painted.
    """
    h, w = anchor.shape
    n = rows.size
    r2s = np.empty(n, dtype=np.int64)
    for k in range(n):
        r2s[k] = r2[rows[k], cols[k]]
    last = last_cover(r2 > 0, rows, cols, r2s).ravel()
    # pixels grouped by their last cover (a counting sort)
    start = np.zeros(n + 1, dtype=np.int64)
    for p in range(last.size):
        if last[p] >= 0:
            start[last[p] + 1] += 1
    for k in range(n):
        start[k + 1] += start[k]
    fill = start[:-1].copy()
    pixels = np.empty(start[n], dtype=np.int64)
    for p in range(last.size):
        if last[p] >= 0:
            pixels[fill[last[p]]] = p
            fill[last[p]] += 1
    kept = np.zeros(h * w, dtype=np.bool_)  # covered by a disk that stayed
    for k in range(n):
        redundant = True
        for i in range(start[k], start[k + 1]):
            if not kept[pixels[i]]:
                redundant = False
                break
        r, c, v = rows[k], cols[k], r2s[k]
        if redundant:
            anchor[r, c] = False
            continue
        for dy in range(-isqrt(v - 1), isqrt(v - 1) + 1):
            half = disk_half_width(v, dy)
            base = (r + dy) * w + c
            kept[base - half : base + half + 1] = True
