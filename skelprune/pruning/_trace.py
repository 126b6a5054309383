"""The compiled walks that build a skeleton's branch graph (:mod:`.branch_graph`), on any grid.

A grid hands over its skeleton as points with a neighbour table (``nbr[p, i]``: the
point at neighbour slot ``i`` of point ``p``, -1 where none; 8 slots in the plane, 26 in
a volume) and the step kind of each slot (``slot_kind[i]``: axial or diagonal in the
plane, one of seven in a volume). From those alone: the junction clusters (adjacent
points of three neighbours or more) and the branches traced between them as one flat
point array with offsets (compressed sparse rows), with each branch's end attachments
and its steps of each kind.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["junction_clusters", "path_kinds", "trace_branches"]


@njit(cache=True)
def junction_clusters(nbr, deg):
    """The cluster of adjacent junction points (degree 3 or more; -1 for the others) of
    each point, numbered in the order of their first point, and the number of clusters."""
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
            for i in range(nbr.shape[1]):
                q = nbr[u, i]
                if q >= 0 and deg[q] >= 3 and out[q] < 0:
                    out[q] = n_clusters
                    stack[top] = q
                    top += 1
        n_clusters += 1
    return out, n_clusters


@njit(cache=True)
def _walk(nbr, deg, junction, visited, pts, used, prev, cur):
    """Follow degree-2 points from ``cur`` (coming from ``prev``): the junction point it
    ended on (-1: a free end, -2: back on itself) and the next free slot of ``pts``."""
    while True:
        visited[cur] = True
        pts[used] = cur
        used += 1
        if deg[cur] != 2:
            return -1, used
        nxt = -1
        for i in range(nbr.shape[1]):
            q = nbr[cur, i]
            if q >= 0 and q != prev:
                nxt = q
                break
        if junction[nxt]:
            return nxt, used
        if visited[nxt]:
            return -2, used
        prev, cur = cur, nxt


@njit(cache=True, inline="always")
def _kind(nbr, slot_kind, p, q):
    """The step kind from point ``p`` to its neighbour ``q``."""
    for i in range(nbr.shape[1]):
        if nbr[p, i] == q:
            return slot_kind[i]
    return -1


@njit(cache=True)
def path_kinds(nbr, slot_kind, path):
    """The step kind of each step of ``path`` (consecutive neighbours)."""
    out = np.empty(max(path.size - 1, 0), np.int64)
    for k in range(out.size):
        out[k] = _kind(nbr, slot_kind, path[k], path[k + 1])
    return out


@njit(cache=True)
def trace_branches(nbr, deg, slot_kind, n_kinds):
    """Trace all branches.

    Returns the concatenated point lists (``pts``, split at ``starts``), per branch the
    junction point each end attaches to (-1: a free end; -2: the branch is a closed
    cycle without junction), and per branch its steps of each kind, the steps into its
    junction points and, for a cycle, the closing step included.
    """
    n = deg.size
    junction = deg >= 3
    visited = np.zeros(n, dtype=np.bool_)
    pts = np.empty(n, dtype=np.int64)
    starts = np.zeros(n + 1, dtype=np.int64)
    att = np.empty((n, 2), dtype=np.int64)
    used = 0
    nb = 0
    for j in range(n):
        if not junction[j]:
            continue
        for i in range(nbr.shape[1]):
            q = nbr[j, i]
            if q < 0 or junction[q] or visited[q]:
                continue
            end, used = _walk(nbr, deg, junction, visited, pts, used, j, q)
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
            for i in range(nbr.shape[1]):
                if nbr[k, i] >= 0:
                    first = nbr[k, i]
            if junction[first]:
                end = first
            elif not visited[first]:
                end, used = _walk(nbr, deg, junction, visited, pts, used, k, first)
        att[nb, 0] = -1
        att[nb, 1] = max(end, -1)
        nb += 1
        starts[nb] = used
    for k in range(n):
        if visited[k] or junction[k]:
            continue
        prev = -1  # a cycle of degree-2 points: walk it from its first point
        for i in range(nbr.shape[1]):
            if nbr[k, i] >= 0:
                prev = nbr[k, i]
        _, used = _walk(nbr, deg, junction, visited, pts, used, prev, k)
        att[nb, 0] = -2
        att[nb, 1] = -2
        nb += 1
        starts[nb] = used
    counts = np.zeros((nb, n_kinds), dtype=np.int64)
    for b in range(nb):
        s0, s1 = starts[b], starts[b + 1]
        prev = att[b, 0] if att[b, 0] >= 0 else (pts[s1 - 1] if att[b, 0] == -2 else -1)
        if att[b, 0] == -2 and s1 - s0 < 3:
            prev = -1  # not a real cycle: no closing step
        for i in range(s0, s1 + 1):
            if i < s1:
                cur = pts[i]
            elif att[b, 1] >= 0:
                cur = att[b, 1]
            else:
                break
            if prev >= 0:
                counts[b, _kind(nbr, slot_kind, prev, cur)] += 1
            prev = cur
    return pts[:used], starts[: nb + 1], att[:nb], counts
