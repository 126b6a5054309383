"""Disk painting in 32-pixel tiles of bits: which disk last covers each pixel, the
redundant-anchor pass of the medial axis built on it, and the thinning's capped counts.

A row of a tile is one int64 word (32 bits used), so a disk paints a tile row in one
step and skips the pixels already painted through a union-find over the tiles.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._digital import disk_half_width, find_root, isqrt
from ._disk_counts import BLOCK, with_blocks

__all__ = ["TILE", "capped_coverage", "drop_redundant_anchors", "last_cover"]


# Side of the square tiles :func:`last_cover` works in: 32 pixels, one int64 word holds
# a tile's row as 32 bits (the other 32 stay clear, so no arithmetic ever overflows).
TILE = 32
_DE_BRUIJN = np.array(
    [
        0,
        1,
        28,
        2,
        29,
        14,
        24,
        3,
        30,
        22,
        20,
        15,
        25,
        17,
        4,
        8,
        31,
        27,
        13,
        23,
        21,
        19,
        16,
        7,
        26,
        12,
        18,
        6,
        11,
        5,
        10,
        9,
    ],
    dtype=np.int64,
)


@njit(cache=True, inline="always")
def _bit_index(low) -> int:
    """Position of the one set bit of ``low`` (a power of two below 2**32)."""
    return _DE_BRUIJN[((low * 0x077CB531) & 0xFFFFFFFF) >> 27]


@njit(cache=True, inline="always")
def _top_bit(word) -> int:
    """Position of the highest set bit of ``word`` (0 < word < 2**32)."""
    word |= word >> 1
    word |= word >> 2
    word |= word >> 4
    word |= word >> 8
    word |= word >> 16
    return _bit_index((word + 1) >> 1)


@njit(cache=True, inline="always")
def _bits(a, e) -> int:
    """Bits ``a`` to ``e`` set (0 <= a <= e <= 31)."""
    return ((1 << (e + 1)) - 1) ^ ((1 << a) - 1)


@njit(cache=True, inline="always")
def _next_busy(busy):
    """Per row of tiles, the next tile (at or after each) with a bit left, the row's end
    ``tw`` past the last: a skip list whose entries all point at a busy tile."""
    th, tw = busy.shape
    tnxt = np.empty((th, tw + 1), dtype=np.int32)
    for ty in range(th):
        for tx in range(tw + 1):
            tnxt[ty, tx] = tx if tx == tw or busy[ty, tx] else tx + 1
    for ty in range(th):  # compress: every entry points at a busy tile (or the end)
        for tx in range(tw - 1, -1, -1):
            tnxt[ty, tx] = tnxt[ty, tnxt[ty, tx]] if tnxt[ty, tx] != tx else tx
    return tnxt


@njit(cache=True, inline="always")
def _rows_reached(ys, cols_left, ty, x0, r, c, v):
    """Of the rows ``ys`` (bits) of the tile at row ``ty`` and column ``x0``, whose bits
    left lie in the columns ``cols_left`` (bits), those where the disk ``(r, c, v)`` can
    reach them: none if the disk misses the box of the bits left (most tiles a disk
    meets have their bits elsewhere), else the rows where it reaches the box's columns."""
    if not ys:
        return ys
    ya = ty * TILE + _bit_index(ys & -ys)
    ye = ty * TILE + _top_bit(ys)
    xa = x0 + _bit_index(cols_left & -cols_left)
    xe = x0 + _top_bit(cols_left)
    dy = ya - r if r < ya else (r - ye if r > ye else 0)
    dx = xa - c if c < xa else (c - xe if c > xe else 0)
    if dy * dy + dx * dx >= v:
        return 0
    reach = isqrt(v - 1 - dx * dx)
    return ys & _bits(
        max(r - reach, ty * TILE) - ty * TILE,
        min(r + reach, ty * TILE + TILE - 1) - ty * TILE,
    )


