"""Skeleton graph: endpoints, junction clusters, branches and loops (docs/algorithm.md).

A skeleton is a set of pixels. Pixels with three or more 8-neighbours are junction
pixels; adjacent junction pixels form one junction node. Branches are the pixel
paths between nodes; a path with no junction at all is a single branch (two free
ends), and a cycle with no junction is a loop branch.

:class:`BranchGraph` is the mutable graph the pruning works on. It implements the
one operation pruning needs, removing an end branch, with the rule of docs/algorithm.md: a
junction left with two branch ends is dissolved and its two branches become one.
Lengths are kept as exact integer counts of axial and diagonal steps, so that two
implementations that do the same removals get bit-identical lengths.
"""

from __future__ import annotations

import heapq
import itertools
import math
from dataclasses import dataclass, field

import numpy as np
from numba.extending import register_jitable

from ._trace import junction_clusters, neighbour_table, point_index, trace_branches

__all__ = ["SQRT2", "Branch", "BranchGraph", "step_length"]

SQRT2 = math.sqrt(2.0)
_AXIAL, _DIAGONAL = (1, 0), (0, 1)  # (axial, diagonal) step counts of one step


@register_jitable
def step_length(na, nd):
    """Length of a digital path of ``na`` axial and ``nd`` diagonal steps (1 and √2).

    The one definition of skeleton length, for Python (scalars or arrays) and compiled
    code alike; keeping lengths as integer step counts until here makes two
    implementations that do the same removals agree bit for bit.

    >>> step_length(3, 2)
    5.82842712474619
    """
    return na + nd * SQRT2


@dataclass
class Branch:
    """A branch: ordered points and, for each end, the junction node it attaches to.

    ``node[e]`` is a junction node id or ``None`` (a free end: an endpoint);
    ``attach[e]`` is the junction pixel the end touches. A loop without junction has
    ``loop = True`` and no nodes.

    ``side`` lists the points of ``points`` that are not on the branch's path: pixels of
    a dissolved junction cluster beside the path through it. ``points`` keeps them, in
    the order the pruning has always seen them; :meth:`path` leaves them out. Both lists
    are replaced, never changed in place, and a removed branch is never changed again:
    :meth:`BranchGraph.copy` shares them.
    """

    points: list[int]
    node: list[int | None]
    attach: list[int]
    na: int
    nd: int
    loop: bool = False
    alive: bool = True
    side: list[int] = field(default_factory=list)

    @property
    def length(self) -> float:
        return step_length(self.na, self.nd)

    def path(self) -> list[int]:
        """``points`` without ``side``: consecutive 8-neighbours, in the branch's order.

        Its step length, with the step from each junction end's ``attach`` pixel into
        it (and, for a loop, the closing step), is ``length``.
        """
        if not self.side:
            return list(self.points)
        off = set(self.side)
        return [p for p in self.points if p not in off]


@dataclass
class Junction:
    points: list[int]
    ends: list[tuple[int, int]] = field(default_factory=list)  # (branch, end index)
    alive: bool = True


