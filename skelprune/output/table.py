"""The branch table: a pruned skeleton as flat arrays, the one source of every output.

A component's answer is read out of its mutable branch graph
(:class:`~skelprune.pruning.branch_graph.PointGraph`, of an image or of a volume) once,
into a :class:`BranchTable`: coordinate columns (``x``, ``y``, for a volume ``z``, and
``radius`` of every skeleton point) and, per node and per branch, a row of plain arrays,
with each branch's path and off-path points (and each junction's cluster) as offsets
into index arrays over the coordinates (compressed sparse rows, as skan's ``Skeleton``
keeps its paths). An image's table is in image pixel coordinates
(:func:`branch_table`), a volume's in voxel indices of the whole volume with physical
radii and lengths (:func:`volume_table`); both are built by :func:`graph_table`. The
documents, the GeoJSON, the tables, the networkx graphs, SWC and the overlays' marks
are views of it; a frame to the caller's coordinates is applied to an image's
coordinate columns once (:meth:`BranchTable.framed`), and not at all for the identity
frame.

Examples
--------
>>> import skelprune
>>> m = np.zeros((80, 180), bool); m[10:70, 10:170] = True
>>> t = skelprune.prune(m).components[0].table
>>> t.n_nodes, t.n_branches, t.kinds().count("endpoint")
(6, 5, 4)
>>> t.path(0).shape[1]  # x, y, radius of each pixel of branch 0's path
3
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from ..io.frame import IDENTITY, PixelFrame

if TYPE_CHECKING:
    from ..grid3d.skeleton import VolumeSkeleton
    from ..pruning.branch_graph import PointGraph
    from ..pruning.margin import Margins
    from ..skeleton import Skeleton

__all__ = [
    "ENDPOINT",
    "JUNCTION",
    "KINDS",
    "LOOP",
    "BranchTable",
    "branch_table",
    "frame_distances",
    "frame_points",
    "graph_table",
    "nullable",
    "round_like_python",
    "volume_table",
]

#: Node kinds, by their code in :attr:`BranchTable.node_kind`.
#: A node's kind, as the document names it.
NodeKind = Literal["endpoint", "junction", "loop"]
KINDS: tuple[NodeKind, ...] = ("endpoint", "junction", "loop")
ENDPOINT, JUNCTION, LOOP = range(3)


def _csr(parts: list[list[int]]) -> tuple[np.ndarray, np.ndarray]:
    """Concatenated index lists and their offsets (``offsets[i]:offsets[i + 1]``)."""
    ends = list(itertools.accumulate(map(len, parts), initial=0))
    flat = np.fromiter(itertools.chain.from_iterable(parts), np.int64, ends[-1])
    return flat, np.array(ends, np.int64)


def nullable(values: np.ndarray, missing: float) -> list[Any]:
    """``values`` as a list with None where a value is ``missing`` (NaN for NaN): the one
    place where an array's missing values become the document's nulls."""
    gone = np.isnan(values) if missing != missing else values == missing
    out = values.tolist()
    for i in np.flatnonzero(gone).tolist():
        out[i] = None
    return out


def frame_points(frame: PixelFrame, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pixel centres ``(x, y)`` mapped by ``frame``, as :meth:`PixelFrame.point` maps
    them one by one (the same arithmetic and rounding); unchanged for the identity."""
    if frame == IDENTITY:
        return x, y
    ps = frame.pixel_size
    fx = frame.x0 + x * ps
    fy = frame.y0 - y * ps if frame.flip_y else frame.y0 + y * ps
    return _rounded(fx, frame), _rounded(fy, frame)


def frame_distances(frame: PixelFrame, d: np.ndarray) -> np.ndarray:
    """Lengths and radii scaled by ``frame`` (:meth:`PixelFrame.distance`)."""
    if frame == IDENTITY:
        return d
    return _rounded(d * frame.pixel_size, frame)


