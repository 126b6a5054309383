"""Reconstruction of a shape from skeleton disks, and its area term (docs/algorithm.md).

Besides the plain reconstruction, :class:`Coverage` keeps the area each owner (a branch
or a junction cluster) alone covers with its disks, the area its removal would lose,
exactly up to date. Each owner's disks are held as one union, a set of row runs
(:mod:`skelprune.grid._intervals`), and the shape is cut into square tiles: a tile that two
owners cover whole holds no pixel with fewer than two owners, so it is only counted
(how many owners cover it whole), and its pixels are looked at once that count falls
below two. Work then follows the pixels near the owners' edges and the shape's
boundary, not the owners' areas, which on a blob-like shape are huge and pile up.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._digital import disk_half_width, isqrt
from ._disk_counts import last_cover
from ._intervals import owner_runs, union

__all__ = [
    "COVER_TILE",
    "Coverage",
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
    (:func:`~skelprune.grid._disk_counts.last_cover`), so a disk costs about its height in
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


# Coverage counts owners, not disks: each owner (a branch, or a junction cluster) is the
# union of its disks, a run set (skelprune.grid._intervals), held in one growing buffer
# (``buf``; owner ``b``'s runs are ``buf[lo[b]:hi[b]]``). Per-pixel counts live in tiles
# (``c``, ``s``: tile-major, so that a tile never looked at costs no memory), and only
# in the tiles that are "open" (``opened``); a closed tile has ``full[t] >= 2`` owners
# that cover it whole, so none of its pixels has fewer than two owners. Each owner also
# lists the tiles it meets (``tiles``: tile * 2 + 1 if it covers the tile whole).

#: Side of the square tiles of :class:`Coverage`.
COVER_TILE = 32


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


@njit(cache=True, inline="always")
def _find(alias, b):
    """The owner label ``b`` is now part of (labels merge into others)."""
    root = b
    while alias[root] != root:
        root = alias[root]
    while alias[b] != root:
        alias[b], b = root, alias[b]
    return root


@njit(cache=True)
def _open(t, tile, tw, mask, buf, lo, hi, start, owners, alias, alive, stamp, c, s, excl):
    """Count the pixels of tile ``t`` (every owner meeting it, painted); credit the
    pixels with one owner to it, and return those of the shape with none."""
    ty, tx = t // tw, t % tw
    y0, x0 = ty * tile, tx * tile
    ct, st = c[t], s[t]
    for j in range(start[t], start[t + 1]):
        b = _find(alias, owners[j])
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
            row_c, row_s = ct[buf[i, 0] - y0], st[buf[i, 0] - y0]
            for q in range(a - x0, e - x0 + 1):
                row_c[q] += 1
                row_s[q] += b
            i += 1
    lost = 0
    h, w = mask.shape
    for y in range(y0, min(y0 + tile, h)):
        row_c, row_s, row_m = ct[y - y0], st[y - y0], mask[y]
        for x in range(x0, min(x0 + tile, w)):
            n = row_c[x - x0]
            if n == 1:
                excl[row_s[x - x0]] += 1
            elif n == 0 and row_m[x]:
                lost += 1
    return lost


@njit(cache=True)
def _open_thin_tiles(
    tile, tw, mask, buf, lo, hi, start, owners, alias, alive, stamp, c, s, excl, full, opened
):
    lost = 0
    for t in range(full.size):
        if full[t] < 2:
            opened[t] = True
            lost += _open(
                t, tile, tw, mask, buf, lo, hi, start, owners, alias, alive, stamp, c, s, excl
            )
    return lost


@njit(cache=True)
def _remove_owner(
    old,
    tile,
    tw,
    mask,
    buf,
    lo,
    hi,
    tiles,
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
):
    """Take owner ``old`` off the pixels of its run set; return the pixels left uncovered.

    In open tiles each pixel is visited once (a run set is disjoint), so the pixels left
    with one owner are credited to it at once; a closed tile loses one owner covering it
    whole, if ``old`` was one, and is opened when fewer than two are left.
    """
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
                lost += _open(
                    t, tile, tw, mask, buf, lo, hi, start, owners, alias, alive, stamp, c, s, excl
                )
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
def _merge_tiles(
    out,
    m,
    old,
    new,
    tile,
    tw,
    mask,
    buf,
    lo,
    hi,
    tiles,
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
):
    """The tile list of ``new`` after it absorbed ``old``, written to ``out[m:]``; a closed
    tile both covered whole loses one such owner (and opens when fewer than two are
    left). Returns the new end of ``out`` and the pixels left uncovered (none: a merge
    uncovers nothing, but opening a tile counts its pixels)."""
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
                    lost += _open(
                        t,
                        tile,
                        tw,
                        mask,
                        buf,
                        lo,
                        hi,
                        start,
                        owners,
                        alias,
                        alive,
                        stamp,
                        c,
                        s,
                        excl,
                    )
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
    lost = _open_thin_tiles(
        tile, tw, mask, runs, lo, hi, start, owners, alias, alive, stamp, c, s, excl, full, opened
    )
    return (
        runs,
        lo,
        hi,
        tiles,
        tlo,
        thi,
        start,
        owners,
        full,
        alias,
        alive,
        stamp,
        opened,
        excl,
        lost,
    )


@njit(cache=True)
def _merge(
    old,
    new,
    mlo,
    mhi,
    tile,
    tw,
    mask,
    buf,
    lo,
    hi,
    tiles,
    tused,
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
):
    """Owner ``old`` joins owner ``new``, whose merged runs are ``buf[mlo:mhi]``: the
    pixels of the open tiles, then the tiles (written from ``tiles[tused:]``). Returns
    the new end of ``tiles`` and the pixels left uncovered by the tiles it opened."""
    excl[new] += _merge_pixels(
        c, s, opened, tile, tw, buf[lo[old] : hi[old]], buf[lo[new] : hi[new]], old, new
    )
    lo[new], hi[new] = mlo, mhi
    alias[old] = new
    alive[old] = False
    end, lost = _merge_tiles(
        tiles,
        tused,
        old,
        new,
        tile,
        tw,
        mask,
        buf,
        lo,
        hi,
        tiles,
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
    tlo[new], thi[new] = tused, end
    thi[old] = tlo[old]
    hi[old] = lo[old]
    return end, lost


class Coverage:
    """Incremental coverage of a shape by labelled skeleton disks.

    Points with one label form one owner (a branch or a junction cluster); a pixel
    counts its distinct owners ``c`` and the sum ``s`` of their labels, so it has a
    single owner iff ``c == 1``, and that owner is ``s``. Owners are removed and merged
    whole, by label (:meth:`remove_label`, :meth:`merge_label`): a branch's points always
    share its label, and a merge moves whole owners.

    The counts are kept only in the tiles (``tile`` × ``tile`` pixels) that fewer than
    two owners cover whole: elsewhere no pixel can have fewer than two owners, so the
    tile only counts its whole-covering owners, and is opened (its pixels counted from
    the owners' runs) once that count falls below two.

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
    tile : int
        Side of the tiles, default :data:`COVER_TILE`.

    Attributes
    ----------
    lost : int
        Pixels of ``D`` no disk covers, ``Λ(D \\ R(S))``.
    exclusive : (n_labels,) int64
        Pixels covered by the disks of one label only: what removing it would lose.
        Exact for the labels still in use; stale for removed or merged ones.

    Examples
    --------
    Two disjoint disks of 13 pixels, labels 1 and 2, in a 9 x 12 shape:

    >>> cov = Coverage(np.ones((9, 12), bool), np.array([4, 4]), np.array([3, 8]),
    ...                np.array([5, 5]), np.array([1, 2]), 3)
    >>> cov.exclusive.tolist(), cov.lost
    ([0, 13, 13], 82)
    >>> cov.merge_label(2, 1)
    >>> cov.exclusive[1], cov.remove_label(1), cov.lost
    (np.int64(26), 26, 108)
    """

    def __init__(self, mask, rows, cols, r2, labels, n_labels: int, tile: int = COVER_TILE) -> None:
        self.mask = np.ascontiguousarray(mask, dtype=np.bool_)
        h, w = self.mask.shape
        self.tile = tile
        self.th, self.tw = -(-h // tile), -(-w // tile)
        n_tiles = self.th * self.tw
        # zeroed lazily by the system: the pages of tiles never opened are never touched
        self.c = np.zeros((n_tiles, tile, tile), np.int32)
        self.s = np.zeros((n_tiles, tile, tile), np.int64)
        (
            self.buf,
            self.lo,
            self.hi,
            self.tiles,
            self.tlo,
            self.thi,
            self.start,
            self.owners,
            self.full,
            self.alias,
            self.alive,
            self.stamp,
            self.opened,
            self.exclusive,
            lost,
        ) = _build(
            np.asarray(rows, np.int64),
            np.asarray(cols, np.int64),
            np.asarray(r2, np.int64),
            np.asarray(labels, np.int64),
            n_labels,
            tile,
            self.tw,
            self.mask,
            self.c,
            self.s,
        )
        self.used, self.tused = self.buf.shape[0], self.tiles.size
        self.lost = int(lost)

    def _state(self) -> tuple:
        return (
            self.buf,
            self.lo,
            self.hi,
            self.start,
            self.owners,
            self.alias,
            self.alive,
            self.stamp,
            self.c,
            self.s,
            self.exclusive,
        )

    def remove_label(self, old: int) -> int:
        """Remove the disks of all points labelled ``old``; returns the newly uncovered area.

        The pruning knows the label of the branch it removes, so no point is looked at.
        """
        buf, lo, hi, start, owners, alias, alive, stamp, c, s, excl = self._state()
        lost = int(
            _remove_owner(
                old,
                self.tile,
                self.tw,
                self.mask,
                buf,
                lo,
                hi,
                self.tiles,
                self.tlo,
                self.thi,
                start,
                owners,
                alias,
                alive,
                stamp,
                c,
                s,
                excl,
                self.full,
                self.opened,
            )
        )
        self.hi[old] = self.lo[old]
        self.thi[old] = self.tlo[old]
        self.lost += lost
        return lost

    def merge_label(self, old: int, new: int) -> None:
        """Give all points labelled ``old`` the label ``new``."""
        if old == new or self.hi[old] == self.lo[old]:
            return
        merged = union(self.buf[self.lo[new] : self.hi[new]], self.buf[self.lo[old] : self.hi[old]])
        if self.used + len(merged) > len(self.buf):
            bigger = np.empty((2 * (self.used + len(merged)), 3), np.int64)
            bigger[: self.used] = self.buf[: self.used]
            self.buf = bigger
        mlo = self.used
        self.buf[mlo : mlo + len(merged)] = merged
        self.used += len(merged)
        need = self.thi[old] - self.tlo[old] + self.thi[new] - self.tlo[new]
        if self.tused + need > self.tiles.size:
            bigger = np.empty(2 * (self.tused + need), np.int64)
            bigger[: self.tused] = self.tiles[: self.tused]
            self.tiles = bigger
        buf, lo, hi, start, owners, alias, alive, stamp, c, s, excl = self._state()
        self.tused, lost = _merge(
            old,
            new,
            mlo,
            self.used,
            self.tile,
            self.tw,
            self.mask,
            buf,
            lo,
            hi,
            self.tiles,
            self.tused,
            self.tlo,
            self.thi,
            start,
            owners,
            alias,
            alive,
            stamp,
            c,
            s,
            excl,
            self.full,
            self.opened,
        )
        self.lost += int(lost)

    def counts(self) -> np.ndarray:
        """Owners per pixel where the tiles are open, -1 in the closed ones (where every
        pixel has two owners or more): for checks."""
        h, w, t = self.mask.shape[0], self.mask.shape[1], self.tile
        grid = self.c.reshape(self.th, self.tw, t, t).transpose(0, 2, 1, 3)
        out = grid.reshape(self.th * t, self.tw * t).copy()
        shut = np.repeat(np.repeat(~self.opened.reshape(self.th, self.tw), t, 0), t, 1)
        out[shut] = -1
        return out[:h, :w]

    def uncovered(self) -> np.ndarray:
        """Flat indices (raster order) of the pixels of ``D`` no disk covers."""
        return np.flatnonzero(self.mask & (self.counts() == 0))