@njit(cache=True, inline="always")  # called from compiled code and from tests: see coverage
def last_cover(inside, rows, cols, r2s) -> np.ndarray:
    """For every pixel, the largest ``k`` whose disk ``(rows[k], cols[k], r2s[k])``
    covers it, -1 where none does.

    ``inside`` (bool, the grid's shape) must hold every pixel a disk covers: the shape,
    for its own maximal disks.

    Disks are painted last to first, each onto the pixels no later disk took. Most disks
    of a large shape lie where later (larger) disks have painted everything already, so
    the work is organised to cost the pixels painted, not the disks' size. The pixels
    still to paint are a bitmap, one 32-bit word per row of a ``TILE`` × ``TILE`` tile,
    and each tile keeps a 32-bit mask of its rows with a bit left. A disk walks its rows
    of tiles (one step each); in each, a union-find skips the tiles with nothing left,
    and in the others it looks only at the rows with a bit left, painting a row's run
    with one mask. A disk that paints nothing then costs about one step per row of tiles
    plus one per tile it meets that is not yet full.
    """
    shape_h, shape_w = inside.shape
    last = np.full((shape_h, shape_w), -1, dtype=np.int32)
    th, tw = (shape_h + TILE - 1) // TILE, (shape_w + TILE - 1) // TILE
    todo = np.zeros((shape_h, tw), dtype=np.int64)  # bit i of [y, t]: pixel (y, 32 t + i)
    busy = np.zeros((th, tw), dtype=np.int64)  # bit i of [s, t]: row 32 s + i of a tile has one
    across = np.zeros((th, tw), dtype=np.int64)  # columns of a tile with a bit left (or more)
    for y in range(shape_h):
        for x in range(shape_w):
            if inside[y, x]:
                todo[y, x // TILE] |= 1 << (x % TILE)
                busy[y // TILE, x // TILE] |= 1 << (y % TILE)
                across[y // TILE, x // TILE] |= 1 << (x % TILE)
    tnxt = _next_busy(busy)
    for k in range(rows.size - 1, -1, -1):
        r, c, v = rows[k], cols[k], r2s[k]
        h = isqrt(v - 1)
        for ty in range((r - h) // TILE, (r + h) // TILE + 1):
            y0, y1 = max(r - h, ty * TILE), min(r + h, ty * TILE + TILE - 1)
            # the widest row of the disk within this row of tiles
            wide = disk_half_width(v, min(max(r, y0), y1) - r)
            trow = tnxt[ty]
            span = _bits(y0 - ty * TILE, y1 - ty * TILE)
            tx = find_root(trow, (c - wide) // TILE)
            while tx <= (c + wide) // TILE:
                x0 = tx * TILE
                ys = _rows_reached(busy[ty, tx] & span, across[ty, tx], ty, x0, r, c, v)
                painted = False
                while ys:
                    low = ys & -ys
                    ys ^= low
                    y = ty * TILE + _bit_index(low)
                    w = disk_half_width(v, y - r)
                    a, e = max(c - w, x0), min(c + w, x0 + TILE - 1)
                    if a > e:
                        continue
                    paint = todo[y, tx] & _bits(a - x0, e - x0)
                    if paint == 0:
                        continue
                    painted = True
                    todo[y, tx] ^= paint
                    if todo[y, tx] == 0:
                        busy[ty, tx] ^= low
                    while paint:
                        bit = paint & -paint
                        paint ^= bit
                        last[y, x0 + _bit_index(bit)] = k
                if painted:  # the columns box again, from the rows left
                    cols_left = 0
                    rest = busy[ty, tx]
                    while rest:
                        low = rest & -rest
                        rest ^= low
                        cols_left |= todo[ty * TILE + _bit_index(low), tx]
                    across[ty, tx] = cols_left
                if busy[ty, tx] == 0:
                    trow[tx] = tx + 1
                tx = find_root(trow, tx + 1)
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


@njit(cache=True, inline="always")  # called from compiled code and from tests: see coverage
def capped_coverage(inside, rows, cols, r2s, cap: int):
    """:func:`coverage` with every count above ``cap`` lowered to ``cap``.

    The thinning asks only which pixels one disk alone covers, and removes few disks:
    after ``j`` removals a count stored as ``cap`` is still at least ``cap - j``, so while
    ``j <= cap - 2`` the pixels counted 1 are exactly those covered once. Most of a
    large shape is covered by far more than ``cap`` disks, so the counting is organised
    as :func:`last_cover`'s painting: one bitmap a level (the pixels covered ``l`` times,
    ``l < cap``), tiles whose pixels all reached ``cap`` are skipped, and a disk costs
    about one step per row of tiles plus the tiles it meets that are not yet full,
    instead of its height. ``inside`` (bool, the grid's shape) must hold every pixel a
    disk covers.

    Returns the arrays of :func:`coverage` (the same block layout).
    """
    shape_h, shape_w = inside.shape
    th, tw = (shape_h + TILE - 1) // TILE, (shape_w + TILE - 1) // TILE
    level = np.zeros((shape_h, tw, cap), dtype=np.int64)  # [y, t, l]: pixels covered l times
    todo = np.zeros((shape_h, tw), dtype=np.int64)  # pixels below the cap
    busy = np.zeros((th, tw), dtype=np.int64)
    across = np.zeros((th, tw), dtype=np.int64)
    for y in range(shape_h):
        for x in range(shape_w):
            if inside[y, x]:
                todo[y, x // TILE] |= 1 << (x % TILE)
                busy[y // TILE, x // TILE] |= 1 << (y % TILE)
                across[y // TILE, x // TILE] |= 1 << (x % TILE)
    for y in range(shape_h):
        for t in range(tw):
            level[y, t, 0] = todo[y, t]
    tnxt = _next_busy(busy)
    # largest disks first: they fill the interior's tiles, which the many smaller disks
    # then skip (the counts do not depend on the order)
    for k in np.argsort(-r2s):
        r, c, v = rows[k], cols[k], r2s[k]
        h = isqrt(v - 1)
        for ty in range((r - h) // TILE, (r + h) // TILE + 1):
            y0, y1 = max(r - h, ty * TILE), min(r + h, ty * TILE + TILE - 1)
            wide = disk_half_width(v, min(max(r, y0), y1) - r)
            trow = tnxt[ty]
            span = _bits(y0 - ty * TILE, y1 - ty * TILE)
            tx = find_root(trow, (c - wide) // TILE)
            while tx <= (c + wide) // TILE:
                x0 = tx * TILE
                ys = _rows_reached(busy[ty, tx] & span, across[ty, tx], ty, x0, r, c, v)
                full = False  # some pixel reached the cap
                while ys:
                    low = ys & -ys
                    ys ^= low
                    y = ty * TILE + _bit_index(low)
                    w = disk_half_width(v, y - r)
                    a, e = max(c - w, x0), min(c + w, x0 + TILE - 1)
                    if a > e:
                        continue
                    paint = todo[y, tx] & _bits(a - x0, e - x0)
                    if paint == 0:
                        continue
                    lv = level[y, tx]
                    top = lv[cap - 1] & paint  # these reach the cap
                    if top:
                        lv[cap - 1] ^= top
                        paint ^= top
                        todo[y, tx] ^= top
                        full = True
                    for lev in range(cap - 2, -1, -1):
                        if paint == 0:
                            break
                        moved = lv[lev] & paint
                        if moved:
                            lv[lev] ^= moved
                            lv[lev + 1] |= moved
                            paint ^= moved
                    if todo[y, tx] == 0:
                        busy[ty, tx] ^= low
                if full:  # the columns box again, from the rows left
                    cols_left = 0
                    rest = busy[ty, tx]
                    while rest:
                        low = rest & -rest
                        rest ^= low
                        cols_left |= todo[ty * TILE + _bit_index(low), tx]
                    across[ty, tx] = cols_left
                if busy[ty, tx] == 0:
                    trow[tx] = tx + 1
                tx = find_root(trow, tx + 1)
    nb = (shape_w + BLOCK - 1) // BLOCK
    cover = np.zeros((shape_h, nb * BLOCK), dtype=np.int32)
    for y in range(shape_h):
        for x in range(shape_w):
            if inside[y, x]:
                cover[y, x] = cap
        for t in range(tw):
            for lev in range(cap):
                bits = level[y, t, lev]
                while bits:
                    bit = bits & -bits
                    bits ^= bit
                    cover[y, t * TILE + _bit_index(bit)] = lev
    return with_blocks(cover)