def round_like_python(v: np.ndarray, n: int) -> np.ndarray:
    """``round(a, n)`` of every element, exactly as Python rounds a float, without a
    Python call for each.

    Python rounds correctly (the exact binary value, ties to even); ``np.round`` scales,
    rounds and unscales, and differs in the last place now and then. Here the scaled
    value ``p = v·10ⁿ`` is rounded to an integer ``m`` and ``m / 10ⁿ`` (one correctly
    rounded division) is the double nearest the decimal ``m·10⁻ⁿ``, which is what Python
    returns; ``p`` carries a rounding error of half an ulp, so only where ``p`` lies that
    close to a half-integer could ``m`` be the wrong neighbour, and those few elements
    (and any the scaling cannot hold exactly) go to Python's own ``round``.

    >>> v = np.array([2.675, 0.125, 1.0000000000000002, -3.14159, 15.049999999999997])
    >>> round_like_python(v, 2).tolist() == [round(a, 2) for a in v.tolist()]
    True
    """
    v = np.asarray(v, np.float64)
    if n < 0 or n > 22:  # 10ⁿ exact only for 0 ≤ n ≤ 22
        return np.array([round(a, n) for a in v.tolist()], np.float64).reshape(v.shape)
    scale = float(10**n)
    p = v * scale
    m = np.rint(p)
    near_half = np.abs(np.abs(p - np.floor(p)) - 0.5) <= np.abs(p) * 2.3e-16 + 1e-300
    doubt = near_half | ~(np.abs(p) < 2.0**52)
    out = m / scale
    for i in np.flatnonzero(doubt).tolist():
        out.flat[i] = round(float(v.flat[i]), n)
    return out


def _rounded(v: np.ndarray, frame: PixelFrame) -> np.ndarray:
    # correctly rounded as Python's round: the document's numbers must not move
    return round_like_python(v, frame.decimals)


