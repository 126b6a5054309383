"""The tiled owner counts behind :class:`~skelprune.grid.coverage.Coverage` (compiled).

Used only by :mod:`skelprune.grid.coverage`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from ._digital import find_root
from ._intervals import owner_runs

# Coverage counts owners, not disks: each owner (a branch, or a junction cluster) is the
# union of its disks, a run set (skelprune.grid._intervals), held in one growing buffer
# (``buf``; owner ``b``'s runs are ``buf[lo[b]:hi[b]]``). Per-pixel counts live in tiles
# (``c``, ``s``: tile-major, so that a tile never looked at costs no memory), and only
# in the tiles that are "open" (``opened``); a closed tile has ``full[t] >= 2`` owners
# that cover it whole, so none of its pixels has fewer than two owners. Each owner also
# lists the tiles it meets (``tiles``: tile * 2 + 1 if it covers the tile whole).

#: Side of the square tiles of :class:`Coverage`.
COVER_TILE = 32


class TileState(NamedTuple):
    """What the tile kernels share, passed as one record: every array above but the two
    that grow and are passed beside it (``buf``, the owners' runs, and ``tiles``, their
    tile lists)."""

    tile: int
    tw: int
    mask: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    tlo: np.ndarray
    thi: np.ndarray
    start: np.ndarray
    owners: np.ndarray
    alias: np.ndarray
    alive: np.ndarray
    stamp: np.ndarray
    c: np.ndarray
    s: np.ndarray
    excl: np.ndarray
    full: np.ndarray
    opened: np.ndarray


@njit(cache=True)
def _grow_tiles(out, m, code):
    if m == out.size:
        bigger = np.empty(2 * out.size + 16, np.int64)
        bigger[:m] = out[:m]
        out = bigger
    out[m] = code
    return out, m + 1


@njit(cache=True)
def _owner_tiles(runs, offsets, tile, tw):
    """Per owner, the tiles its runs meet, as ``tile_id * 2 + whole`` sorted by tile."""
    n = offsets.size - 1
    out = np.empty(max(16, runs.shape[0]), np.int64)
    toff = np.zeros(n + 1, np.int64)
    seen = np.full(tw, -1, np.int64)  # group stamp of each column of tiles
    rows_whole = np.zeros(tw, np.int64)
    met = np.empty(tw, np.int64)
    m = 0
    group = 0
    for b in range(n):
        i = offsets[b]
        while i < offsets[b + 1]:
            ty = runs[i, 0] // tile
            k = 0
            while i < offsets[b + 1] and runs[i, 0] // tile == ty:
                a, e = runs[i, 1], runs[i, 2]
                for tx in range(a // tile, e // tile + 1):
                    if seen[tx] != group:
                        seen[tx] = group
                        rows_whole[tx] = 0
                        met[k] = tx
                        k += 1
                    if a <= tx * tile and e >= tx * tile + tile - 1:
                        rows_whole[tx] += 1  # a row has one run over a tile at most
                i += 1
            for tx in np.sort(met[:k]):
                out, m = _grow_tiles(out, m, (ty * tw + tx) * 2 + (rows_whole[tx] == tile))
            group += 1
        toff[b + 1] = m
    return out[:m].copy(), toff


@njit(cache=True)
def _tile_owners(tiles, toff, n_tiles):
    """The owners meeting each tile (CSR: ``owners[start[t]:start[t + 1]]``), and how
    many cover it whole."""
    start = np.zeros(n_tiles + 1, np.int64)
    full = np.zeros(n_tiles, np.int32)
    for j in range(tiles.size):
        start[(tiles[j] >> 1) + 1] += 1
        full[tiles[j] >> 1] += tiles[j] & 1
    for t in range(n_tiles):
        start[t + 1] += start[t]
    fill = start[:-1].copy()
    owners = np.empty(tiles.size, np.int64)
    for b in range(toff.size - 1):
        for j in range(toff[b], toff[b + 1]):
            t = tiles[j] >> 1
            owners[fill[t]] = b
            fill[t] += 1
    return start, owners, full


@njit(cache=True)
def _open(t, st, buf):
    """Count the pixels of tile ``t`` (every owner meeting it, painted); credit the
    pixels with one owner to it, and return those of the shape with none."""
    tile, tw, mask, lo, hi, start, owners, alias, alive, stamp, c, s, excl = (
        st.tile,
        st.tw,
        st.mask,
        st.lo,
        st.hi,
        st.start,
        st.owners,
        st.alias,
        st.alive,
        st.stamp,
        st.c,
        st.s,
        st.excl,
    )
    ty, tx = t // tw, t % tw
    y0, x0 = ty * tile, tx * tile
    ct, cs = c[t], s[t]
    for j in range(start[t], start[t + 1]):
        b = find_root(alias, owners[j])
        if not alive[b] or stamp[b] == t:
            continue
        stamp[b] = t
        # the first run at or below row y0 (runs are sorted by row)
        u, v = lo[b], hi[b]
        while u < v:
            mid = (u + v) // 2
            if buf[mid, 0] < y0:
                u = mid + 1
            else:
                v = mid
        i = u
        while i < hi[b] and buf[i, 0] < y0 + tile:
            a, e = max(buf[i, 1], x0), min(buf[i, 2], x0 + tile - 1)
            row_c, row_s = ct[buf[i, 0] - y0], cs[buf[i, 0] - y0]
            for q in range(a - x0, e - x0 + 1):
                row_c[q] += 1
                row_s[q] += b
            i += 1
    lost = 0
    h, w = mask.shape
    for y in range(y0, min(y0 + tile, h)):
        row_c, row_s, row_m = ct[y - y0], cs[y - y0], mask[y]
        for x in range(x0, min(x0 + tile, w)):
            n = row_c[x - x0]
            if n == 1:
                excl[row_s[x - x0]] += 1
            elif n == 0 and row_m[x]:
                lost += 1
    return lost


@njit(cache=True)
def _open_thin_tiles(st, buf):
    """Open every tile fewer than two owners cover whole; the shape's pixels they leave
    uncovered."""
    lost = 0
    for t in range(st.full.size):
        if st.full[t] < 2:
            st.opened[t] = True
            lost += _open(t, st, buf)
    return lost


@njit(cache=True)
def _remove_owner(old, st, buf, tiles):
    """Take owner ``old`` off the pixels of its run set; return the pixels left uncovered.

    In open tiles each pixel is visited once (a run set is disjoint), so the pixels left
    with one owner are credited to it at once; a closed tile loses one owner covering it
    whole, if ``old`` was one, and is opened when fewer than two are left.
    """
    tile, tw, lo, hi, tlo, thi, alive, c, s, excl, full, opened = (
        st.tile,
        st.tw,
        st.lo,
        st.hi,
        st.tlo,
        st.thi,
        st.alive,
        st.c,
        st.s,
        st.excl,
        st.full,
        st.opened,
    )
    lost = 0
    for i in range(lo[old], hi[old]):
        r, a, e = buf[i, 0], buf[i, 1], buf[i, 2]
        ty = r // tile
        for tx in range(a // tile, e // tile + 1):
            t = ty * tw + tx
            if not opened[t]:
                continue
            x0 = tx * tile
            row_c, row_s = c[t, r - ty * tile], s[t, r - ty * tile]
            for q in range(max(a, x0) - x0, min(e, x0 + tile - 1) - x0 + 1):
                row_c[q] -= 1
                row_s[q] -= old
                n = row_c[q]
                if n == 0:
                    lost += 1
                elif n == 1:
                    excl[row_s[q]] += 1
    alive[old] = False
    for j in range(tlo[old], thi[old]):
        t = tiles[j] >> 1
        if tiles[j] & 1 and not opened[t]:
            full[t] -= 1
            if full[t] < 2:
                opened[t] = True
                lost += _open(t, st, buf)
    return lost


@njit(cache=True, inline="always")
def _merge_span(c, s, opened, tile, tw, r, a, e, both, old, d):
    """Pixels ``a..e`` of row ``r`` pass from owner ``old`` to owner ``old + d``, in the
    open tiles: where both cover them (``both``) they lose one owner, elsewhere they
    change label. Returns how many are left with that one owner."""
    single = 0
    ty = r // tile
    y = r - ty * tile
    for tx in range(a // tile, e // tile + 1):
        t = ty * tw + tx
        if not opened[t]:
            continue
        x0 = tx * tile
        row_c, row_s = c[t, y], s[t, y]
        for q in range(max(a, x0) - x0, min(e, x0 + tile - 1) - x0 + 1):
            if both:
                row_c[q] -= 1
                row_s[q] -= old
            else:
                row_s[q] += d
            if row_c[q] == 1:
                single += 1
    return single


@njit(cache=True)
def _merge_pixels(c, s, opened, tile, tw, moved, kept, old, new):
    """Owner ``old`` (run set ``moved``) becomes owner ``new`` (run set ``kept``), in the
    open tiles.

    Pixels both cover lose one owner; the others change label. Returns how many pixels
    of ``moved`` are left with the single owner ``new``: none was before, as ``old``
    covered them too.
    """
    single = 0
    d = new - old
    j = 0
    for i in range(moved.shape[0]):
        r, lo, hi = moved[i, 0], moved[i, 1], moved[i, 2]
        # The first run of kept not wholly before this one (kept is sorted too).
        while j < kept.shape[0] and (kept[j, 0] < r or (kept[j, 0] == r and kept[j, 2] < lo)):
            j += 1
        k = j
        q = lo
        while q <= hi:
            if k < kept.shape[0] and kept[k, 0] == r and kept[k, 1] <= q:
                # q lies in kept[k]: covered by both owners
                end = min(hi, kept[k, 2])
                single += _merge_span(c, s, opened, tile, tw, r, q, end, True, old, d)
                k += 1
            else:
                end = hi
                if k < kept.shape[0] and kept[k, 0] == r and kept[k, 1] <= hi:
                    end = kept[k, 1] - 1
                single += _merge_span(c, s, opened, tile, tw, r, q, end, False, old, d)
            q = end + 1
    return single


@njit(cache=True)
def _merge_tiles(out, m, old, new, st, buf, tiles):
    """The tile list of ``new`` after it absorbed ``old``, written to ``out[m:]``; a closed
    tile both covered whole loses one such owner (and opens when fewer than two are
    left). Returns the new end of ``out`` and the pixels left uncovered (none: a merge
    uncovers nothing, but opening a tile counts its pixels)."""
    tlo, thi, full, opened = st.tlo, st.thi, st.full, st.opened
    i, e_i = tlo[old], thi[old]
    j, e_j = tlo[new], thi[new]
    lost = 0
    while i < e_i or j < e_j:
        if j == e_j or (i < e_i and tiles[i] >> 1 < tiles[j] >> 1):
            out[m] = tiles[i]
            i += 1
        elif i == e_i or tiles[j] >> 1 < tiles[i] >> 1:
            out[m] = tiles[j]
            j += 1
        else:
            t = tiles[i] >> 1
            out[m] = tiles[i] | tiles[j]
            if tiles[i] & tiles[j] & 1 and not opened[t]:
                full[t] -= 1
                if full[t] < 2:
                    opened[t] = True
                    lost += _open(t, st, buf)
            i += 1
            j += 1
        m += 1
    return m, lost


@njit(cache=True)
def _build(rows, cols, r2, labels, n_labels, tile, tw, mask, c, s):
    """Everything :class:`Coverage` starts with, in one kernel (each kernel a fresh
    process loads from the cache costs it time). ``c`` and ``s`` come zeroed from the
    caller, whose allocation leaves the pages of tiles never opened untouched."""
    runs, offsets = owner_runs(rows, cols, r2, labels, n_labels)
    tiles, toff = _owner_tiles(runs, offsets, tile, tw)
    n_tiles = c.shape[0]
    start, owners, full = _tile_owners(tiles, toff, n_tiles)
    lo, hi = offsets[:-1].copy(), offsets[1:].copy()
    tlo, thi = toff[:-1].copy(), toff[1:].copy()
    alias = np.arange(n_labels)
    alive = np.ones(n_labels, np.bool_)
    stamp = np.full(n_labels, -1, np.int64)
    opened = np.zeros(n_tiles, np.bool_)
    excl = np.zeros(n_labels, np.int64)
    st = TileState(
        tile,
        tw,
        mask,
        lo,
        hi,
        tlo,
        thi,
        start,
        owners,
        alias,
        alive,
        stamp,
        c,
        s,
        excl,
        full,
        opened,
    )
    return runs, tiles, st, _open_thin_tiles(st, runs)


@njit(cache=True)
def _merge(old, new, mlo, mhi, tused, st, buf, tiles):
    """Owner ``old`` joins owner ``new``, whose merged runs are ``buf[mlo:mhi]``: the
    pixels of the open tiles, then the tiles (written from ``tiles[tused:]``). Returns
    the new end of ``tiles`` and the pixels left uncovered by the tiles it opened."""
    tile, tw, lo, hi, tlo, thi, alias, alive, c, s, excl, opened = (
        st.tile,
        st.tw,
        st.lo,
        st.hi,
        st.tlo,
        st.thi,
        st.alias,
        st.alive,
        st.c,
        st.s,
        st.excl,
        st.opened,
    )
    excl[new] += _merge_pixels(
        c, s, opened, tile, tw, buf[lo[old] : hi[old]], buf[lo[new] : hi[new]], old, new
    )
    lo[new], hi[new] = mlo, mhi
    alias[old] = new
    alive[old] = False
    end, lost = _merge_tiles(tiles, tused, old, new, st, buf, tiles)
    tlo[new], thi[new] = tused, end
    thi[old] = tlo[old]
    hi[old] = lo[old]
    return end, lost
