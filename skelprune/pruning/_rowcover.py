"""Disk coverage counted row by row: work per disk row, never per disk pixel.

A disk ``|p − s|² < r²`` is one run of pixels per row (``_digital.disk_half_width``). The
kernels here take a set of disks as those runs, binned by row, and per row add them up
with a difference array over the runs' extent. Against painting every pixel of every
disk, a row costs its runs plus the columns the runs span, once: on a blob, where
hundreds of disks of hundreds of pixels' radius overlap, that is the difference between
the sum of the disks' areas and the area they cover.

Used by the tips' cut (:mod:`skelprune.pruning.tips`) and the noise-floor choice
(:mod:`skelprune.pruning.floor`), which both keep ``c``: per pixel, how many disks of the
current skeleton cover it.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .._digital import isqrt

__all__ = ["cover_counts", "exclusive_losses", "uncover", "uncover_count"]


@njit(cache=True)
def _runs(rows, cols, r2, order, tag):
    """The disks' runs binned by row, each row's runs in ``order`` of the disks.

    Returns ``(y0, start, lo, hi, t)``: runs of row ``y0 + i`` are
    ``start[i] … start[i + 1] − 1``, run ``j`` covering columns ``lo[j] … hi[j]`` of a
    disk ``i`` whose ``tag[i]`` is ``t[j]``.
    """
    n = rows.size
    rad = np.empty(n, np.int64)
    y0, y1 = 0, -1
    if n:
        y0, y1 = np.iinfo(np.int64).max, np.iinfo(np.int64).min
    for i in range(n):
        rad[i] = isqrt(r2[i] - 1)
        y0 = min(y0, rows[i] - rad[i])
        y1 = max(y1, rows[i] + rad[i])
    start = np.zeros(y1 - y0 + 3, np.int64)
    for i in range(n):  # a disk adds one run to each of its rows
        start[rows[i] - rad[i] - y0 + 1] += 1
        start[rows[i] + rad[i] - y0 + 2] -= 1
    for i in range(1, start.size):
        start[i] += start[i - 1]
    for i in range(1, start.size):
        start[i] += start[i - 1]
    start = start[:-1]
    total = start[-1]
    lo = np.empty(total, np.int32)
    hi = np.empty(total, np.int32)
    t = np.empty(total, tag.dtype)
    fill = start[:-1].copy()
    for i in order:
        r, q, v, g = rows[i], cols[i], r2[i], tag[i]
        dx = rad[i]
        for dy in range(rad[i] + 1):
            while dx * dx + dy * dy >= v:  # strictly inside (disk_half_width, in steps)
                dx -= 1
            j = fill[r + dy - y0]
            fill[r + dy - y0] += 1
            lo[j], hi[j], t[j] = q - dx, q + dx, g
            if dy:  # the same run, mirrored
                j = fill[r - dy - y0]
                fill[r - dy - y0] += 1
                lo[j], hi[j], t[j] = q - dx, q + dx, g
    return y0, start, lo, hi, t


@njit(cache=True)
def _row_sum(run, lo, hi, a, b):
    """Add runs ``a … b − 1`` into the difference array ``run``; return their extent."""
    left, right = np.iinfo(np.int64).max, np.iinfo(np.int64).min
    for j in range(a, b):
        run[lo[j]] += 1
        run[hi[j] + 1] -= 1
        left = min(left, lo[j])
        right = max(right, hi[j])
    return left, right


@njit(cache=True)
def cover_counts(h, w, rows, cols, r2):
    """How many disks ``|p − s|² < r²`` cover each pixel (``int32``, ``h × w``)."""
    c = np.zeros((h, w), np.int32)
    for i in range(rows.size):
        r, q, v = rows[i], cols[i], r2[i]
        dx = rad = isqrt(v - 1)
        for dy in range(rad + 1):
            while dx * dx + dy * dy >= v:  # strictly inside (disk_half_width, in steps)
                dx -= 1
            for y in range(r - dy, r + dy + 1, max(2 * dy, 1)):  # rows r ± dy
                c[y, q - dx] += 1
                if q + dx + 1 < w:
                    c[y, q + dx + 1] -= 1
    for y in range(h):
        acc = 0
        for x in range(w):
            acc += c[y, x]
            c[y, x] = acc
    return c


@njit(cache=True)
def uncover(c, rows, cols, r2):
    """Take the disks of these points off the counts ``c``."""
    y0, start, lo, hi, _ = _runs(rows, cols, r2, np.arange(rows.size), rows)
    run = np.zeros(c.shape[1] + 1, np.int32)
    for i in range(start.size - 1):
        if start[i] == start[i + 1]:
            continue
        y = y0 + i
        left, right = _row_sum(run, lo, hi, start[i], start[i + 1])
        acc = 0
        for x in range(left, right + 1):
            acc += run[x]
            run[x] = 0
            c[y, x] -= acc
        run[right + 1] = 0


@njit(cache=True)
def uncover_count(c, deep, rows, cols, r2):
    """Take these disks off the counts ``c``; return how many ``deep`` pixels lost their
    last one."""
    y0, start, lo, hi, _ = _runs(rows, cols, r2, np.arange(rows.size), rows)
    run = np.zeros(c.shape[1] + 1, np.int32)
    n = 0
    for i in range(start.size - 1):
        if start[i] == start[i + 1]:
            continue
        y = y0 + i
        left, right = _row_sum(run, lo, hi, start[i], start[i + 1])
        acc = 0
        for x in range(left, right + 1):
            acc += run[x]
            run[x] = 0
            if acc > 0:
                c[y, x] -= acc
                if c[y, x] == 0 and deep[y, x]:
                    n += 1
        run[right + 1] = 0
    return n


@njit(cache=True)
def _find(nxt, x):
    """The first column ``≥ x`` still open (path halving)."""
    while nxt[x] != x:
        nxt[x] = nxt[nxt[x]]
        x = nxt[x]
    return x


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
    order = np.argsort(-drop, kind="mergesort")
    y0, start, lo, hi, t = _runs(rows, cols, r2, order, drop.astype(np.int32))
    w = c.shape[1]
    run = np.zeros(w + 1, np.int32)
    nxt = np.empty(w + 1, np.int32)
    loss = np.zeros(n_drop, np.int64)
    for i in range(start.size - 1):
        if start[i] == start[i + 1]:
            continue
        y = y0 + i
        left, right = _row_sum(run, lo, hi, start[i], start[i + 1])
        acc = 0
        for x in range(left, right + 1):
            acc += run[x]
            run[x] = 0
            # open: covered by these disks and by no other
            nxt[x] = x if acc > 0 and acc == c[y, x] and mask[y, x] else x + 1
        run[right + 1] = 0
        nxt[right + 1] = right + 1
        for j in range(start[i], start[i + 1]):  # decreasing drop index
            d = t[j]
            x = _find(nxt, lo[j])
            while x <= hi[j]:
                loss[d] += 1
                nxt[x] = x + 1
                x = _find(nxt, x + 1)
    return loss