@dataclass(frozen=True)
class BranchTable:
    """Nodes and branches of a skeleton as flat arrays (see the module's docstring).

    Node ``i`` sits at point ``node_point[i]``; a junction's cluster is
    ``members[member_offsets[i]:member_offsets[i + 1]]`` (empty for endpoints and
    loops). Branch ``j`` runs from node ``source[j]`` to ``target[j]`` along
    ``paths[path_offsets[j]:path_offsets[j + 1]]``, with its pixels beside the path
    (of a dissolved junction cluster) in ``off_path[off_offsets[j]:off_offsets[j + 1]]``.
    ``margin`` is NaN and ``removed_at`` -1 where the document says null, ``source`` and
    ``target`` -1 for a loop of a table without loop nodes (a volume's).
    ``graph_branch`` and ``node_junction`` are the graph's own ids of each branch and
    junction node (-1: not a junction), which the pruning sequence's events name.
    """

    #: Image column, row and radius of every pixel of the graph (pixels indexed as the
    #: graph's points); for a volume, voxel x, y (``z`` below) and physical radius.
    x: np.ndarray
    y: np.ndarray
    radius: np.ndarray
    node_point: np.ndarray
    node_kind: np.ndarray
    node_junction: np.ndarray
    members: np.ndarray
    member_offsets: np.ndarray
    source: np.ndarray
    target: np.ndarray
    length: np.ndarray
    margin: np.ndarray
    removed_at: np.ndarray
    graph_branch: np.ndarray
    paths: np.ndarray
    path_offsets: np.ndarray
    off_path: np.ndarray
    off_offsets: np.ndarray
    #: A volume's third coordinate (the array's first axis); None in the plane.
    z: np.ndarray | None = None

    @property
    def ndim(self) -> int:
        """2 for an image's table, 3 for a volume's."""
        return 2 if self.z is None else 3

    @property
    def n_nodes(self) -> int:
        return int(self.node_point.size)

    @property
    def n_branches(self) -> int:
        return int(self.source.size)

    def kinds(self) -> list[NodeKind]:
        """Each node's kind, as the document names it."""
        return [KINDS[k] for k in self.node_kind.tolist()]

    def pixels(self) -> np.ndarray:
        """Indices of the skeleton's pixels (paths, pixels beside them and junction
        clusters), sorted."""
        return np.unique(np.concatenate([self.paths, self.off_path, self.members]))

    def margins(self) -> list[float | None]:
        """Each branch's margin, None where it has none."""
        return nullable(self.margin, np.nan)

    def removal_steps(self) -> list[int | None]:
        """The step that removes each branch, None where none does."""
        return nullable(self.removed_at, -1)

    def columns(self) -> list[np.ndarray]:
        """The coordinate columns: ``x``, ``y`` and, for a volume, ``z``."""
        return [self.x, self.y] if self.z is None else [self.x, self.y, self.z]

    def coordinates(self) -> np.ndarray:
        """``(n, ndim)`` coordinates of every point."""
        return np.column_stack(self.columns())

    def xyr(self) -> np.ndarray:
        """``(n, ndim + 1)`` coordinates and radius of every point: ``[x, y, radius]``,
        for a volume ``[x, y, z, radius]``, as the documents list points."""
        return np.column_stack([*self.columns(), self.radius])

    def path(self, j: int) -> np.ndarray:
        """``(m, ndim + 1)`` coordinates and radius of branch ``j``'s path, source to
        target."""
        idx = self.paths[self.path_offsets[j] : self.path_offsets[j + 1]]
        return np.column_stack([c[idx] for c in (*self.columns(), self.radius)])

    def lines(self) -> list[np.ndarray]:
        """Every branch as a polyline ``(m, 3)`` from its source node to its target node.

        The path's points, with the source node's position before them and the target
        node's after them where the path does not already end there, so that the lines
        of a skeleton meet exactly at its nodes. A loop's line is closed; a single-point
        branch gets two equal positions, as a LineString needs two.
        """
        xyr = self.xyr()
        pts = xyr[self.paths]
        nodes = xyr[self.node_point]
        out = []
        for j, (s, e) in enumerate(itertools.pairwise(self.path_offsets.tolist())):
            line = pts[s:e]
            a, b = nodes[self.source[j]], nodes[self.target[j]]
            head = [a[None]] if not np.array_equal(line[0, :-1], a[:-1]) else []
            single = e - s == 1 and not head  # (after the source's point: two already)
            tail = [b[None]] if single or not np.array_equal(line[-1, :-1], b[:-1]) else []
            out.append(np.concatenate([*head, line, *tail]) if head or tail else line.copy())
        return out

    def framed(self, frame: PixelFrame) -> BranchTable:
        """The table in ``frame``'s coordinates (itself for the identity frame); an
        image's only (a frame maps the plane)."""
        if frame == IDENTITY:
            return self
        if self.z is not None:
            raise ValueError("a volume's branch table has no frame but the identity")
        x, y = frame_points(frame, self.x, self.y)
        return replace(
            self,
            x=x,
            y=y,
            radius=frame_distances(frame, self.radius),
            length=frame_distances(frame, self.length),
        )


def branch_table(sk: Skeleton, margins: Margins | None) -> BranchTable:
    """The table of an image skeleton's live nodes and branches, in image pixel
    coordinates (:func:`graph_table`): each junction placed at its pixel of largest
    radius, ties to the smaller row, then column, in the graph's own frame; a loop
    without junction gets a node of its own; off-path pixels sorted.
    """
    g = sk.graph
    rows, cols = sk.image_coordinates(g.rows, g.cols)
    return graph_table(g, sk.r2, [cols, rows], margins, ties=[g.rows, g.cols])


def volume_table(sk: VolumeSkeleton, margins: Margins | None) -> BranchTable:
    """The table of a volume skeleton's live nodes and branches (:func:`graph_table`), in
    voxel indices of the whole volume (``x`` the array's last axis, ``z`` its first),
    radii and lengths physical: each junction placed at its voxel of largest radius,
    ties to the smaller point index; a loop without junction has no node (its
    ``source`` and ``target`` are -1); off-path voxels in the graph's order, as a
    volume's document has always listed them.
    """
    oz, oy, ox = sk.origin
    return graph_table(
        sk.graph,
        sk.r2,
        [sk.x + ox, sk.y + oy, sk.z + oz],
        margins,
        ties=[],
        loop_nodes=False,
        sort_sides=False,
    )


