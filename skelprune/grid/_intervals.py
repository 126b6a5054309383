"""Pixel sets as row runs, for the incremental reconstruction
(:class:`~skelprune.grid.coverage.Coverage`).

A run set is an ``(m, 3)`` int64 array of runs ``(row, lo, hi)``, the pixels
``lo <= col <= hi`` of ``row``, sorted by ``(row, lo)``, disjoint and not touching
(two runs of one row leave at least one pixel between them). This form is unique
for a pixel set, so a union keeps it with one merge pass.

The consecutive disks of a branch are almost identical; their union covers each
pixel once, so painting it costs its area, about ``length * 2r + πr²``, instead of
``length * πr²`` for the disks one by one.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._digital import isqrt

__all__ = ["disk_runs", "owner_runs", "union", "union_runs"]

# Runs are sorted on the key ``row << 32 | lo``: rows and columns are array indices,
# non-negative and far below 2**31.
_SHIFT = 32


@njit(cache=True)
def _n_disk_rows(r2, pts):
    n = 0
    for k in pts:
        n += 2 * isqrt(r2[k] - 1) + 1
    return n


@njit(cache=True)
def _disk_runs_into(out, m, rows, cols, r2, pts, head, link, prow, plo, phi):
    """Write the runs of the union of the disks of ``pts`` into ``out[m:]``.

    ``out`` and the pool ``link, prow, plo, phi`` need room for one run per disk row;
    ``head`` (one entry per array row) must be -1 and is left so. Returns the new end.
    """
    # Neighbouring disks of one owner overlap row by row: a disk row that meets a pool
    # run of its row extends it, so the pool stays near the final run count and only
    # it needs sorting (sorting every disk row was most of the cost).
    n = 0
    for k in pts:
        v = r2[k]
        h = isqrt(v - 1)
        w = 0  # the half width, walked up to the middle row and down again (no square root)
        for dy in range(-h, h + 1):
            while dy <= 0 and (w + 1) * (w + 1) <= v - 1 - dy * dy:
                w += 1
            while w * w > v - 1 - dy * dy:
                w -= 1
            r = rows[k] + dy
            lo = cols[k] - w
            hi = cols[k] + w
            e = head[r]
            while e >= 0 and (lo > phi[e] + 1 or hi + 1 < plo[e]):
                e = link[e]
            if e >= 0:
                # Pool runs of a row may now overlap: the merge below joins them.
                plo[e] = min(plo[e], lo)
                phi[e] = max(phi[e], hi)
            else:
                prow[n] = r
                plo[n] = lo
                phi[n] = hi
                link[n] = head[r]
                head[r] = n
                n += 1
    for e in range(n):
        head[prow[e]] = -1
    key = (prow[:n] << _SHIFT) | plo[:n]
    start = m
    for j in np.argsort(key):
        m = _append_run(out, m, start, prow[j], plo[j], phi[j])
    return m


@njit(cache=True)
def _append_run(out, m, first, r, lo, hi):
    """Append run ``(r, lo, hi)`` to ``out[:m]`` (runs in order), merging it into the last
    run (if that is at or after ``first``) when they touch; returns the new length."""
    if m > first and out[m - 1, 0] == r and lo <= out[m - 1, 2] + 1:
        if hi > out[m - 1, 2]:
            out[m - 1, 2] = hi
        return m
    out[m, 0] = r
    out[m, 1] = lo
    out[m, 2] = hi
    return m + 1


def disk_runs(rows, cols, r2, pts):
    """Run set of the union of the disks ``|p - s|**2 < r2(s)`` of the points ``pts``.

    The disks must lie inside the array (non-negative pixel indices).
    """
    pts = np.asarray(pts, np.int64)
    runs, _ = owner_runs(rows[pts], cols[pts], r2[pts], np.zeros(pts.size, np.int64), 1)
    return runs


@njit(cache=True)
def owner_runs(rows, cols, r2, labels, n_labels):
    """Run set of the union of each label's disks, all in one array.

    Returns ``runs`` and ``offsets`` (``n_labels + 1``): the runs of label ``b`` are
    ``runs[offsets[b]:offsets[b + 1]]``.
    """
    order = np.argsort(labels, kind="mergesort")
    n = _n_disk_rows(r2, order)
    height = 1
    for k in range(rows.size):
        height = max(height, rows[k] + isqrt(r2[k] - 1) + 1)
    out = np.empty((n, 3), np.int64)
    pool = np.empty((4, n), np.int64)
    head = np.full(height, -1, np.int64)
    offsets = np.zeros(n_labels + 1, np.int64)
    m = 0
    i = 0
    for b in range(n_labels):
        j = i
        while j < order.size and labels[order[j]] == b:
            j += 1
        if j > i:
            m = _disk_runs_into(
                out, m, rows, cols, r2, order[i:j], head, pool[0], pool[1], pool[2], pool[3]
            )
        offsets[b + 1] = m
        i = j
    return out[:m].copy(), offsets


@njit(cache=True)
def union(a, b):
    """Run set of the pixels of ``a`` or ``b``."""
    return union_runs(a, b)


# inline="always": also called inside compiled code (the coverage's merge), and a
# cached callee that returns an array must not also be entered from Python (see
# skelprune.grid._disk_counts.coverage).
@njit(cache=True, inline="always")
def union_runs(a, b):
    """:func:`union`, for compiled callers."""
    out = np.empty((a.shape[0] + b.shape[0], 3), np.int64)
    i = j = m = 0
    while i < a.shape[0] or j < b.shape[0]:
        if j == b.shape[0] or (
            i < a.shape[0] and (a[i, 0] < b[j, 0] or (a[i, 0] == b[j, 0] and a[i, 1] <= b[j, 1]))
        ):
            r, lo, hi = a[i, 0], a[i, 1], a[i, 2]
            i += 1
        else:
            r, lo, hi = b[j, 0], b[j, 1], b[j, 2]
            j += 1
        m = _append_run(out, m, 0, r, lo, hi)
    return out[:m].copy()
