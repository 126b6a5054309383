"""The compiled walks that build a pixel skeleton's branch graph (:mod:`.graph`).

From the skeleton's pixels: an index image, the 8-neighbour table and degree of every
pixel, the junction clusters (8-connected junction pixels) and the branches traced
between them as one flat point array with offsets (compressed sparse rows), with each
branch's end attachments and its axial and diagonal step counts.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._digital import NEIGHBOURS

__all__ = ["junction_clusters", "neighbour_table", "point_index", "trace_branches"]


@njit(cache=True)
def point_index(rows, cols, shape):
    index = np.full(shape, -1, dtype=np.int64)
    for k in range(rows.size):
        index[rows[k], cols[k]] = k
    return index


@njit(cache=True)
def neighbour_table(rows, cols, index):
    """(n, 8) neighbour point indices (-1 where none) and the degree of each point."""
    n = rows.size
    nbr = np.full((n, 8), -1, dtype=np.int64)
    deg = np.zeros(n, dtype=np.int64)
    for k in range(n):
        for i in range(8):
            q = index[rows[k] + NEIGHBOURS[i, 0], cols[k] + NEIGHBOURS[i, 1]]
            if q >= 0:
                nbr[k, i] = q
                deg[k] += 1
    return nbr, deg


@njit(cache=True)
def junction_clusters(nbr, deg):
    """The 8-connected cluster of each junction pixel (degree 3 or more; -1 for the
    others), numbered in the order of their first pixel, and the number of clusters."""
    n = deg.size
    out = np.full(n, -1, dtype=np.int64)
    stack = np.empty(n, dtype=np.int64)
    n_clusters = 0
    for k in range(n):
        if deg[k] < 3 or out[k] >= 0:
            continue
        out[k] = n_clusters
        stack[0] = k
        top = 1
        while top:
            top -= 1
            u = stack[top]
            for i in range(8):
                q = nbr[u, i]
                if q >= 0 and deg[q] >= 3 and out[q] < 0:
                    out[q] = n_clusters
                    stack[top] = q
                    top += 1
        n_clusters += 1
    return out, n_clusters


@njit(cache=True)
def trace_branches(nbr, deg, rows, cols):
    """Trace all branches.

    Returns the concatenated point lists (``pts``, split at ``starts``) and, per
    branch, the junction pixel each end attaches to (-1: a free end; -2: the branch
    is a closed cycle without junction).
    """
    n = deg.size
    junction = deg >= 3
    visited = np.zeros(n, dtype=np.bool_)
    pts = np.empty(n, dtype=np.int64)
    starts = np.zeros(n + 1, dtype=np.int64)
    att = np.empty((n, 2), dtype=np.int64)
    used = 0
    nb = 0

    def walk(prev, cur, used):
        # Follow degree-2 points from ``cur`` (coming from ``prev``); returns where it ended.
        while True:
            visited[cur] = True
            pts[used] = cur
            used += 1
            if deg[cur] != 2:
                return -1, used
            nxt = -1
            for i in range(8):
                q = nbr[cur, i]
                if q >= 0 and q != prev:
                    nxt = q
                    break
            if junction[nxt]:
                return nxt, used
            if visited[nxt]:
                return -2, used
            prev, cur = cur, nxt

    for j in range(n):
        if not junction[j]:
            continue
        for i in range(8):
            q = nbr[j, i]
            if q < 0 or junction[q] or visited[q]:
                continue
            end, used = walk(j, q, used)
            att[nb, 0] = j
            att[nb, 1] = max(end, -1)
            nb += 1
            starts[nb] = used
    for k in range(n):
        if visited[k] or junction[k] or deg[k] > 1:
            continue
        visited[k] = True
        pts[used] = k
        used += 1
        end = -1
        if deg[k] == 1:
            first = -1
            for i in range(8):
                if nbr[k, i] >= 0:
                    first = nbr[k, i]
            if junction[first]:
                end = first
            elif not visited[first]:
                end, used = walk(k, first, used)
        att[nb, 0] = -1
        att[nb, 1] = max(end, -1)
        nb += 1
        starts[nb] = used
    for k in range(n):
        if visited[k] or junction[k]:
            continue
        # A cycle of degree-2 points: walk it from its first point.
        prev = -1
        for i in range(8):
            if nbr[k, i] >= 0:
                prev = nbr[k, i]
        _, used = walk(prev, k, used)
        att[nb, 0] = -2
        att[nb, 1] = -2
        nb += 1
        starts[nb] = used
    # Step counts of each branch, including the steps into its junction pixels and,
    # for a cycle, the closing step.
    counts = np.zeros((nb, 2), dtype=np.int64)
    for b in range(nb):
        s0, s1 = starts[b], starts[b + 1]
        prev = att[b, 0] if att[b, 0] >= 0 else (pts[s1 - 1] if att[b, 0] == -2 else -1)
        for i in range(s0, s1 + 1):
            if i < s1:
                cur = pts[i]
            elif att[b, 1] >= 0:
                cur = att[b, 1]
            else:
                break
            if prev >= 0 and not (att[b, 0] == -2 and i == s0 and s1 - s0 < 2):
                if rows[prev] != rows[cur] and cols[prev] != cols[cur]:
                    counts[b, 1] += 1
                else:
                    counts[b, 0] += 1
            prev = cur
    return pts[:used], starts[: nb + 1], att[:nb], counts
