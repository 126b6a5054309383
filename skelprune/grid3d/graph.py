"""Branch graph of a curve skeleton in a volume (docs/volumes.md).

Voxels with three or more 26-neighbours are junction voxels; 26-adjacent junction
voxels form one junction cluster. Branches are the voxel paths between clusters and
free ends, ordered, each with the junction voxel each end attaches to; a path with no
junction at all is one branch with two free ends, and a cycle with none a loop branch.
As in the image graph, a cluster left with two branch ends (a sharp turn of a path) is
dissolved and its two branches become one through it; a cluster with one branch end
becomes that branch's free end.

Paths are kept flat (CSR: one array of point indices, an offset per branch) and
lengths as integer counts of the seven step kinds of :data:`~._topology.STEP_KINDS`,
turned into physical lengths in one place (:func:`~._topology.step_lengths`).
"""

from __future__ import annotations

from collections import deque

import numpy as np

from ..pruning._trace import junction_clusters, path_kinds, trace_branches
from ..pruning.branch_graph import GridSteps, PointGraph
from ._topology import OFFSETS, step_lengths
from .distance import check_spacing

__all__ = ["SLOT_KINDS", "VolumeBranchGraph", "VolumeGraph", "euler_characteristic"]


def neighbour_table(z: np.ndarray, y: np.ndarray, x: np.ndarray) -> np.ndarray:
    """(n, 26) index of each point's 26-neighbours among the points, in the slot order
    of ``OFFSETS`` (-1: none)."""
    if z.size == 0:
        return np.zeros((0, 26), np.int64)
    ny, nx = int(y.max()) + 3, int(x.max()) + 3  # room for the offsets
    key = ((z + 1) * ny + (y + 1)) * nx + (x + 1)
    order = np.argsort(key, kind="stable")
    sorted_key = key[order]
    cand = key[:, None] + (OFFSETS[:, 0] * ny * nx + OFFSETS[:, 1] * nx + OFFSETS[:, 2])[None, :]
    pos = np.minimum(np.searchsorted(sorted_key, cand), key.size - 1)
    return np.where(sorted_key[pos] == cand, order[pos], -1)


#: The volume grid's steps: slot ``i`` of the 26-neighbour table (:data:`~._topology.OFFSETS`)
#: is a step of kind ``4·|dz| + 2·|dy| + |dx| − 1`` (:data:`~._topology.STEP_KINDS`).
SLOT_KINDS = (np.abs(OFFSETS) @ np.array([4, 2, 1]) - 1).astype(np.int64)


