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
    neighbourhood_code,
)
from ._disk_counts import coverage, disk_loss, disk_remove
from ._edt import squared_distance
from ._last_cover import capped_coverage, drop_redundant_anchors
from ._maximal_disks import VECTOR_KIND, VECTORS, _anchors, _domination_table
from ._orientation import IDENTITY_ORIENTATION, oriented

__all__ = [
    "DEGREE",
    "SIMPLE",
    "MedialAxis",
    "medial_axis",
    "oriented_medial_axis",
    "squared_distance",
]


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
#: Capped counts from the first when the disks' heights exceed this many times the pixels.
_CAPPED_HEIGHTS = 12.0


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


def oriented_medial_axis(
    padded: np.ndarray, r2: np.ndarray, thinning_r2: np.ndarray | None = None
) -> MedialAxis:
    """:func:`medial_axis` of a shape already in its canonical orientation
    (:func:`skelprune.api.oriented`), without finding that orientation again.
    ``thinning_r2``, when given, orders and anchors the thinning instead of ``r2`` (the
    distances of a shape that goes on beyond the image); the radii stay ``r2``'s."""
    order = r2 if thinning_r2 is None else thinning_r2
    rows, cols = _medial_axis_pixels(np.asarray(padded, dtype=np.bool_), order)
    return MedialAxis(rows, cols, r2[rows, cols])


def _medial_axis_pixels(padded: np.ndarray, r2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows and columns of the medial axis, computed in the given frame."""
    need = _domination_table(r2)  # sized by the maximum: no need to select the shape
    return _axis_pixels(
        np.asarray(padded, dtype=np.bool_), r2, need, VECTORS, VECTOR_KIND, SIMPLE, DEGREE
    )


@njit(cache=True)
def _by_radius(fg, r2):
    """The pixels of ``fg``, smallest ``r2`` first, ties in raster order (a stable sort
    of the raster order by radius, as ``np.lexsort((cols, rows, r2[rows, cols]))``)."""
    rows, cols = _raster_pixels(fg)
    n = rows.size
    vals = np.empty(n, dtype=np.int64)
    top = 0
    for k in range(n):
        vals[k] = r2[rows[k], cols[k]]
        top = max(top, vals[k])
    if top > 4 * n + 1024:  # radii far apart (few pixels of a large blob): a merge sort
        order = np.argsort(vals, kind="mergesort")  # stable
        return rows[order], cols[order]
    # a stable counting sort by radius: the same order, without the n·log n
    start = np.zeros(top + 2, dtype=np.int64)
    for k in range(n):
        start[vals[k] + 1] += 1
    for v in range(top + 1):
        start[v + 1] += start[v]
    out_rows = np.empty(n, dtype=np.int64)
    out_cols = np.empty(n, dtype=np.int64)
    for k in range(n):
        slot = start[vals[k]]
        start[vals[k]] = slot + 1
        out_rows[slot], out_cols[slot] = rows[k], cols[k]
    return out_rows, out_cols


@njit(cache=True, inline="always")
def _raster_pixels(fg):
    """Rows and columns of the pixels of ``fg``, in raster order (``np.nonzero``)."""
    h, w = fg.shape
    n = 0
    for r in range(h):
        for c in range(w):
            if fg[r, c]:
                n += 1
    rows = np.empty(n, dtype=np.int64)
    cols = np.empty(n, dtype=np.int64)
    k = 0
    for r in range(h):
        for c in range(w):
            if fg[r, c]:
                rows[k], cols[k] = r, c
                k += 1
    return rows, cols


@njit(cache=True)
def _axis_pixels(padded, r2, need, vectors, kind, simple, degree):
    """:func:`_medial_axis_pixels`'s stages in one compiled call: the anchors (centres of
    maximal disks), the redundant ones dropped, the distance-ordered thinning, the
    thinning pass and the ends extended; returns the axis's rows and columns, in raster
    order."""
    anchor = _anchors(r2, need, vectors, kind)
    ar, ac = _by_radius(anchor, r2)
    drop_redundant_anchors(anchor, r2, ar, ac)
    fg = padded.copy()
    _ordered_thinning(fg, r2, anchor, simple)
    rows, cols = _by_radius(fg, r2)  # smallest radius first
    # The first cap on the thinning's counts: capped counts (see _thin) cost about the
    # pixels, exact ones the disks' heights; but a capped count is painted ten times
    # slower a pixel and is painted again after 2 and 14 removals. Capped only where the
    # heights outweigh the pixels by far (a blob's axis, few removals and disks of
    # hundreds of pixels' radius: the drawn heart at 2048 px, 15×), exact otherwise
    # (every kimia216 shape, at any scale). Either gives the same axis.
    heights = 0.0
    for k in range(rows.size):
        heights += 2.0 * np.sqrt(np.float64(r2[rows[k], cols[k]])) + 1.0
    capped = heights > _CAPPED_HEIGHTS * r2.size
    _thin(fg, r2, rows, cols, simple, degree, _FIRST_CAP if capped else 0)
    _extend_ends(fg, r2, degree)
    return _raster_pixels(fg)
