"""Disk coverage counted row by row: work per disk row, never per disk pixel.

A disk ``|p − s|² < r²`` is one run of pixels per row (``_digital.disk_half_width``). The
kernels here walk the rows top to bottom with the disks that reach the current row
(small buffers, in cache) and add their runs up with a difference array over the
runs' extent. Against painting every pixel of every disk, a row costs its runs plus the
columns the runs span, once: on a blob, where
hundreds of disks of hundreds of pixels' radius overlap, that is the difference between
the sum of the disks' areas and the area they cover.

Used by the tips' cut (:mod:`skelprune.grid.tips`) and the noise-floor choice
(:mod:`skelprune.pruning.choice`), which both keep ``c``: per pixel, how many disks of the
current skeleton cover it.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._digital import find_root, isqrt

__all__ = [
    "cover_counts",
    "cut_counts",
    "exclusive_losses",
    "last_losses",
    "uncover",
    "uncover_count",
]


@njit(cache=True)
def _by_top(rows, cols, r2, order, tag):
    """The disks in ``order`` (positions ``0 … n − 1``), each row's new disks listed.

    Returns the disks' centres, squared radii, tags and radii in rows, by position; the
    first row ``y0`` and the number of rows they span; and the positions of the disks
    whose top row is ``y0 + i``, ``ids[first[i] : first[i + 1]]``, ascending.
    """
    n = rows.size
    rr, qq, vv, tt = rows[order], cols[order], r2[order], tag[order]
    rad = np.empty(n, np.int64)
    y0, y1 = 0, -1
    if n:
        y0, y1 = np.iinfo(np.int64).max, np.iinfo(np.int64).min
    for i in range(n):
        rad[i] = isqrt(vv[i] - 1)
        y0 = min(y0, rr[i] - rad[i])
        y1 = max(y1, rr[i] + rad[i])
    nrow = y1 - y0 + 1
    first = np.zeros(nrow + 1, np.int64)
    for i in range(n):
        first[rr[i] - rad[i] - y0 + 1] += 1
    for i in range(nrow):
        first[i + 1] += first[i]
    ids = np.empty(n, np.int64)
    fill = first[:-1].copy()
    for i in range(n):
        top = rr[i] - rad[i] - y0
        ids[fill[top]] = i
        fill[top] += 1
    return rr, qq, vv, tt, rad, y0, nrow, first, ids


@njit(cache=True)
def _row(y, new, rr, qq, vv, tt, rad, active, tmp, na, lo, hi, t, run):
    """Row ``y``'s runs: the disks ``new`` starting here merged into ``active`` (kept in
    position order), those past their bottom row let go; each active disk's run goes
    into ``lo``, ``hi``, ``t`` (in position order) and into the difference array
    ``run``. Returns ``(active, tmp, n_runs, left, right)``, ``left … right`` the runs'
    extent."""
    if new.size:
        p, q, m = 0, 0, 0
        while p < na or q < new.size:
            if q >= new.size or (p < na and active[p] < new[q]):
                tmp[m] = active[p]
                p += 1
            else:
                tmp[m] = new[q]
                q += 1
            m += 1
        active, tmp, na = tmp, active, m
    m = 0
    left, right = np.iinfo(np.int64).max, np.iinfo(np.int64).min
    for p in range(na):
        j = active[p]
        dy = y - rr[j]
        if dy > rad[j]:
            continue  # past its bottom row
        active[m] = j
        dx = isqrt(vv[j] - 1 - dy * dy)  # strictly inside: dx² < r² − dy²
        lo[m], hi[m], t[m] = qq[j] - dx, qq[j] + dx, tt[j]
        run[lo[m]] += 1
        run[hi[m] + 1] -= 1
        left = min(left, lo[m])
        right = max(right, hi[m])
        m += 1
    return active, tmp, m, left, right


@njit(cache=True)
def cover_counts(h, w, rows, cols, r2):
    """How many disks ``|p − s|² < r²`` cover each pixel (``int32``, ``h × w``)."""
    c = np.zeros((h, w), np.int32)
    n = rows.size
    order = np.arange(n)
    rr, qq, vv, tt, rad, y0, nrow, first, ids = _by_top(rows, cols, r2, order, order)
    active, tmp = np.empty(n, np.int64), np.empty(n, np.int64)
    lo, hi, t = np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n, np.int64)
    run = np.zeros(w + 1, np.int32)
    na = 0
    for i in range(nrow):
        y = y0 + i
        new = ids[first[i] : first[i + 1]]
        active, tmp, na, left, right = _row(
            y, new, rr, qq, vv, tt, rad, active, tmp, na, lo, hi, t, run
        )
        if na == 0:
            continue
        acc = 0
        for x in range(left, right + 1):
            acc += run[x]
            run[x] = 0
            c[y, x] = acc
        run[right + 1] = 0
    return c


@njit(cache=True)
def _take_off(c, deep, rows, cols, r2, count):
    """Take the disks off ``c``; with ``count``, return how many ``deep`` pixels lost
    their last one."""
    n = rows.size
    order = np.arange(n)
    rr, qq, vv, tt, rad, y0, nrow, first, ids = _by_top(rows, cols, r2, order, order)
    active, tmp = np.empty(n, np.int64), np.empty(n, np.int64)
    lo, hi, t = np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n, np.int64)
    run = np.zeros(c.shape[1] + 1, np.int32)
    na, lost = 0, 0
    for i in range(nrow):
        y = y0 + i
        new = ids[first[i] : first[i + 1]]
        active, tmp, na, left, right = _row(
            y, new, rr, qq, vv, tt, rad, active, tmp, na, lo, hi, t, run
        )
        if na == 0:
            continue
        acc = 0
        for x in range(left, right + 1):
            acc += run[x]
            run[x] = 0
            if acc > 0:
                c[y, x] -= acc
                if count and c[y, x] == 0 and deep[y, x]:
                    lost += 1
        run[right + 1] = 0
    return lost


@njit(cache=True)
def uncover(c, rows, cols, r2):
    """Take the disks of these points off the counts ``c``."""
    _take_off(c, np.zeros((1, 1), np.bool_), rows, cols, r2, False)


@njit(cache=True)
def uncover_count(c, deep, rows, cols, r2):
    """Take these disks off the counts ``c``; return how many ``deep`` pixels lost their
    last one."""
    return _take_off(c, deep, rows, cols, r2, True)


@njit(cache=True)
def exclusive_losses(mask, c, rows, cols, r2, drop, n_drop):
    """Pixels of ``mask`` covered by these disks only, by the largest ``drop`` among them.

    ``loss[d]`` counts the pixels of ``mask`` whose covering disks (``c`` of them in all)
    are all among these and the largest drop index of which is ``d``: what dropping the
    disks with ``drop < k`` loses is ``loss[0] + … + loss[k − 1]``.

    Per row, the runs' count is compared with ``c`` over their extent; then the runs, in
    decreasing drop index, claim the open pixels they cover, skipping claimed ones with
    a union-find: each pixel is claimed once, by its largest drop index.
    """
    n = rows.size
    order = np.argsort(-drop, kind="mergesort")
    rr, qq, vv, tt, rad, y0, nrow, first, ids = _by_top(rows, cols, r2, order, drop)
    active, tmp = np.empty(n, np.int64), np.empty(n, np.int64)
    lo, hi, t = np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n, np.int64)
    w = c.shape[1]
    run = np.zeros(w + 1, np.int32)
    nxt = np.empty(w + 1, np.int32)
    loss = np.zeros(n_drop, np.int64)
    na = 0
    for i in range(nrow):
        y = y0 + i
        new = ids[first[i] : first[i + 1]]
        active, tmp, na, left, right = _row(
            y, new, rr, qq, vv, tt, rad, active, tmp, na, lo, hi, t, run
        )
        if na == 0:
            continue
        acc = 0
        for x in range(left, right + 1):
            acc += run[x]
            run[x] = 0
            # open: covered by these disks and by no other
            nxt[x] = x if acc > 0 and acc == c[y, x] and mask[y, x] else x + 1
        run[right + 1] = 0
        nxt[right + 1] = right + 1
        for j in range(na):  # decreasing drop index
            d = t[j]
            x = find_root(nxt, lo[j])
            while x <= hi[j]:
                loss[d] += 1
                nxt[x] = x + 1
                x = find_root(nxt, x + 1)
    return loss


@njit(cache=True)
def last_losses(mask, runs, offsets, n_drop):
    """Pixels of ``mask`` by the largest drop index among the disks covering them.

    ``runs``, ``offsets``: the union of the disks of each drop index ``0 … n_drop``
    (:func:`skelprune.grid._intervals.owner_runs` with the drop indices for labels;
    ``n_drop`` for the disks never dropped). ``loss[d]`` (``d < n_drop``) counts the pixels
    whose covering disks all have a drop index ``≤ d``, one of them ``d``: dropping the
    disks in the order of their index, what dropping those of index ``d`` uncovers.
    Returns ``loss`` and the pixels of ``mask`` covered in all.

    One pass for all the drops instead of one :func:`uncover_count` per drop: per row,
    the runs in decreasing drop index claim the pixels of ``mask`` they cover, skipping
    claimed ones with a union-find, so each pixel is claimed once, by its largest drop
    index. A drop's disks overlap row by row: a row holds one run of each drop or a few,
    not one per disk.
    """
    m = runs.shape[0]
    n_labels = offsets.size - 1
    label = np.empty(m, np.int64)
    for b in range(n_labels):
        for i in range(offsets[b], offsets[b + 1]):
            label[i] = b
    # by row, then by decreasing drop index: each pixel claimed by its largest
    order = np.argsort(runs[:, 0] * n_labels + (n_labels - 1 - label))
    nxt = np.empty(mask.shape[1] + 1, np.int32)
    loss = np.zeros(n_drop, np.int64)
    covered = 0
    i = 0
    while i < m:
        y = runs[order[i], 0]
        left, right = runs[order[i], 1], runs[order[i], 2]
        j = i + 1
        while j < m and runs[order[j], 0] == y:
            left = min(left, runs[order[j], 1])
            right = max(right, runs[order[j], 2])
            j += 1
        row_m = mask[y]
        for x in range(left, right + 1):
            nxt[x] = x if row_m[x] else x + 1
        nxt[right + 1] = right + 1
        for k in range(i, j):
            e = order[k]
            d = label[e]
            x = find_root(nxt, runs[e, 1])
            while x <= runs[e, 2]:
                covered += 1
                if d < n_drop:
                    loss[d] += 1
                nxt[x] = x + 1
                x = find_root(nxt, x + 1)
        i = j
    return loss, covered


@njit(cache=True)
def cut_counts(mask, c, rows, cols, r2, pts, drop, diag, m):
    """A tip's cuts ``k < m`` (its points ``pts``, their ``drop`` indices, ``diag`` per
    step of its path whether it is diagonal): pixels lost and (axial, diagonal) steps
    dropped per cut; the box (top, left, bottom, right) the points' disks can reach; and
    the pixels only they cover.

    Compiled with :func:`exclusive_losses` in one module, so that numba's cache never
    pairs it with an older copy of that kernel.
    """
    loss = exclusive_losses(mask, c, rows[pts], cols[pts], r2[pts], drop, diag.size + 1)
    lost = np.zeros(m, np.int64)
    cut = np.zeros((m, 2), np.int64)
    for k in range(1, m):
        lost[k] = lost[k - 1] + loss[k - 1]
        cut[k, 0] = cut[k - 1, 0] + 1 - diag[k - 1]
        cut[k, 1] = cut[k - 1, 1] + diag[k - 1]
    box = np.empty(4, np.int64)
    box[0] = box[1] = np.iinfo(np.int64).max
    box[2] = box[3] = np.iinfo(np.int64).min
    for p in pts:
        rad = int(math.sqrt(r2[p])) + 1
        box[0] = min(box[0], rows[p] - rad)
        box[1] = min(box[1], cols[p] - rad)
        box[2] = max(box[2], rows[p] + rad)
        box[3] = max(box[3], cols[p] + rad)
    return lost, cut, box, loss.sum()