def graph_table(
    g: PointGraph,
    r2: np.ndarray,
    coords: Sequence[np.ndarray],
    margins: Margins | None,
    ties: Sequence[np.ndarray],
    loop_nodes: bool = True,
    sort_sides: bool = True,
) -> BranchTable:
    """The table of a branch graph's live nodes and branches, on any grid.

    ``coords``: ``x``, ``y`` (and ``z``) of every point of the graph. Junction nodes come
    first (in the graph's order), each placed at its point of largest radius (ties: the
    smaller ``ties`` values in turn, then the smaller point index); then, branch by
    branch, the endpoints (or, ``loop_nodes``, a loop's node) as they are met; a lone
    point is one node, the source and target of its branch. ``sort_sides``: a branch's
    off-path points sorted, else in the graph's order. ``margins`` None: no branch has a
    margin or a step that removes it.
    """
    # (Python lists: a junction is a few points, too few for numpy's per-call cost)
    neg_r2 = (-r2).tolist()
    tie = [t.tolist() for t in ties]
    node_point: list[int] = []
    node_kind: list[int] = []
    node_junction: list[int] = []
    members: list[list[int]] = []
    junction_node: dict[int, int] = {}
    for j, junc in enumerate(g.junctions):
        if not junc.alive:
            continue
        pts = sorted(junc.points)
        junction_node[j] = len(node_point)
        node_point.append(min(pts, key=lambda p: (neg_r2[p], [t[p] for t in tie], p)))
        node_kind.append(JUNCTION)
        node_junction.append(j)
        members.append(pts)

    def new_node(p: int, kind: int) -> int:
        node_point.append(p)
        node_kind.append(kind)
        node_junction.append(-1)
        members.append([])
        return len(node_point) - 1

    source: list[int] = []
    target: list[int] = []
    length: list[float] = []
    margin: list[float] = []
    removed: list[int] = []
    graph_branch: list[int] = []
    paths: list[list[int]] = []
    sides: list[list[int]] = []
    got_margin = {} if margins is None else margins.margin
    got_removed = {} if margins is None else margins.removed_at
    for b, br in enumerate(g.branches):
        if not br.alive:
            continue
        path = br.path()
        if br.loop:
            src = dst = new_node(path[0], LOOP) if loop_nodes else -1
        else:
            ends: list[int] = []
            for e, p in ((0, path[0]), (1, path[-1])):
                nid = br.node[e]
                if nid is not None:
                    ends.append(junction_node[nid])
                elif e == 1 and len(path) == 1 and br.node[0] is None:
                    ends.append(ends[0])  # a single point: one node
                else:
                    ends.append(new_node(p, ENDPOINT))
            src, dst = ends
        source.append(src)
        target.append(dst)
        length.append(g.branch_length(b))
        m = got_margin.get(b)
        margin.append(np.nan if m is None else float(m))
        k = got_removed.get(b)
        removed.append(-1 if k is None else int(k))
        graph_branch.append(b)
        paths.append(path)
        sides.append(sorted(br.side) if sort_sides else list(br.side))
    member_idx, member_off = _csr(members)
    path_idx, path_off = _csr(paths)
    side_idx, side_off = _csr(sides)
    x, y, *z = (np.asarray(c, np.float64) for c in coords)
    return BranchTable(
        x=x,
        y=y,
        radius=np.sqrt(r2.astype(np.float64)),
        node_point=np.asarray(node_point, np.int64),
        node_kind=np.asarray(node_kind, np.int8),
        node_junction=np.asarray(node_junction, np.int64),
        members=member_idx,
        member_offsets=member_off,
        source=np.asarray(source, np.int64),
        target=np.asarray(target, np.int64),
        length=np.asarray(length, np.float64),
        margin=np.asarray(margin, np.float64),
        removed_at=np.asarray(removed, np.int64),
        graph_branch=np.asarray(graph_branch, np.int64),
        paths=path_idx,
        path_offsets=path_off,
        off_path=side_idx,
        off_offsets=side_off,
        z=z[0] if z else None,
    )