class BranchGraph:
    """Mutable branch graph of a skeleton given as pixel coordinates.

    Parameters
    ----------
    rows, cols : (n,) int arrays
        Skeleton pixels (one pixel thin, 8-connected components).
    shape : tuple
        Shape of the array the coordinates index; the border must be empty.

    Examples
    --------
    >>> rows = np.array([1, 1, 1, 1, 1, 2, 3]); cols = np.array([1, 2, 3, 4, 5, 3, 3])
    >>> g = BranchGraph(rows, cols, (5, 7))
    >>> len(g.end_branches())
    3
    """

    def __init__(self, rows: np.ndarray, cols: np.ndarray, shape: tuple[int, int]) -> None:
        self.rows = np.asarray(rows, dtype=np.int64)
        self.cols = np.asarray(cols, dtype=np.int64)
        self.shape = (int(shape[0]), int(shape[1]))
        index = point_index(self.rows, self.cols, shape)
        self.nbr, self.degree = neighbour_table(self.rows, self.cols, index)
        self.extra_na = 0  # steps inside dissolved junction clusters, a running total
        self.extra_nd = 0
        self.branches: list[Branch] = []
        self.junctions: list[Junction] = []
        self._build()

    # -- construction -------------------------------------------------------------
    def _build(self) -> None:
        pts, starts, att, counts = trace_branches(self.nbr, self.degree, self.rows, self.cols)
        # Junction nodes: 8-connected clusters of junction pixels, numbered in the order
        # of their first pixel.
        jpix = np.flatnonzero(self.degree >= 3)
        junction_of, n_junctions = junction_clusters(self.nbr, self.degree)
        if jpix.size:
            members: list[list[int]] = [[] for _ in range(n_junctions)]
            for p, j in zip(jpix.tolist(), junction_of[jpix].tolist(), strict=True):
                members[j].append(p)
            self.junctions = [Junction(m) for m in members]
        jof = junction_of.tolist()
        starts_l = starts.tolist()
        pts_l = pts.tolist()
        for b, ((a0, a1), (na, nd)) in enumerate(zip(att.tolist(), counts.tolist(), strict=True)):
            seg = pts_l[starts_l[b] : starts_l[b + 1]]
            if a0 == -2:
                self.branches.append(Branch(seg, [None, None], [-1, -1], na, nd, loop=True))
                continue
            nodes = [jof[a0] if a0 >= 0 else None, jof[a1] if a1 >= 0 else None]
            self.branches.append(Branch(seg, nodes, [a0, a1], na, nd))
            for e in (0, 1):
                if nodes[e] is not None:
                    self.junctions[nodes[e]].ends.append((b, e))
        for jid, junc in enumerate(self.junctions):
            if len(junc.ends) <= 2:
                self._dissolve(jid)
        self.ends = {b for b in range(len(self.branches)) if self.is_end_branch(b)}
        self.na = sum(b.na for b in self.branches if b.alive)
        self.nd = sum(b.nd for b in self.branches if b.alive)

    def copy(self) -> BranchGraph:
        """An independent copy; the point arrays, which no removal changes, are shared.

        Cheaper than building the graph again and replaying its removals.
        """
        g = object.__new__(BranchGraph)
        g.rows, g.cols, g.nbr, g.degree = self.rows, self.cols, self.nbr, self.degree
        g.shape = self.shape
        g.extra_na, g.extra_nd = self.extra_na, self.extra_nd
        g.na, g.nd = self.na, self.nd
        # A removed branch or junction is never changed again, and a branch's ``points``
        # and ``side`` (a junction's ``points``) are only ever replaced, never changed in
        # place: the copies share those.
        g.branches = [
            Branch(b.points, list(b.node), list(b.attach), b.na, b.nd, b.loop, True, b.side)
            if b.alive
            else b
            for b in self.branches
        ]
        g.junctions = [
            Junction(j.points, list(j.ends), True) if j.alive else j for j in self.junctions
        ]
        g.ends = set(self.ends)
        g._lists = self._coordinate_lists()
        return g

    # -- queries ------------------------------------------------------------------
    def is_end_branch(self, b: int) -> bool:
        br = self.branches[b]
        return br.alive and not br.loop and (br.node[0] is None) != (br.node[1] is None)

    def end_branches(self) -> list[int]:
        """Ids of the current end branches (one free end, one junction end), sorted."""
        return sorted(self.ends)

    def endpoint(self, b: int) -> int:
        """The free-end point of end branch ``b``."""
        br = self.branches[b]
        return br.points[0] if br.node[0] is None else br.points[-1]

    def n_endpoints(self) -> int:
        """Number of free branch ends (a single isolated point counts once)."""
        n = 0
        for br in self.branches:
            if br.alive and not br.loop:
                free = (br.node[0] is None) + (br.node[1] is None)
                n += 1 if free == 2 and len(br.points) == 1 else free
        return n

    @property
    def coords(self) -> tuple[np.ndarray, np.ndarray]:
        """``(rows, cols)``: the points' coordinates, in the order that breaks ties."""
        return self.rows, self.cols

    def branch_steps(self, b: int) -> tuple[int, int]:
        """Branch ``b``'s (axial, diagonal) steps."""
        br = self.branches[b]
        return br.na, br.nd

    def total_steps(self) -> tuple[int, int]:
        """The skeleton's (axial, diagonal) steps."""
        return self.na, self.nd

    def length_counts(self) -> tuple[int, int]:
        """Total (axial, diagonal) step counts of the current skeleton."""
        return self.na, self.nd

    def alive_points(self) -> np.ndarray:
        """Indices of the points still in the skeleton."""
        keep: list[int] = []
        for br in self.branches:
            if br.alive:
                keep.extend(br.points)
        for junc in self.junctions:
            if junc.alive:
                keep.extend(junc.points)
        out = np.fromiter(keep, np.int64, len(keep))  # (faster than sorting the list)
        out.sort()
        return out

    def counts_without(self, b: int) -> tuple[int, int]:
        """(axial, diagonal) step counts of the skeleton once end branch ``b`` is removed,
        without removing it: what :meth:`remove_end_branch` would leave, a dissolved
        junction's path through its cluster included."""
        br = self.branches[b]
        e = 0 if br.node[0] is not None else 1
        jid = br.node[e]
        assert jid is not None
        na, nd = self.na - br.na, self.nd - br.nd
        rest = [end for end in self.junctions[jid].ends if end != (b, e)]
        if len(rest) == 2:
            (b1, e1), (b2, e2) = rest
            # a shortest path's (axial, diagonal) counts are the same either way round
            _, pa, pd = self._cluster_path(
                jid, self.branches[b1].attach[e1], self.branches[b2].attach[e2]
            )
            na, nd = na + pa, nd + pd
        return na, nd

    def free_ends(self) -> list[tuple[int, int]]:
        """``(branch, end)`` of every free end that a tip cut may shorten: the free end
        of each end branch and both ends of a single path (of two points or more)."""
        out = []
        for b, br in enumerate(self.branches):
            if not br.alive or br.loop:
                continue
            free = [e for e in (0, 1) if br.node[e] is None]
            if len(free) == 1 or (len(free) == 2 and len(br.path()) > 1):
                out.extend((b, e) for e in free)
        return out

    def free_end_point(self, b: int, e: int) -> int:
        """The path point at end ``e`` of branch ``b``."""
        path = self.branches[b].path()
        return path[0] if e == 0 else path[-1]

    def tip(self, b: int, e: int) -> tuple[list[int], list[int], list[int]]:
        """Branch ``b`` seen from its free end ``e``, as a tip cut drops it.

        Returns the branch's points, the drop index of each (a cut of ``k`` drops the
        points whose index is below ``k``), and per step of the path from the end
        whether it is diagonal. The path's ``i``-th point from the end has index ``i``;
        a point beside the path (of a dissolved junction cluster) goes with the last
        path point it touches, directly or through other such points, so that what a
        cut leaves stays connected.
        """
        br = self.branches[b]
        path = br.path()
        if e == 1:
            path = path[::-1]
        # (Python lists: a tip is tens of points, too few for numpy's per-call cost)
        rl, cl = self._coordinate_lists()
        steps = [int(rl[p] != rl[q] and cl[p] != cl[q]) for p, q in itertools.pairwise(path)]
        if not br.side:
            return path, list(range(len(path))), steps
        index = {p: i for i, p in enumerate(path)}
        side = [p for p in br.points if p not in index]
        drop: dict[int, int] = {}
        pending = list(side)
        while pending:
            left = []
            for p in pending:
                near = [index.get(int(q), drop.get(int(q), -1)) for q in self.nbr[p] if q >= 0]
                best = max(near, default=-1)
                if best < 0:
                    left.append(p)
                else:
                    drop[p] = best
            if len(left) == len(pending):  # touches nothing placed: never dropped
                for p in left:
                    drop[p] = len(path) - 1
                break
            pending = left
        return path + side, list(range(len(path))) + [drop[p] for p in side], steps

    def _coordinate_lists(self) -> tuple[list[int], list[int]]:
        """``rows`` and ``cols`` as Python lists, made once and shared by copies."""
        lists = self.__dict__.get("_lists")
        if lists is None:
            lists = self._lists = (self.rows.tolist(), self.cols.tolist())
        return lists

    # -- mutation -----------------------------------------------------------------
    def cut_tip(self, b: int, e: int, gone: list[int], na: int, nd: int) -> None:
        """Drop points ``gone`` from the free end ``e`` of branch ``b``, with their
        ``na`` axial and ``nd`` diagonal steps (:func:`skelprune.pruning.tips.trim_tips`)."""
        br = self.branches[b]
        out = set(gone)
        br.points = [p for p in br.points if p not in out]
        br.side = [p for p in br.side if p not in out]
        br.na -= na
        br.nd -= nd
        self.na -= na
        self.nd -= nd

    def remove_end_branch(self, b: int) -> tuple[int, int, int] | None:
        """Remove end branch ``b``.

        Returns ``None``, or, when its junction ``jid`` is dissolved, ``(kept, absorbed,
        jid)``: branch ``absorbed`` (maybe equal to ``kept`` for a loop) and the
        junction's pixels now belong to branch ``kept``.
        """
        if not self.is_end_branch(b):
            raise ValueError(f"branch {b} is not an end branch")
        br = self.branches[b]
        br.alive = False
        self.ends.discard(b)
        self.na -= br.na
        self.nd -= br.nd
        e = 0 if br.node[0] is not None else 1
        jid = br.node[e]
        assert jid is not None
        junc = self.junctions[jid]
        junc.ends.remove((b, e))
        if len(junc.ends) != 2:
            return None
        before = self.extra_na, self.extra_nd
        merged = self._dissolve(jid)
        self.na += self.extra_na - before[0]
        self.nd += self.extra_nd - before[1]
        if merged is not None:
            kept, absorbed = merged[0], merged[1]
            self.ends.discard(absorbed)
            if self.is_end_branch(kept):
                self.ends.add(kept)
            else:
                self.ends.discard(kept)
        return merged

    def _cluster_path(self, jid: int, a: int, z: int) -> tuple[list[int], int, int]:
        """Shortest path from pixel ``a`` to ``z`` inside junction cluster ``jid``."""
        if a == z:  # (most clusters: one pixel, a tip's own attach pixel)
            return [a], 0, 0
        members = set(self.junctions[jid].points)
        best: dict[int, float] = {a: 0.0}
        prev: dict[int, tuple[int, tuple[int, int]]] = {}
        heap = [(0.0, a)]
        nbr = self.nbr
        while heap:
            d, u = heapq.heappop(heap)
            if u == z or d > best[u]:
                continue
            # the neighbour slot says the step: even slots are diagonal (see _digital.NEIGHBOURS)
            for i, q in enumerate(nbr[u].tolist()):
                if q < 0 or q not in members:
                    continue
                step = _DIAGONAL if i % 2 == 0 else _AXIAL
                nd = d + step_length(*step)
                if nd < best.get(q, math.inf) - 1e-12:
                    best[q] = nd
                    prev[q] = (u, step)
                    heapq.heappush(heap, (nd, q))
        path, na, ndg = [z], 0, 0
        while path[-1] != a:
            u, step = prev[path[-1]]
            na += step[0]
            ndg += step[1]
            path.append(u)
        return path[::-1], na, ndg

    def _dissolve(self, jid: int) -> tuple[int, int, int] | None:
        """A junction with at most two branch ends becomes ordinary points."""
        junc = self.junctions[jid]
        junc.alive = False
        ends = list(junc.ends)
        junc.ends.clear()
        if not ends:  # an isolated blob of junction pixels: one branch, two free ends
            self.branches.append(
                Branch(list(junc.points), [None, None], [-1, -1], 0, 0, side=list(junc.points[1:]))
            )
            return None
        if len(ends) == 1:  # the cluster is the tip of a branch
            b, e = ends[0]
            br = self.branches[b]
            path, na, nd = self._cluster_path(jid, br.attach[e], br.attach[e])
            rest = [p for p in junc.points if p not in path]
            tip = path + rest
            br.points = br.points + tip if e == 1 else tip[::-1] + br.points
            br.side = br.side + rest
            br.node[e], br.attach[e] = None, -1
            return None
        (b1, e1), (b2, e2) = ends
        if b1 == b2:  # a loop through the junction closes into a cycle
            br = self.branches[b1]
            path, na, nd = self._cluster_path(jid, br.attach[1], br.attach[0])
            moved = list(dict.fromkeys(path + list(junc.points)))
            br.points = br.points + moved
            br.side = br.side + moved[len(path) :]
            br.na += na
            br.nd += nd
            self.extra_na += na
            self.extra_nd += nd
            br.node, br.attach, br.loop = [None, None], [-1, -1], True
            return b1, b1, jid
        # Keep the branch with more points: the absorbed one is the owner that
        # Coverage.merge_label moves, at the cost of its disks' area.
        if len(self.branches[b2].points) > len(self.branches[b1].points):
            (b1, e1), (b2, e2) = (b2, e2), (b1, e1)
        k, a = self.branches[b1], self.branches[b2]
        kp = k.points if e1 == 1 else k.points[::-1]
        kn = [k.node[1 - e1], None]
        kt = [k.attach[1 - e1], -1]
        ap = a.points if e2 == 0 else a.points[::-1]
        path, na, nd = self._cluster_path(jid, k.attach[e1], a.attach[e2])
        rest = [p for p in junc.points if p not in path]
        k.points = kp + path + rest + ap
        k.side = k.side + rest + a.side
        k.node = [kn[0], a.node[1 - e2]]
        k.attach = [kt[0], a.attach[1 - e2]]
        k.na += a.na + na
        k.nd += a.nd + nd
        self.extra_na += na
        self.extra_nd += nd
        a.alive = False
        # Re-point the far junctions' records; the kept branch's own record first, so
        # that a loop through one other junction does not confuse the two.
        near, far = kn[0], a.node[1 - e2]
        if near is not None and e1 == 0:
            nj = self.junctions[near]
            nj.ends[nj.ends.index((b1, 1))] = (b1, 0)
        if far is not None:
            fj = self.junctions[far]
            fj.ends[fj.ends.index((b2, 1 - e2))] = (b1, 1)
        return b1, b2, jid
