"""The branch graph of a skeleton, on any grid (docs/algorithm.md, "The skeleton graph").

A skeleton is a set of points; a grid gives their neighbour table (``nbr[p, i]``: the
point at neighbour slot ``i`` of ``p``, -1 where none), the step kind of each slot and
the length of each kind (:class:`GridSteps`). Points with three or more neighbours are
junction points; adjacent junction points form one junction cluster. Branches are the
point paths between clusters and free ends; a path with no junction at all is a single
branch (two free ends), and a cycle with no junction is a loop branch.

:class:`PointGraph` is the mutable graph the pruning works on. It implements the one
operation pruning needs, removing an end branch, with the rule of docs/algorithm.md: a
junction left with two branch ends is dissolved and its two branches become one
through the cluster's shortest path; a cluster with one branch end becomes that
branch's free end. Lengths are kept as exact integer counts of steps of each kind, so
that two implementations that do the same removals get bit-identical lengths
(:func:`~skelprune.pruning.grid.path_length`).
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass, field, replace
from typing import Generic, NamedTuple, Self, TypeVar

import numpy as np

from ._trace import junction_clusters, path_kinds, trace_branches
from .grid import path_length

__all__ = ["AxisOnGraph", "Branch", "GridSteps", "Junction", "PointGraph", "Steps", "add_steps"]

#: Step counts, one per step kind of the grid.
Steps = tuple[int, ...]


def add_steps(a: Steps, b: Steps, sign: int = 1) -> Steps:
    """``a + sign·b``, kind by kind."""
    return tuple(u + sign * v for u, v in zip(a, b, strict=True))


class GridSteps(NamedTuple):
    """What a grid tells the graph about its steps.

    ``slot_kind[i]`` is the step kind of neighbour slot ``i``; ``weights[k]`` the length
    of a step of kind ``k`` (for the shortest paths through junction clusters).
    """

    slot_kind: np.ndarray
    weights: np.ndarray


@dataclass
class Branch:
    """A branch: ordered points and, for each end, the junction cluster it attaches to.

    ``node[e]`` is a junction id or ``None`` (a free end: an endpoint); ``attach[e]`` is
    the junction point the end touches; ``steps`` the branch's steps of each kind, the
    steps into its junction points included. A loop without junction has ``loop = True``
    and no nodes.

    ``side`` lists the points of ``points`` that are not on the branch's path: points of
    a dissolved junction cluster beside the path through it. ``points`` keeps them, in
    the order the pruning has always seen them; :meth:`path` leaves them out. Both lists
    are replaced, never changed in place, and a removed branch is never changed again:
    :meth:`PointGraph.copy` shares them.
    """

    points: list[int]
    node: list[int | None]
    attach: list[int]
    steps: Steps
    loop: bool = False
    alive: bool = True
    side: list[int] = field(default_factory=list)

    def path(self) -> list[int]:
        """``points`` without ``side``: consecutive neighbours, in the branch's order."""
        if not self.side:
            return list(self.points)
        off = set(self.side)
        return [p for p in self.points if p not in off]


@dataclass
class Junction:
    """A junction cluster: its points and the branch ends attached to it."""

    points: list[int]
    ends: list[tuple[int, int]] = field(default_factory=list)  # (branch, end index)
    alive: bool = True


