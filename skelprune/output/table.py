"""The branch table: a pruned skeleton as flat arrays, the one source of every output.

A component's answer is read out of its mutable :class:`~skelprune.grid.graph.BranchGraph`
once, into a :class:`BranchTable` in image pixel coordinates: one coordinate array
(``x``, ``y``, ``radius`` of every skeleton pixel) and, per node and per branch, a row
of plain arrays, with each branch's path and off-path pixels (and each junction's
cluster) as offsets into index arrays over the coordinates (compressed sparse rows, as
skan's ``Skeleton`` keeps its paths). The document, the GeoJSON, the networkx graph
and the overlay's marks are views of it; a frame to the caller's coordinates is
applied to the coordinate array once (:meth:`BranchTable.framed`), and not at all for
the identity frame.

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
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from ..io.frame import IDENTITY, PixelFrame

if TYPE_CHECKING:
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
    "nullable",
    "round_like_python",
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

    Node ``i`` sits at pixel ``node_point[i]``; a junction's cluster is
    ``members[member_offsets[i]:member_offsets[i + 1]]`` (empty for endpoints and
    loops). Branch ``j`` runs from node ``source[j]`` to ``target[j]`` along
    ``paths[path_offsets[j]:path_offsets[j + 1]]``, with its pixels beside the path
    (of a dissolved junction cluster) in ``off_path[off_offsets[j]:off_offsets[j + 1]]``.
    ``margin`` is NaN and ``removed_at`` -1 where the document says null.
    ``graph_branch`` and ``node_junction`` are the graph's own ids of each branch and
    junction node (-1: not a junction), which the pruning sequence's events name.
    """

    #: Image column, row and radius of every pixel of the graph (pixels indexed as the
    #: graph's points).
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

    def xyr(self) -> np.ndarray:
        """``(n, 3)`` x, y and radius of every pixel."""
        return np.column_stack([self.x, self.y, self.radius])

    def path(self, j: int) -> np.ndarray:
        """``(m, 3)`` x, y, radius of branch ``j``'s path, source to target."""
        idx = self.paths[self.path_offsets[j] : self.path_offsets[j + 1]]
        return np.column_stack([self.x[idx], self.y[idx], self.radius[idx]])

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
            head = [a[None]] if not np.array_equal(line[0, :2], a[:2]) else []
            single = e - s == 1 and not head  # (after the source's point: two already)
            tail = [b[None]] if single or not np.array_equal(line[-1, :2], b[:2]) else []
            out.append(np.concatenate([*head, line, *tail]) if head or tail else line.copy())
        return out

    def framed(self, frame: PixelFrame) -> BranchTable:
        """The table in ``frame``'s coordinates (itself for the identity frame)."""
        if frame == IDENTITY:
            return self
        x, y = frame_points(frame, self.x, self.y)
        return replace(
            self,
            x=x,
            y=y,
            radius=frame_distances(frame, self.radius),
            length=frame_distances(frame, self.length),
        )


def branch_table(sk: Skeleton, margins: Margins | None) -> BranchTable:
    """The table of a skeleton's live nodes and branches, in image pixel coordinates.

    Junction nodes come first (in the graph's order), each placed at its pixel of largest
    radius (ties: the smaller row, then column, in the graph's own frame); then, branch by
    branch, the endpoints (or a loop's node) as they are met. ``margins`` None: no
    branch has a margin or a step that removes it.
    """
    g, r2 = sk.graph, sk.r2
    rows, cols = sk.image_coordinates(g.rows, g.cols)
    # (Python lists: a junction is a few pixels, too few for numpy's per-call cost)
    neg_r2, grow, gcol = (-r2).tolist(), g.rows.tolist(), g.cols.tolist()
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
        node_point.append(min(pts, key=lambda p: (neg_r2[p], grow[p], gcol[p])))
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
            src = dst = new_node(path[0], LOOP)
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
        sides.append(sorted(br.side))
    member_idx, member_off = _csr(members)
    path_idx, path_off = _csr(paths)
    side_idx, side_off = _csr(sides)
    return BranchTable(
        x=cols.astype(np.float64),
        y=rows.astype(np.float64),
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
    )