class VolumeGraph:
    """Branch graph of a one-voxel-thin, 26-connected skeleton.

    Parameters
    ----------
    z, y, x : (n,) int arrays
        Skeleton voxels (e.g. a :class:`~.medial_axis.CurveSkeleton`'s).
    spacing : (dz, dy, dx)
        Physical size of a voxel: the branches' lengths are in its units.

    Attributes
    ----------
    nbr : (n, 26) int64
        Each point's 26-neighbours among the points (-1: none); ``degree`` their number.
    junction_of : (n,) int64
        The junction each point belongs to (-1: none).
    junctions : list of (k,) int64 arrays
        The points of each junction (clusters with three or more branch ends, or none
        at all: a blob, or a shell around a cavity).
    path_points, path_offsets : int64 arrays
        Branch ``b``'s points, ordered, are ``path_points[path_offsets[b]:path_offsets[b + 1]]``.
    ends : (m, 2) int64
        The junction each end of a branch attaches to (-1: a free end, an end point).
    attach : (m, 2) int64
        The junction point each end touches (-1: none).
    steps : (m, 7) int64
        Steps of each kind along the branch, the steps into its junction points included.
    loop : (m,) bool
        A closed branch without junction.

    Examples
    --------
    >>> y = np.array([5, 5, 5, 5, 5, 4, 3, 6, 7])
    >>> x = np.array([1, 2, 3, 4, 5, 6, 7, 6, 7])
    >>> g = VolumeGraph(np.zeros(9, int), y, x)                       # a Y
    >>> len(g.junctions), g.n_endpoints, g.n_cycles, g.length().round(3).tolist()
    (1, 3, 0, [2.828, 4.0, 2.828])
    """

    def __init__(
        self,
        z: np.ndarray,
        y: np.ndarray,
        x: np.ndarray,
        spacing: tuple[float, float, float] = (1.0, 1.0, 1.0),
    ) -> None:
        self.z = np.asarray(z, dtype=np.int64)
        self.y = np.asarray(y, dtype=np.int64)
        self.x = np.asarray(x, dtype=np.int64)
        self.spacing = check_spacing(spacing)
        self.nbr = neighbour_table(self.z, self.y, self.x)
        self.degree = (self.nbr >= 0).sum(axis=1)
        cluster, n_clusters = junction_clusters(self.nbr, self.degree)
        pts, starts, att, counts = trace_branches(self.nbr, self.degree, SLOT_KINDS, 7)
        self._build(cluster, int(n_clusters), pts, starts, att, counts)

    # -- construction --------------------------------------------------------------
    def _build(self, cluster, n_clusters, pts, starts, att, counts) -> None:
        paths = [pts[starts[b] : starts[b + 1]].tolist() for b in range(starts.size - 1)]
        ends = [[-2, -2] if a0 == -2 else [a0, a1] for a0, a1 in att.tolist()]
        steps = [c for c in counts]
        alive = [True] * len(paths)
        loop = [a0 == -2 for a0, _ in att.tolist()]
        members: list[list[int]] = [[] for _ in range(n_clusters)]
        for p in np.flatnonzero(cluster >= 0).tolist():
            members[int(cluster[p])].append(p)
        at: list[list[tuple[int, int]]] = [[] for _ in range(n_clusters)]
        for b, (a0, a1) in enumerate(ends):
            for e, a in ((0, a0), (1, a1)):
                if a >= 0:
                    at[int(cluster[a])].append((b, e))

        def cluster_path(cid: int, a: int, b: int) -> tuple[list[int], np.ndarray]:
            """Shortest path of cluster points from ``a`` to ``b`` and its steps."""
            inside = set(members[cid])
            back = {a: -1}
            todo = deque([a])
            while todo:
                u = todo.popleft()
                if u == b:
                    break
                for q in self.nbr[u].tolist():
                    if q in inside and q not in back:
                        back[q] = u
                        todo.append(q)
            path = [b]
            while back[path[-1]] != -1:
                path.append(back[path[-1]])
            path.reverse()
            kinds = path_kinds(self.nbr, SLOT_KINDS, np.asarray(path, np.int64))
            return path, np.bincount(kinds, minlength=7).astype(np.int64)

        for cid in range(n_clusters):
            here = [(b, e) for b, e in at[cid] if alive[b]]
            if len(here) not in (1, 2):
                continue
            if len(here) == 1:  # the branch ends in the cluster: its far voxel is the end
                (b, e), a = here[0], ends[here[0][0]][here[0][1]]
                far = max(members[cid], key=lambda q: (len(cluster_path(cid, a, q)[0]), -q))
                path, st = cluster_path(cid, a, far)
                paths[b] = paths[b] + path if e == 1 else path[::-1] + paths[b]
                steps[b] = steps[b] + st
                ends[b][e] = -1
                continue
            (b1, e1), (b2, e2) = here
            path, st = cluster_path(cid, ends[b1][e1], ends[b2][e2])
            if b1 == b2:  # both ends of one branch: a loop
                paths[b1] = paths[b1] + path if e1 == 1 else path + paths[b1]
                steps[b1] = steps[b1] + st
                ends[b1] = [-2, -2]
                loop[b1] = True
                continue
            first = paths[b1] if e1 == 1 else paths[b1][::-1]
            last = paths[b2] if e2 == 0 else paths[b2][::-1]
            keep = [ends[b1][1 - e1], ends[b2][1 - e2]]
            alive[b1] = alive[b2] = False
            nb = len(paths)
            paths.append(first + path + last)
            steps.append(steps[b1] + steps[b2] + st)
            ends.append(keep)
            loop.append(False)
            alive.append(True)
            for e, a in enumerate(keep):
                if a >= 0:
                    c = int(cluster[a])
                    old = (b1, 1 - e1) if e == 0 else (b2, 1 - e2)
                    at[c] = [(nb, e) if be == old else be for be in at[c]]
        kept = [b for b in range(len(paths)) if alive[b]]
        used = sorted({int(cluster[a]) for b in kept for a in ends[b] if a >= 0})
        used += [c for c in range(n_clusters) if not at[c]]  # blobs and shells
        renumber = {c: i for i, c in enumerate(sorted(used))}
        self.junctions = [np.array(members[c], dtype=np.int64) for c in sorted(used)]
        self.junction_of = np.full(self.z.size, -1, dtype=np.int64)
        for c, i in renumber.items():
            self.junction_of[members[c]] = i
        lengths = [len(paths[b]) for b in kept]
        self.path_offsets = np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64)
        self.path_points = np.array([p for b in kept for p in paths[b]], dtype=np.int64)
        self.attach = np.array([[max(a, -1) for a in ends[b]] for b in kept], np.int64).reshape(
            -1, 2
        )
        self.ends = np.where(self.attach >= 0, self.junction_of[np.maximum(self.attach, 0)], -1)
        self.steps = np.array([steps[b] for b in kept], dtype=np.int64).reshape(-1, 7)
        self.loop = np.array([loop[b] for b in kept], dtype=bool)

    # -- queries -------------------------------------------------------------------
    def __len__(self) -> int:
        """The number of branches."""
        return int(self.loop.size)

    def path(self, b: int) -> np.ndarray:
        """The points of branch ``b``, in order."""
        return self.path_points[self.path_offsets[b] : self.path_offsets[b + 1]]

    def length(self) -> np.ndarray:
        """Each branch's length in physical units."""
        return self.steps @ step_lengths(self.spacing)

    def end_points(self) -> np.ndarray:
        """The points at free ends of branches (a lone voxel counted once)."""
        out = []
        for b in range(len(self)):
            if self.loop[b]:
                continue
            p = self.path(b)
            for e in (0, 1):
                if self.ends[b, e] < 0 and not (e == 1 and p.size == 1 and self.ends[b, 0] < 0):
                    out.append(int(p[0] if e == 0 else p[-1]))
        return np.array(out, dtype=np.int64)

    @property
    def n_endpoints(self) -> int:
        return int(self.end_points().size)

    @property
    def n_components(self) -> int:
        """The number of 26-connected components of the skeleton."""
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import connected_components

        n = self.z.size
        rows, cols = np.nonzero(self.nbr >= 0)
        adj = coo_matrix((np.ones(rows.size), (rows, self.nbr[rows, cols])), shape=(n, n))
        return int(connected_components(adj, directed=False)[0])

    @property
    def n_cycles(self) -> int:
        """Independent cycles of the skeleton, ``C − χ`` (:func:`euler_characteristic`):
        for a skeleton without cavity, the number of tunnels of the volume it was made
        from. Unlike :attr:`graph_cycles`, this counts cycles inside junction clusters."""
        return self.n_components - euler_characteristic(self.z, self.y, self.x)

    @property
    def graph_cycles(self) -> int:
        """Independent cycles of the branch graph, ``E − V + C``, junctions contracted
        to nodes: :attr:`n_cycles` less the cycles inside junction clusters."""
        lone = sum(
            1
            for b in range(len(self))
            if not self.loop[b] and (self.ends[b] < 0).all() and self.path(b).size == 1
        )
        edges = len(self) - lone
        nodes = len(self.junctions) + self.n_endpoints + int(self.loop.sum())
        return edges - nodes + self.n_components


