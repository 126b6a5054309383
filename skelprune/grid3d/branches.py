"""The mutable branch graph of a curve skeleton: what the pruning removes branches from.

:class:`VolumeBranchGraph` is the volume grid's :class:`~skelprune.pruning.grid.GridGraph`,
the counterpart of :class:`skelprune.grid.graph.BranchGraph` with 26 neighbours and seven
step kinds, under the same rules (docs/algorithm.md, docs/volumes.md): junction clusters
are 26-connected voxels with three or more neighbours; a cluster left with two branch
ends is dissolved and its two branches become one through the cluster's shortest path
(the branch with more points is kept, the other absorbed), the cluster's other voxels
going with it beside the path; a cluster with one branch end becomes that branch's tip.
Every skeleton voxel belongs to exactly one live branch or junction, so the balls the
pruning weighs are all the skeleton's.
"""

from __future__ import annotations

import heapq
import itertools
import math
from dataclasses import dataclass, field

import numpy as np

from ._topology import STEP_KINDS, step_lengths
from .distance import check_spacing
from .graph import _clusters, _trace, neighbour_table

__all__ = ["VolumeBranch", "VolumeBranchGraph"]

Steps = tuple[int, int, int, int, int, int, int]
NO_STEPS: Steps = (0, 0, 0, 0, 0, 0, 0)
_KIND = {tuple(int(v) for v in k): i for i, k in enumerate(STEP_KINDS)}


def _add(a: Steps, b: Steps, sign: int = 1) -> Steps:
    return tuple(u + sign * v for u, v in zip(a, b, strict=True))  # type: ignore[return-value]


@dataclass
class VolumeBranch:
    """A branch: ordered voxels (``side``: those beside its path, from dissolved
    clusters), the junction of each end (``None``: a free end) and the junction voxel
    it touches, and its steps of each kind. Lists are replaced, never changed in place."""

    points: list[int]
    node: list[int | None]
    attach: list[int]
    steps: Steps
    loop: bool = False
    alive: bool = True
    side: list[int] = field(default_factory=list)


@dataclass
class VolumeJunction:
    points: list[int]
    ends: list[tuple[int, int]] = field(default_factory=list)  # (branch, end index)
    alive: bool = True


