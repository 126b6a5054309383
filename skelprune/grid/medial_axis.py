"""Medial axis of a binary shape (docs/algorithm.md).

The axis is computed by distance-ordered homotopic thinning (Pudney 1998) anchored
at the centres of maximal disks, followed by a thinning pass that makes it one pixel
thin while preferring removals that lose no reconstructed area. The result keeps the
topology of the shape (8-connected foreground, 4-connected background) and, through
the anchors, reconstructs it almost exactly.

Disk convention (docs/algorithm.md): a point ``s`` with squared radius ``r2`` covers pixel
``p`` iff ``|p - s|**2 < r2``, where ``r2`` is the exact squared Euclidean distance
from ``s`` to the nearest background pixel. The union of the disks of all shape
pixels is then exactly the shape.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from numba import njit

from ..errors import InvalidImageError
from ._digital import (
    DEGREE,
    NEIGHBOURS,
    SIMPLE,
    heap_pop,
    heap_push,
    isqrt,
    neighbourhood_code,
)
from ._disk_counts import (
    capped_coverage,
    coverage,
    disk_loss,
    disk_remove,
    drop_redundant_anchors,
)
from ._orientation import IDENTITY_ORIENTATION, oriented

__all__ = [
    "DEGREE",
    "SIMPLE",
    "MedialAxis",
    "medial_axis",
    "oriented_medial_axis",
    "squared_distance",
]


def squared_distance(padded: np.ndarray) -> np.ndarray:
    """Exact squared Euclidean distance of each pixel to the nearest background pixel.

    Parameters
    ----------
    padded : (H, W) bool array
        The shape, with at least one background pixel all around.

    Returns
    -------
    (H, W) int64 array, 0 on the background.

    Examples
    --------
    >>> m = np.zeros((5, 5), bool); m[1:4, 1:4] = True
    >>> squared_distance(m)[2, 2]
    np.int64(4)
    """
    padded = np.asarray(padded, dtype=np.bool_)
    if padded.all():  # no background to measure from: scipy's convention
        from scipy import ndimage

        d = ndimage.distance_transform_edt(padded)
        return np.rint(d * d).astype(np.int64)
    return _squared_edt(padded)


@njit(cache=True)
def _squared_edt(fg: np.ndarray) -> np.ndarray:
    """Exact squared Euclidean distance transform in integers (Meijster, Roerdink &
    Hesselink 2000): the distance along each column, then the lower envelope of the
    parabolas ``(x - i)² + g(i)²`` along each row. Equal to the rounded square of
    scipy's exact transform, with a quarter of its memory and no floating point.
    """
    h, w = fg.shape
    inf = h + w  # more than any distance along a column
    out = np.empty((h, w), dtype=np.int64)
    for x in range(w):  # columns, walked row by row: contiguous in memory
        out[0, x] = 0 if not fg[0, x] else inf
    for y in range(1, h):
        for x in range(w):
            out[y, x] = 0 if not fg[y, x] else min(out[y - 1, x] + 1, inf)
    for y in range(h - 2, -1, -1):
        for x in range(w):
            if out[y + 1, x] + 1 < out[y, x]:
                out[y, x] = out[y + 1, x] + 1
    g = np.empty(w, dtype=np.int64)
    s = np.empty(w, dtype=np.int64)  # columns whose parabola is on the envelope
    t = np.empty(w, dtype=np.int64)  # where each starts to be the lowest
    for y in range(h):
        for x in range(w):
            g[x] = out[y, x] * out[y, x]
        q = 0
        s[0] = 0
        t[0] = 0
        for u in range(1, w):
            while q >= 0 and (t[q] - s[q]) ** 2 + g[s[q]] > (t[q] - u) ** 2 + g[u]:
                q -= 1
            if q < 0:
                q = 0
                s[0] = u
            else:
                i = s[q]
                sep = 1 + (u * u - i * i + g[u] - g[i]) // (2 * (u - i))
                if sep < w:
                    q += 1
                    s[q] = u
                    t[q] = sep
        for u in range(w - 1, -1, -1):
            out[y, u] = (u - s[q]) ** 2 + g[s[q]]
            if u == t[q]:
                q -= 1
    return out


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


@njit(cache=True)
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


@njit(cache=True, inline="always")
def _enqueue(item, nxt, head, tail, used, p, level):
    """Append pixel ``p`` to the FIFO bucket ``level``; returns the next free slot."""
    item[used] = p
    nxt[used] = -1
    if tail[level] < 0:
        head[level] = used
    else:
        nxt[tail[level]] = used
    tail[level] = used
    return used + 1


@njit(cache=True)
def _ordered_thinning(fg, r2, anchor, simple) -> None:
    """Distance-ordered homotopic thinning in place: a bucket queue keyed by ``r2``.

    A pixel found not simple leaves the queue; it comes back (at the current level)
    when a neighbour is deleted, which is what keeps the order by distance exact.
    Each bucket is FIFO: first its initial pixels in raster order (a counting sort,
    contiguous, where linked-list appends scatter over memory), then the pixels
    queued again, in a linked list.
    """
    h, w = fg.shape
    n = h * w
    max_level = r2.max()
    flat = r2.ravel()
    anchored = anchor.ravel()  # once: ravel() inside the loop costs ~60 ns a pixel
    pix = fg.reshape(n)  # a view: deletions land in fg
    step = np.empty(8, dtype=np.int64)  # NEIGHBOURS as offsets in the flat array
    for i in range(8):
        step[i] = NEIGHBOURS[i, 0] * w + NEIGHBOURS[i, 1]
    start = np.zeros(max_level + 2, dtype=np.int64)
    for p in range(n):
        if flat[p] > 0 and not anchored[p]:
            start[flat[p] + 1] += 1
    for lvl in range(max_level + 1):
        start[lvl + 1] += start[lvl]
    fill = start[:-1].copy()
    initial = np.empty(start[max_level + 1], dtype=np.int64)
    queued = np.zeros(n, dtype=np.bool_)
    for p in range(n):
        if flat[p] > 0 and not anchored[p]:
            initial[fill[flat[p]]] = p
            fill[flat[p]] += 1
            queued[p] = True
    cap = 8 * n + 1  # each deletion re-queues at most 8 neighbours
    # uninitialised: _enqueue writes a slot before it is read, and untouched pages
    # of these large buffers then cost nothing
    nxt = np.empty(cap, dtype=np.int64)
    item = np.empty(cap, dtype=np.int64)
    head = np.full(max_level + 1, -1, dtype=np.int64)
    tail = np.full(max_level + 1, -1, dtype=np.int64)
    used = 0
    for lvl in range(max_level + 1):
        k = start[lvl]
        while True:
            if k < start[lvl + 1]:
                p = initial[k]
                k += 1
            elif head[lvl] >= 0:
                slot = head[lvl]
                head[lvl] = nxt[slot]
                if head[lvl] < 0:
                    tail[lvl] = -1
                p = item[slot]
            else:
                break
            queued[p] = False
            if not pix[p]:
                continue
            code = 0  # neighbourhood_code, on the flat array: no division a pixel
            for i in range(8):
                if pix[p + step[i]]:
                    code |= 1 << i
            if not simple[code]:
                continue
            pix[p] = False
            for i in range(8):
                q = p + step[i]
                if pix[q] and not queued[q] and not anchored[q]:
                    used = _enqueue(item, nxt, head, tail, used, q, max(flat[q], lvl))
                    queued[q] = True


#: The thinning's first cap on the counts, and the largest before exact counts.
_FIRST_CAP = 4
_LAST_CAP = 64


def thinning_cap(r2s: np.ndarray, pixels: int) -> int:
    """The first cap on the thinning's counts for disks ``r2s`` on a grid of ``pixels``.

    Capped counts (see :func:`_thin`) cost about the pixels, exact ones the disks'
    heights: capped where the heights outweigh the pixels (a blob's axis, few removals
    and disks of hundreds of pixels' radius), exact otherwise.
    """
    heights = float(np.sum(2.0 * np.sqrt(r2s.astype(np.float64)) + 1.0))
    return _FIRST_CAP if heights > pixels else 0


@njit(cache=True)
def _counts(inside, rows, cols, r2s, cap):
    """The thinning's disk counts: capped at ``cap`` (:func:`capped_coverage`), exact if 0."""
    if cap:
        return capped_coverage(inside, rows, cols, r2s, cap)
    return coverage(inside.shape[0], inside.shape[1], rows, cols, r2s)


@njit(cache=True)
def _thin(fg, r2, rows, cols, simple, degree, cap) -> None:
    """Make the anchored skeleton one pixel thin.

    Removes simple pixels that are not endpoints, the one losing the fewest
    reconstructed pixels first (ties: smaller radius, then the given order). Removals
    only lower the coverage, so a pixel's loss never decreases: a min-heap with lazy
    re-evaluation of the popped key gives exactly that greedy order.

    The counts are capped at ``cap`` (0: exact counts), raised (by 4×, then exact)
    and remade from the disks left whenever the removals since they were made would
    reach ``cap - 1``: the losses are the same either way (:func:`capped_coverage`).
    """
    r2s = np.empty(rows.size, dtype=np.int64)
    for k in range(rows.size):
        r2s[k] = r2[rows[k], cols[k]]
    inside = r2 > 0
    cover, bmin, bcnt, lazy = _counts(inside, rows, cols, r2s, cap)
    removed = 0  # removals since the counts were made
    n = rows.size
    rank = np.full(fg.shape, -1, dtype=np.int32)  # int32: 64 MB less at 4096 px
    for k in range(n):
        rank[rows[k], cols[k]] = k
    big = n + 1
    heap = np.empty(9 * n + 1, dtype=np.int64)
    size = 0
    inheap = np.zeros(n, dtype=np.bool_)
    for k in range(n):
        code = neighbourhood_code(fg, rows[k], cols[k])
        if degree[code] >= 2 and simple[code]:
            loss = disk_loss(cover, bmin, bcnt, lazy, rows[k], cols[k], r2s[k])
            size = heap_push(heap, size, loss * big + k)
            inheap[k] = True
    while size > 0:
        key, size = heap_pop(heap, size)
        k = key % big
        inheap[k] = False
        r, c = rows[k], cols[k]
        if not fg[r, c]:
            continue
        code = neighbourhood_code(fg, r, c)
        if degree[code] < 2 or not simple[code]:
            continue  # comes back when a neighbour changes
        v = r2[r, c]
        loss = disk_loss(cover, bmin, bcnt, lazy, r, c, v)
        if loss > key // big:
            size = heap_push(heap, size, loss * big + k)
            inheap[k] = True
            continue
        if cap and removed + 1 > cap - 2:  # capped counts would stop being exact
            cap = cap * 4 if cap * 4 <= _LAST_CAP else 0
            live = np.array([j for j in range(n) if fg[rows[j], cols[j]]], dtype=np.int64)
            cover, bmin, bcnt, lazy = _counts(inside, rows[live], cols[live], r2s[live], cap)
            removed = 0
        fg[r, c] = False
        disk_remove(cover, bmin, bcnt, lazy, r, c, v)
        removed += 1
        for i in range(8):
            rr, cc = r + NEIGHBOURS[i, 0], c + NEIGHBOURS[i, 1]
            q = rank[rr, cc]
            if q < 0 or not fg[rr, cc] or inheap[q]:
                continue
            qcode = neighbourhood_code(fg, rr, cc)
            if degree[qcode] >= 2 and simple[qcode]:
                qloss = disk_loss(cover, bmin, bcnt, lazy, rr, cc, r2s[q])
                size = heap_push(heap, size, qloss * big + q)
                inheap[q] = True


@njit(cache=True)
def _extend_ends(fg, r2, degree) -> None:
    """Extend every endpoint down the distance map until it reaches the boundary.

    docs/algorithm.md: end branches of ``M`` reach the boundary. A discrete centre of maximal
    disk can sit a few pixels inside (a rounded end has several); its branch then
    stops short. Each step goes to the neighbour of least ``r2`` (axial first on
    ties) that touches no other axis pixel, so topology and thinness are kept and
    reconstruction can only grow. Axes without a junction (a single path) are left
    alone: their ends are the shape's own, not branches to prune.
    """
    rows, cols = np.nonzero(fg)
    has_junction = False
    for k in range(rows.size):
        if degree[neighbourhood_code(fg, rows[k], cols[k])] >= 3:
            has_junction = True
            break
    if not has_junction:
        return
    for k in range(rows.size):
        r, c = rows[k], cols[k]
        if degree[neighbourhood_code(fg, r, c)] != 1:
            continue
        while r2[r, c] > 2:
            best_r, best_c, best_v = -1, -1, r2[r, c]
            for i in (1, 3, 5, 7, 0, 2, 4, 6):  # axial neighbours first
                rr, cc = r + NEIGHBOURS[i, 0], c + NEIGHBOURS[i, 1]
                v = r2[rr, cc]
                if fg[rr, cc] or v == 0 or v >= best_v:
                    continue
                # the new pixel may touch the current end only
                alone = True
                for j in range(8):
                    qr, qc = rr + NEIGHBOURS[j, 0], cc + NEIGHBOURS[j, 1]
                    if (qr != r or qc != c) and fg[qr, qc]:
                        alone = False
                        break
                if alone:
                    best_r, best_c, best_v = rr, cc, v
            if best_r < 0:
                break
            fg[best_r, best_c] = True
            r, c = best_r, best_c


@dataclass(frozen=True)
class MedialAxis:
    """Medial axis of one shape, in the frame of the padded array it was computed in.

    Attributes
    ----------
    rows, cols : (n,) int64
        Pixel coordinates of the axis points, in raster order.
    r2 : (n,) int64
        Squared radius of each point (exact squared distance to the background).
    """

    rows: np.ndarray
    cols: np.ndarray
    r2: np.ndarray

    @property
    def radius(self) -> np.ndarray:
        return np.sqrt(self.r2.astype(np.float64))

    def __len__(self) -> int:
        return int(self.rows.size)


def medial_axis(padded: np.ndarray, r2: np.ndarray | None = None) -> MedialAxis:
    """Medial axis of a shape given with a background border.

    The axis is computed in the shape's canonical orientation
    (:mod:`skelprune.grid._orientation`) and mapped back, so that a shape turned by 90° or
    mirrored gets exactly the turned or mirrored axis.

    Parameters
    ----------
    padded : (H, W) bool array
        One 8-connected shape; every border pixel must be background.
    r2 : (H, W) int64 array, optional
        Its squared distance transform, if already computed.

    Returns
    -------
    MedialAxis

    Raises
    ------
    InvalidImageError
        When a border pixel belongs to the shape (pad it first, as
        :func:`skelprune.api.components` does).

    Examples
    --------
    >>> m = np.zeros((9, 15), bool); m[2:7, 2:13] = True
    >>> ma = medial_axis(m)
    >>> sorted(set(ma.rows.tolist()))[:1]
    [4]
    >>> t = medial_axis(np.ascontiguousarray(m.T))
    >>> bool(np.array_equal(np.sort(t.rows * 9 + t.cols), np.sort(ma.cols * 9 + ma.rows)))
    True
    """
    padded = np.asarray(padded, dtype=bool)
    if padded[0].any() or padded[-1].any() or padded[:, 0].any() or padded[:, -1].any():
        # the kernels look one pixel beyond every shape pixel, without bounds checks
        raise InvalidImageError(
            "the shape touches the array border: pad it with one background pixel first"
        )
    if r2 is None:
        r2 = squared_distance(padded)
    seen, o = oriented(padded)
    if o == IDENTITY_ORIENTATION:
        return oriented_medial_axis(padded, r2)
    rows, cols = _medial_axis_pixels(seen, np.ascontiguousarray(o.apply(r2)))
    rows, cols = o.points_back(rows, cols, seen.shape)
    order = np.argsort(rows * padded.shape[1] + cols)  # raster order
    rows, cols = rows[order], cols[order]
    return MedialAxis(rows, cols, r2[rows, cols])


def oriented_medial_axis(padded: np.ndarray, r2: np.ndarray) -> MedialAxis:
    """:func:`medial_axis` of a shape already in its canonical orientation
    (:func:`skelprune.api.oriented`), without finding that orientation again."""
    rows, cols = _medial_axis_pixels(np.asarray(padded, dtype=np.bool_), r2)
    return MedialAxis(rows, cols, r2[rows, cols])


def _medial_axis_pixels(padded: np.ndarray, r2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows and columns of the medial axis, computed in the given frame."""
    need = _domination_table(r2)  # sized by the maximum: no need to select the shape
    anchor = _anchors(r2, need, VECTORS, VECTOR_KIND)
    ar, ac = np.nonzero(anchor)
    order = np.lexsort((ac, ar, r2[ar, ac]))
    drop_redundant_anchors(anchor, r2, ar[order].astype(np.int64), ac[order].astype(np.int64))
    fg = padded.copy()
    _ordered_thinning(fg, r2, anchor, SIMPLE)
    rows, cols = np.nonzero(fg)
    order = np.lexsort((cols, rows, r2[rows, cols]))  # smallest radius first
    rows, cols = rows[order].astype(np.int64), cols[order].astype(np.int64)
    _thin(fg, r2, rows, cols, SIMPLE, DEGREE, thinning_cap(r2[rows, cols], r2.size))
    _extend_ends(fg, r2, DEGREE)
    rows, cols = np.nonzero(fg)
    return rows.astype(np.int64), cols.astype(np.int64)
