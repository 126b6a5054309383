"""The document's skeleton parts and the networkx graph, as views of a branch table.

Each function reads a :class:`~skelprune.output.table.BranchTable` already in the
wanted frame and returns plain JSON types (or a networkx graph); whole arrays become
lists at once, and each node or branch takes its slice.
"""

from __future__ import annotations

import itertools
from typing import TYPE_CHECKING, Any

import numpy as np

from ..grid.replay import replay, start_repaint
from ..io.frame import PixelFrame
from .table import BranchTable, branch_table, frame_points, nullable

if TYPE_CHECKING:
    from ..pruning.bayesian import PruningSequence
    from ..skeleton import Skeleton
    from .schema import BranchDoc, NodeDoc, SequenceDoc

__all__ = ["branch_dicts", "node_dicts", "sequence_dict", "to_networkx"]


def _slices(values: list[Any], offsets: np.ndarray) -> list[list[Any]]:
    return [values[s:e] for s, e in itertools.pairwise(offsets.tolist())]


def node_dicts(t: BranchTable) -> list[NodeDoc]:
    """The document's ``nodes``: id, position (``x``, ``y``, a volume's ``z``), radius,
    kind and a junction's points."""
    xyr = t.xyr()
    at = xyr[t.node_point].tolist()
    members = _slices(xyr[t.members].tolist(), t.member_offsets)
    rows = enumerate(zip(at, t.kinds(), members, strict=True))
    if t.z is not None:
        out: list[Any] = [
            {"id": i, "x": x, "y": y, "z": z, "radius": r, "kind": kind, "points": pts}
            for i, ((x, y, z, r), kind, pts) in rows
        ]
        return out
    return [
        {"id": i, "x": x, "y": y, "radius": r, "kind": kind, "points": pts}
        for i, ((x, y, r), kind, pts) in rows
    ]


def branch_dicts(t: BranchTable, margins: bool = True, graph_ids: bool = False) -> list[BranchDoc]:
    """The document's ``branches``; ``margins`` False leaves out ``margin`` and
    ``removed_at`` (the sequence's branches carry events instead). Ids count the
    branches from 0, or, ``graph_ids``, are the graph's own (a volume's document); a
    loop without a node (a volume's) has a null ``source`` and ``target``."""
    xyr = t.xyr()
    paths = _slices(xyr[t.paths].tolist(), t.path_offsets)
    off = _slices(xyr[t.off_path].tolist(), t.off_offsets)
    ids = t.graph_branch.tolist() if graph_ids else range(t.n_branches)
    ends = nullable(t.source, -1), nullable(t.target, -1)
    rows = zip(ids, *ends, t.length.tolist(), paths, off, strict=True)
    out: list[Any] = [
        {"id": j, "source": s, "target": d, "length": L, "points": p, "off_path": o}
        for j, s, d, L, p, o in rows
    ]
    if margins:
        for b, m, k in zip(out, t.margins(), t.removal_steps(), strict=True):
            b["margin"] = m
            b["removed_at"] = k
    return out


def sequence_dict(
    seq: PruningSequence[Skeleton], answer: Skeleton, frame: PixelFrame
) -> SequenceDoc:
    """The pruning sequence as a viewer needs it, in ``frame``'s coordinates.

    ``S(0)``'s nodes and branches (ids of their own), each branch with the step whose
    removal takes its pixels (``removed_at``) and, where a junction dissolved into a
    merge, the step and the branch it became part of (``absorbed_at``,
    ``absorbed_into``); each junction node with the step that dissolved it and the branch
    its pixels joined (:func:`skelprune.grid.replay.replay`). ``uncovered`` lists the
    shape's pixels ``S(0)`` misses, so that ``D \\ R(S(k))`` follows from the disks alone,
    and ``coarse_removed`` the medial axis's pixels the coarse stage took before step 0.
    ``answer`` gives the way back to image coordinates (the start's own, as both share
    the component's crop and orientation).
    """
    start = seq.start
    table = branch_table(start, None)
    ev = replay(seq)
    view = table.framed(frame)
    nodes: list[Any] = node_dicts(view)
    branches: list[Any] = branch_dicts(view, margins=False)
    # graph ids -> document ids
    doc_branch = np.full(len(start.graph.branches) + 1, -1, np.int64)
    doc_branch[table.graph_branch] = np.arange(table.n_branches)
    gb = table.graph_branch

    def ids(graph_ids: np.ndarray) -> list[int | None]:
        return nullable(np.where(graph_ids >= 0, doc_branch[graph_ids], -1), -1)

    for b, k, a, into in zip(
        branches,
        nullable(ev.removed_at[gb], -1),
        nullable(ev.absorbed_at[gb], -1),
        ids(ev.absorbed_into[gb]),
        strict=True,
    ):
        b.update(removed_at=k, absorbed_at=a, absorbed_into=into)
    junctions = np.flatnonzero(table.node_junction >= 0)
    jid = table.node_junction[junctions]
    for i, k, d, into in zip(
        junctions.tolist(),
        nullable(ev.junction_removed_at[jid], -1),
        nullable(ev.dissolved_at[jid], -1),
        ids(ev.dissolved_into[jid]),
        strict=True,
    ):
        nodes[i].update(removed_at=k, dissolved_at=d, dissolved_into=into)
    miss_r, miss_c, gone = start_repaint(start)
    miss_r, miss_c = answer.image_coordinates(miss_r, miss_c)
    ux, uy = frame_points(frame, miss_c.astype(np.float64), miss_r.astype(np.float64))
    cx, cy = view.x[gone], view.y[gone]
    cr = view.radius[gone]
    return {
        "start": "medial_axis" if not gone.size else "coarse",
        "nodes": nodes,
        "branches": branches,
        "uncovered": np.column_stack([ux, uy]).tolist(),
        "coarse_removed": np.column_stack([cx, cy, cr]).tolist(),
        # how to get back to the raster's pixels (the error is painted on them)
        "frame": {
            "x0": frame.x0,
            "y0": frame.y0,
            "pixel_size": frame.pixel_size,
            "flip_y": frame.flip_y,
        },
    }


def to_networkx(tables: list[BranchTable], labels: list[int | None] | None = None) -> Any:
    """The components' skeletons as one ``networkx.MultiGraph`` (see
    :meth:`skelprune.output.document.PruneResult.to_networkx`); a label image's nodes and
    edges also carry their component's ``label``."""
    try:
        import networkx as nx
    except ImportError:  # an optional dependency: say how to get it
        raise ImportError("to_networkx needs networkx: pip install 'skelprune[graph]'") from None
    g = nx.MultiGraph()
    for ci, t in enumerate(tables):
        label = None if labels is None else labels[ci]
        tag = {} if label is None else {"label": label}
        for nd in node_dicts(t):
            attrs = {k: v for k, v in nd.items() if k != "id"}
            g.add_node((ci, nd["id"]), component=ci, **tag, **attrs)
        lines = [ln.tolist() for ln in t.lines()]
        for br, line in zip(branch_dicts(t, margins=False), lines, strict=True):
            g.add_edge(
                (ci, br["source"]),
                (ci, br["target"]),
                key=br["id"],
                component=ci,
                **tag,
                length=br["length"],
                points=br["points"],
                off_path=br["off_path"],
                line=line,
            )
    return g