def euler_characteristic(z: np.ndarray, y: np.ndarray, x: np.ndarray) -> int:
    """Euler characteristic of a set of voxels with 26-connectivity (6 for the background).

    The voxels as closed unit cubes have that topology: ``χ = V − E + F − N`` over the
    corners, edges, faces and cubes of their union. Components − tunnels + cavities.

    >>> ring = np.array([[0, 0, 0], [0, 0, 1], [0, 1, 2], [0, 2, 1], [0, 2, 0], [0, 1, -1]])
    >>> euler_characteristic(*ring.T)                                 # one cycle
    0
    """
    z, y, x = (np.asarray(a, np.int64) for a in (z, y, x))
    if z.size == 0:
        return 0
    base = np.column_stack([z - z.min(), y - y.min(), x - x.min()])
    dims = base.max(axis=0) + 2

    def count(corners: list[tuple[int, int, int]], tag: int) -> int:
        keys = [
            (((base[:, 0] + c[0]) * dims[1] + base[:, 1] + c[1]) * dims[2] + base[:, 2] + c[2]) * 4
            + tag
            for c in corners
        ]
        return int(np.unique(np.concatenate(keys)).size)

    corners = [(a, b, c) for a in (0, 1) for b in (0, 1) for c in (0, 1)]
    n_vertices = count(corners, 3)
    n_edges = sum(count([c for c in corners if c[a] == 0], a) for a in range(3))
    n_faces = sum(
        count([c for c in corners if all(c[i] == 0 for i in range(3) if i != a)], a)
        for a in range(3)
    )
    return n_vertices - n_edges + n_faces - int(z.size)


class VolumeBranchGraph(PointGraph):
    """The mutable branch graph the pruning removes branches from: the one branch graph
    of every grid (:class:`~skelprune.pruning.branch_graph.PointGraph`) over the voxels'
    26-neighbour table, with the seven step kinds of :data:`~._topology.STEP_KINDS`.

    Junction clusters are 26-connected voxels with three or more neighbours; a cluster
    left with two branch ends is dissolved and its two branches become one through the
    cluster's shortest path (physical length), the cluster's other voxels going with it
    beside the path; a cluster with one branch end becomes that branch's tip. Every
    skeleton voxel belongs to exactly one live branch or junction, so the balls the
    pruning weighs are all the skeleton's.

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
        nbr = neighbour_table(self.z, self.y, self.x)
        super().__init__(nbr, GridSteps(SLOT_KINDS, step_lengths(self.spacing)))

    @property
    def coords(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(z, y, x)``: the tie order of end branches."""
        return self.z, self.y, self.x