class VolumeBranchGraph:
    """Mutable branch graph of a one-voxel-thin, 26-connected skeleton.

    Parameters
    ----------
    z, y, x : (n,) int arrays
        Skeleton voxels.
    spacing : (dz, dy, dx)
        Physical size of a voxel (for the shortest paths through junction clusters).

    Examples
    --------
    >>> y = np.array([5, 5, 5, 5, 5, 4, 3, 6, 7])
    >>> x = np.array([1, 2, 3, 4, 5, 6, 7, 6, 7])
    >>> g = VolumeBranchGraph(np.zeros(9, int), y, x)                 # a Y
    >>> g.end_branches(), g.total_steps()
    ([0, 1, 2], (4, 0, 4, 0, 0, 0, 0))
    >>> g.remove_end_branch(1)   # the other two merge through the junction voxel
    (0, 2, 0)
    >>> g.end_branches(), g.n_endpoints()
    ([], 2)
    """

    def __init__(
        self,
        z: np.ndarray,
        y: np.ndarray,
        x: np.ndarray,
        spacing: tuple[float, float, float] = (1.0, 1.0, 1.0),
    ) -> None:
        self.z = np.asarray(z, np.int64)
        self.y = np.asarray(y, np.int64)
        self.x = np.asarray(x, np.int64)
        self.spacing = check_spacing(spacing)
        self.weights = step_lengths(self.spacing)
        n = self.z.size
        self.nbr = neighbour_table(self.z, self.y, self.x) if n else np.zeros((0, 26), np.int64)
        self.degree = (self.nbr >= 0).sum(axis=1)
        self.branches: list[VolumeBranch] = []
        self.junctions: list[VolumeJunction] = []
        self.steps: Steps = NO_STEPS
        self._build()

    def _build(self) -> None:
        cluster, n_clusters = _clusters(self.nbr, self.degree)
        pts, starts, att, counts = _trace(self.nbr, self.degree, self.z, self.y, self.x)
        members: list[list[int]] = [[] for _ in range(int(n_clusters))]
        for p in np.flatnonzero(cluster >= 0).tolist():
            members[int(cluster[p])].append(p)
        self.junctions = [VolumeJunction(m) for m in members]
        jof = cluster.tolist()
        for b, ((a0, a1), st) in enumerate(zip(att.tolist(), counts.tolist(), strict=True)):
            seg = pts[starts[b] : starts[b + 1]].tolist()
            steps: Steps = tuple(st)  # type: ignore[assignment]
            if a0 == -2:
                self.branches.append(VolumeBranch(seg, [None, None], [-1, -1], steps, loop=True))
                continue
            nodes = [jof[a0] if a0 >= 0 else None, jof[a1] if a1 >= 0 else None]
            self.branches.append(VolumeBranch(seg, nodes, [a0, a1], steps))
            for e in (0, 1):
                node = nodes[e]
                if node is not None:
                    self.junctions[node].ends.append((b, e))
        for jid, junc in enumerate(self.junctions):
            if len(junc.ends) <= 2:
                self._dissolve(jid)
        self.ends = {b for b in range(len(self.branches)) if self.is_end_branch(b)}
        total = NO_STEPS
        for br in self.branches:
            if br.alive:
                total = _add(total, br.steps)
        self.steps = total

    def copy(self) -> VolumeBranchGraph:
        """An independent copy (point arrays and replaced-only lists shared)."""
        g = object.__new__(VolumeBranchGraph)
        g.__dict__.update(self.__dict__)
        g.branches = [
            VolumeBranch(b.points, list(b.node), list(b.attach), b.steps, b.loop, True, b.side)
            if b.alive
            else b
            for b in self.branches
        ]
        g.junctions = [
            VolumeJunction(j.points, list(j.ends), True) if j.alive else j for j in self.junctions
        ]
        g.ends = set(self.ends)
        return g

    # -- the grid interface --------------------------------------------------------
    @property
    def coords(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(z, y, x)``: the tie order of end branches."""
        return self.z, self.y, self.x

    def is_end_branch(self, b: int) -> bool:
        br = self.branches[b]
        return br.alive and not br.loop and (br.node[0] is None) != (br.node[1] is None)

    def end_branches(self) -> list[int]:
        return sorted(self.ends)

    def endpoint(self, b: int) -> int:
        br = self.branches[b]
        return br.points[0] if br.node[0] is None else br.points[-1]

    def branch_steps(self, b: int) -> Steps:
        return self.branches[b].steps

    def total_steps(self) -> Steps:
        return self.steps

    def alive_points(self) -> np.ndarray:
        keep: list[int] = []
        for br in self.branches:
            if br.alive:
                keep.extend(br.points)
        for junc in self.junctions:
            if junc.alive:
                keep.extend(junc.points)
        out = np.fromiter(keep, np.int64, len(keep))
        out.sort()
        return out

    def n_endpoints(self) -> int:
        """Free branch ends (a lone voxel counted once)."""
        n = 0
        for br in self.branches:
            if br.alive and not br.loop:
                free = (br.node[0] is None) + (br.node[1] is None)
                n += 1 if free == 2 and len(br.points) == 1 else free
        return n

    def path(self, b: int) -> list[int]:
        """Branch ``b``'s points without those beside its path, in order."""
        br = self.branches[b]
        off = set(br.side)
        return [p for p in br.points if p not in off]

    def counts_without(self, b: int) -> Steps:
        br = self.branches[b]
        e = 0 if br.node[0] is not None else 1
        jid = br.node[e]
        assert jid is not None
        steps = _add(self.steps, br.steps, -1)
        rest = [end for end in self.junctions[jid].ends if end != (b, e)]
        if len(rest) == 2:
            (b1, e1), (b2, e2) = rest
            _, st = self._cluster_path(
                jid, self.branches[b1].attach[e1], self.branches[b2].attach[e2]
            )
            steps = _add(steps, st)
        return steps

    def free_ends(self) -> list[tuple[int, int]]:
        """``(branch, end)`` of every free end a tip cut may shorten: the free end of each
        end branch and both ends of a single path of two voxels or more."""
        out = []
        for b, br in enumerate(self.branches):
            if not br.alive or br.loop:
                continue
            free = [e for e in (0, 1) if br.node[e] is None]
            if len(free) == 1 or (len(free) == 2 and len(self.path(b)) > 1):
                out.extend((b, e) for e in free)
        return out

    def free_end_point(self, b: int, e: int) -> int:
        path = self.path(b)
        return path[0] if e == 0 else path[-1]

    def tip(self, b: int, e: int) -> tuple[list[int], list[int], list[int]]:
        """Branch ``b`` seen from its free end ``e``: its points, the drop index of each
        (a cut of ``k`` drops those below ``k``; the path's ``i``-th point from the end
        has ``i``, a voxel beside the path goes with the last path point it touches,
        directly or through other such voxels) and the step kind of each step of the
        path from the end."""
        path = self.path(b)
        if e == 1:
            path = path[::-1]
        kinds = [self._step(p, q) for p, q in itertools.pairwise(path)]
        index = {p: i for i, p in enumerate(path)}
        side = [p for p in self.branches[b].points if p not in index]
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

    # -- mutation ------------------------------------------------------------------
    def cut_tip(self, b: int, e: int, gone: list[int], steps: Steps) -> None:
        """Drop voxels ``gone`` from the free end ``e`` of branch ``b``, with ``steps``."""
        br = self.branches[b]
        out = set(gone)
        br.points = [p for p in br.points if p not in out]
        br.side = [p for p in br.side if p not in out]
        br.steps = _add(br.steps, steps, -1)
        self.steps = _add(self.steps, steps, -1)

    def remove_end_branch(self, b: int) -> tuple[int, int, int] | None:
        """Remove end branch ``b``; ``(kept, absorbed, junction)`` when its junction was
        dissolved and branch ``absorbed`` and the junction's voxels joined ``kept``."""
        if not self.is_end_branch(b):
            raise ValueError(f"branch {b} is not an end branch")
        br = self.branches[b]
        br.alive = False
        self.ends.discard(b)
        self.steps = _add(self.steps, br.steps, -1)
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

    def _step(self, u: int, v: int) -> int:
        key = (
            abs(int(self.z[u] - self.z[v])),
            abs(int(self.y[u] - self.y[v])),
            abs(int(self.x[u] - self.x[v])),
        )
        return _KIND[key]

    def _cluster_path(self, jid: int, a: int, z: int) -> tuple[list[int], Steps]:
        """Shortest path (physical length) from voxel ``a`` to ``z`` inside cluster
        ``jid``, and its steps of each kind."""
        if a == z:
            return [a], NO_STEPS
        members = set(self.junctions[jid].points)
        best: dict[int, float] = {a: 0.0}
        prev: dict[int, int] = {}
        heap = [(0.0, a)]
        weights = self.weights.tolist()
        while heap:
            d, u = heapq.heappop(heap)
            if u == z or d > best[u]:
                continue
            for q in self.nbr[u].tolist():
                if q < 0 or q not in members:
                    continue
                nd = d + weights[self._step(u, q)]
                if nd < best.get(q, math.inf) - 1e-12:
                    best[q] = nd
                    prev[q] = u
                    heapq.heappush(heap, (nd, q))
        path = [z]
        counts = [0] * 7
        while path[-1] != a:
            u = prev[path[-1]]
            counts[self._step(u, path[-1])] += 1
            path.append(u)
        return path[::-1], tuple(counts)  # type: ignore[return-value]

    def _dissolve(self, jid: int) -> tuple[int, int, int] | None:
        """A junction with at most two branch ends becomes ordinary voxels."""
        junc = self.junctions[jid]
        junc.alive = False
        ends = list(junc.ends)
        junc.ends.clear()
        if not ends:  # a blob (or a shell around a cavity): one branch, two free ends
            self.branches.append(
                VolumeBranch(
                    list(junc.points), [None, None], [-1, -1], NO_STEPS, side=junc.points[1:]
                )
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
            br.steps = _add(br.steps, st)
            self.steps = _add(self.steps, st)
            br.node, br.attach, br.loop = [None, None], [-1, -1], True
            return b1, b1, jid
        # Keep the branch with more points: the absorbed one is the owner the coverage
        # relabels, at the cost of its balls' volume.
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
        k.steps = _add(_add(k.steps, a.steps), st)
        self.steps = _add(self.steps, st)
        a.alive = False
        near, far = kn[0], a.node[1 - e2]
        if near is not None and e1 == 0:
            nj = self.junctions[near]
            nj.ends[nj.ends.index((b1, 1))] = (b1, 0)
        if far is not None:
            fj = self.junctions[far]
            fj.ends[fj.ends.index((b2, 1 - e2))] = (b1, 1)
        return b1, b2, jid