class PointGraph:
    """Mutable branch graph of a skeleton given as points with a neighbour table.

    Parameters
    ----------
    nbr : (n, s) int64 array
        The point at each of the ``s`` neighbour slots of every point (-1: none).
    grid : GridSteps
        The step kind of each slot and the length of each kind.

    Examples
    --------
    A star: point 1 joined to points 0, 2 and 3, one kind of step.

    >>> nbr = np.array([[1, -1, -1], [0, 2, 3], [1, -1, -1], [1, -1, -1]])
    >>> g = PointGraph(nbr, GridSteps(np.zeros(3, np.int64), np.ones(1)))
    >>> g.end_branches(), g.total_steps()
    ([0, 1, 2], (3,))
    >>> g.remove_end_branch(2)   # the other two merge through the junction point
    (0, 1, 0)
    >>> g.end_branches(), g.n_endpoints(), g.branches[0].points
    ([], 2, [0, 1, 2])
    """

    def __init__(self, nbr: np.ndarray, grid: GridSteps) -> None:
        self.nbr = nbr
        self.degree = (nbr >= 0).sum(axis=1)
        self.slot_kind = np.asarray(grid.slot_kind, np.int64)
        self.weights = np.asarray(grid.weights, np.float64)
        self.branches: list[Branch] = []
        self.junctions: list[Junction] = []
        self.steps: Steps = (0,) * self.weights.size
        self._build()

    # -- construction -------------------------------------------------------------
    def _build(self) -> None:
        n_kinds = self.weights.size
        pts, starts, att, counts = trace_branches(self.nbr, self.degree, self.slot_kind, n_kinds)
        # Junction clusters, numbered in the order of their first point.
        cluster, n_clusters = junction_clusters(self.nbr, self.degree)
        members: list[list[int]] = [[] for _ in range(int(n_clusters))]
        for p in np.flatnonzero(cluster >= 0).tolist():
            members[int(cluster[p])].append(p)
        self.junctions = [Junction(m) for m in members]
        jof = cluster.tolist()
        starts_l = starts.tolist()
        pts_l = pts.tolist()
        for b, ((a0, a1), st) in enumerate(zip(att.tolist(), counts.tolist(), strict=True)):
            seg = pts_l[starts_l[b] : starts_l[b + 1]]
            steps = tuple(st)
            if a0 == -2:
                self.branches.append(Branch(seg, [None, None], [-1, -1], steps, loop=True))
                continue
            nodes = [jof[a0] if a0 >= 0 else None, jof[a1] if a1 >= 0 else None]
            self.branches.append(Branch(seg, nodes, [a0, a1], steps))
            for e in (0, 1):
                node = nodes[e]
                if node is not None:
                    self.junctions[node].ends.append((b, e))
        for jid, junc in enumerate(self.junctions):
            if len(junc.ends) <= 2:
                self._dissolve(jid)
        self.ends = {b for b in range(len(self.branches)) if self.is_end_branch(b)}
        total = (0,) * n_kinds
        for br in self.branches:
            if br.alive:
                total = add_steps(total, br.steps)
        self.steps = total

    def copy(self) -> Self:
        """An independent copy; the point arrays, which no removal changes, are shared.

        Cheaper than building the graph again and replaying its removals.
        """
        g = object.__new__(type(self))
        g.__dict__.update(self.__dict__)
        # A removed branch or junction is never changed again, and a branch's ``points``
        # and ``side`` (a junction's ``points``) are only ever replaced, never changed in
        # place: the copies share those.
        g.branches = [
            Branch(b.points, list(b.node), list(b.attach), b.steps, b.loop, True, b.side)
            if b.alive
            else b
            for b in self.branches
        ]
        g.junctions = [
            Junction(j.points, list(j.ends), True) if j.alive else j for j in self.junctions
        ]
        g.ends = set(self.ends)
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

    def branch_length(self, b: int) -> float:
        """Branch ``b``'s length (:func:`~.grid.path_length` of its steps)."""
        return path_length(self.branches[b].steps, self.weights)

    def total_length(self) -> float:
        """The skeleton's length."""
        return path_length(self.steps, self.weights)

    def branch_steps(self, b: int) -> Steps:
        """Branch ``b``'s steps of each kind."""
        return self.branches[b].steps

    def total_steps(self) -> Steps:
        """The skeleton's steps of each kind."""
        return self.steps

    def alive_points(self) -> np.ndarray:
        """Indices of the points still in the skeleton, sorted."""
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

    def path(self, b: int) -> list[int]:
        """Branch ``b``'s points without those beside its path, in order."""
        return self.branches[b].path()

    def counts_without(self, b: int) -> Steps:
        """The skeleton's steps of each kind once end branch ``b`` is removed, without
        removing it: what :meth:`remove_end_branch` would leave, a dissolved junction's
        path through its cluster included."""
        br = self.branches[b]
        e = 0 if br.node[0] is not None else 1
        jid = br.node[e]
        assert jid is not None
        steps = add_steps(self.steps, br.steps, -1)
        rest = [end for end in self.junctions[jid].ends if end != (b, e)]
        if len(rest) == 2:
            (b1, e1), (b2, e2) = rest
            # a shortest path's step counts are the same either way round
            _, st = self._cluster_path(
                jid, self.branches[b1].attach[e1], self.branches[b2].attach[e2]
            )
            steps = add_steps(steps, st)
        return steps

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
        points whose index is below ``k``), and the step kind of each step of the path
        from the end. The path's ``i``-th point from the end has index ``i``; a point
        beside the path (of a dissolved junction cluster) goes with the last path point
        it touches, directly or through other such points, so that what a cut leaves
        stays connected.
        """
        br = self.branches[b]
        path = br.path()
        if e == 1:
            path = path[::-1]
        kinds = path_kinds(self.nbr, self.slot_kind, np.asarray(path, np.int64)).tolist()
        if not br.side:
            return path, list(range(len(path))), kinds
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
        return path + side, list(range(len(path))) + [drop[p] for p in side], kinds

    # -- mutation -----------------------------------------------------------------
    def cut_tip(self, b: int, e: int, gone: list[int], steps: Steps) -> None:
        """Drop points ``gone`` from the free end ``e`` of branch ``b``, with their
        ``steps`` (a tip cut)."""
        br = self.branches[b]
        out = set(gone)
        br.points = [p for p in br.points if p not in out]
        br.side = [p for p in br.side if p not in out]
        br.steps = add_steps(br.steps, steps, -1)
        self.steps = add_steps(self.steps, steps, -1)

    def remove_end_branch(self, b: int) -> tuple[int, int, int] | None:
        """Remove end branch ``b``.

        Returns ``None``, or, when its junction ``jid`` is dissolved, ``(kept, absorbed,
        jid)``: branch ``absorbed`` (maybe equal to ``kept`` for a loop) and the
        junction's points now belong to branch ``kept``.
        """
        if not self.is_end_branch(b):
            raise ValueError(f"branch {b} is not an end branch")
        br = self.branches[b]
        br.alive = False
        self.ends.discard(b)
        self.steps = add_steps(self.steps, br.steps, -1)
        e = 0 if br.node[0] is not None else 1
        jid = br.node[e]
        assert jid is not None
        junc = self.junctions[jid]
        junc.ends.remove((b, e))
        if len(junc.ends) != 2:
            return None
        merged = self._dissolve(jid)
        if merged is not None:
            kept, absorbed = merged[0], merged[1]
            self.ends.discard(absorbed)
            if self.is_end_branch(kept):
                self.ends.add(kept)
            else:
                self.ends.discard(kept)
        return merged

    def _cluster_path(self, jid: int, a: int, z: int) -> tuple[list[int], Steps]:
        """Shortest path from point ``a`` to ``z`` inside junction cluster ``jid``, and
        its steps of each kind."""
        counts = [0] * self.weights.size
        if a == z:  # (most clusters: one point, a tip's own attach point)
            return [a], tuple(counts)
        members = set(self.junctions[jid].points)
        best: dict[int, float] = {a: 0.0}
        prev: dict[int, tuple[int, int]] = {}
        heap = [(0.0, a)]
        nbr = self.nbr
        kind_of = self.slot_kind.tolist()
        weights = self.weights.tolist()
        while heap:
            d, u = heapq.heappop(heap)
            if u == z or d > best[u]:
                continue
            for i, q in enumerate(nbr[u].tolist()):
                if q < 0 or q not in members:
                    continue
                kind = kind_of[i]
                nd = d + weights[kind]
                if nd < best.get(q, math.inf) - 1e-12:
                    best[q] = nd
                    prev[q] = (u, kind)
                    heapq.heappush(heap, (nd, q))
        path = [z]
        while path[-1] != a:
            u, kind = prev[path[-1]]
            counts[kind] += 1
            path.append(u)
        return path[::-1], tuple(counts)

    def _dissolve(self, jid: int) -> tuple[int, int, int] | None:
        """A junction with at most two branch ends becomes ordinary points."""
        junc = self.junctions[jid]
        junc.alive = False
        ends = list(junc.ends)
        junc.ends.clear()
        if not ends:  # an isolated blob of junction points: one branch, two free ends
            no_steps = (0,) * self.weights.size
            self.branches.append(
                Branch(list(junc.points), [None, None], [-1, -1], no_steps, side=junc.points[1:])
            )
            return None
        if len(ends) == 1:  # the cluster is the tip of a branch
            b, e = ends[0]
            br = self.branches[b]
            path = [br.attach[e]]
            rest = [p for p in junc.points if p not in path]
            tip = path + rest
            br.points = br.points + tip if e == 1 else tip[::-1] + br.points
            br.side = br.side + rest
            br.node[e], br.attach[e] = None, -1
            return None
        (b1, e1), (b2, e2) = ends
        if b1 == b2:  # a loop through the junction closes into a cycle
            br = self.branches[b1]
            path, st = self._cluster_path(jid, br.attach[1], br.attach[0])
            moved = list(dict.fromkeys(path + list(junc.points)))
            br.points = br.points + moved
            br.side = br.side + moved[len(path) :]
            br.steps = add_steps(br.steps, st)
            self.steps = add_steps(self.steps, st)
            br.node, br.attach, br.loop = [None, None], [-1, -1], True
            return b1, b1, jid
        # Keep the branch with more points: the absorbed one is the owner the coverage
        # relabels, at the cost of its disks' (balls') area.
        if len(self.branches[b2].points) > len(self.branches[b1].points):
            (b1, e1), (b2, e2) = (b2, e2), (b1, e1)
        k, a = self.branches[b1], self.branches[b2]
        kp = k.points if e1 == 1 else k.points[::-1]
        kn = [k.node[1 - e1], None]
        kt = [k.attach[1 - e1], -1]
        ap = a.points if e2 == 0 else a.points[::-1]
        path, st = self._cluster_path(jid, k.attach[e1], a.attach[e2])
        rest = [p for p in junc.points if p not in path]
        k.points = kp + path + rest + ap
        k.side = k.side + rest + a.side
        k.node = [kn[0], a.node[1 - e2]]
        k.attach = [kt[0], a.attach[1 - e2]]
        k.steps = add_steps(add_steps(k.steps, a.steps), st)
        self.steps = add_steps(self.steps, st)
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


#: The graph type of one grid's axis.
G = TypeVar("G", bound=PointGraph)


class AxisOnGraph(Generic[G]):
    """What a grid's axis (a frozen dataclass with a ``graph`` field) answers from its
    graph alone, the same on every grid."""

    graph: G

    def working_graph(self) -> G:
        """A copy of the graph that a stage may change."""
        return self.graph.copy()

    def with_graph(self, graph: G) -> Self:
        """The same shape and points with another graph over them (a stage's answer)."""
        return replace(self, graph=graph)  # type: ignore[type-var]

    @property
    def length(self) -> float:
        """Total length of the branches (:func:`~.grid.path_length` of their steps)."""
        return self.graph.total_length()

    @property
    def n_endpoints(self) -> int:
        return self.graph.n_endpoints()

    @property
    def n_points(self) -> int:
        """Points in this skeleton."""
        return int(self.graph.alive_points().size)

    def end_branches(self) -> list[int]:
        """Ids of the end branches (docs/algorithm.md), sorted."""
        return self.graph.end_branches()

    def points(self) -> np.ndarray:
        """Indices of the points in this skeleton, sorted."""
        return self.graph.alive_points()
