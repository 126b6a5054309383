"""The document's skeleton and sequence built point by point, as plain dicts: the
reference the branch table's views (:mod:`skelprune.output.views`) are checked against.

The straightforward reading of the graph, one dict a node and a branch, one frame call
a point, the sequence replayed inline; slow and obviously right.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from skelprune.grid.reconstruction import reconstruction
from skelprune.io.frame import IDENTITY, PixelFrame
from skelprune.output.component import ComponentResult
from skelprune.output.volume import VolumeComponent
from skelprune.pruning.margin import Margins
from skelprune.skeleton import Skeleton

__all__ = ["branch_line", "component_dict", "volume_skeleton_dict"]


def _graph_table(
    sk: Skeleton, margins: Margins | None
) -> tuple[list[dict[str, Any]], list[dict[str, Any]], dict[int, int], dict[int, int]]:
    g, r2 = sk.graph, sk.r2
    rows, cols = sk.image_coordinates(g.rows, g.cols)

    def xyr(p: int) -> list[float]:
        return [float(cols[p]), float(rows[p]), float(np.sqrt(float(r2[p])))]

    nodes: list[dict[str, Any]] = []
    junction_node: dict[int, int] = {}
    for j, junc in enumerate(g.junctions):
        if not junc.alive:
            continue
        top = min(junc.points, key=lambda p: (-r2[p], g.rows[p], g.cols[p]))
        x, y, r = xyr(top)
        junction_node[j] = len(nodes)
        pts = [xyr(p) for p in sorted(junc.points)]
        nodes.append(
            {"id": len(nodes), "x": x, "y": y, "radius": r, "kind": "junction", "points": pts}
        )

    def new_node(p: int, kind: str) -> int:
        x, y, r = xyr(p)
        nodes.append({"id": len(nodes), "x": x, "y": y, "radius": r, "kind": kind, "points": []})
        return len(nodes) - 1

    branches: list[dict[str, Any]] = []
    branch_id: dict[int, int] = {}
    for b, br in enumerate(g.branches):
        if not br.alive:
            continue
        path = br.path()
        if br.loop:
            src = dst = new_node(path[0], "loop")
        else:
            ends = []
            for e, p in ((0, path[0]), (1, path[-1])):
                if br.node[e] is not None:
                    ends.append(junction_node[br.node[e]])
                elif e == 1 and len(path) == 1 and br.node[0] is None:
                    ends.append(ends[0])
                else:
                    ends.append(new_node(p, "endpoint"))
            src, dst = ends
        branches.append(
            {
                "id": len(branches),
                "source": src,
                "target": dst,
                "length": g.branch_length(b),
                "points": [xyr(p) for p in path],
                "off_path": [xyr(p) for p in sorted(br.side)],
                "margin": None if margins is None else margins.margin.get(b),
                "removed_at": None if margins is None else margins.removed_at.get(b),
            }
        )
        branch_id[b] = len(branches) - 1
    return nodes, branches, branch_id, junction_node


def _sequence(comp: ComponentResult) -> dict[str, Any]:
    seq = comp.sequence
    start = seq.start
    nodes, branches, branch_id, junction_id = _graph_table(start, None)
    for b in branches:
        del b["margin"]
        b.update(removed_at=None, absorbed_at=None, absorbed_into=None)
    for n in nodes:
        if n["kind"] == "junction":
            n.update(removed_at=None, dissolved_at=None, dissolved_into=None)
    held = {gb: ([db], []) for gb, db in branch_id.items()}
    graph = start.working_graph()
    for step, pick in enumerate(seq.removed, start=1):
        merged = graph.remove_end_branch(pick)
        own_b, own_j = held.pop(pick)
        for db in own_b:
            branches[db]["removed_at"] = step
        for nid in own_j:
            nodes[nid]["removed_at"] = step
        if merged is None:
            continue
        kept, absorbed, jid = merged
        nid = junction_id[jid]
        nodes[nid]["dissolved_at"] = step
        nodes[nid]["dissolved_into"] = branch_id[kept]
        held[kept][1].append(nid)
        if absorbed != kept:
            branches[branch_id[absorbed]]["absorbed_at"] = step
            branches[branch_id[absorbed]]["absorbed_into"] = branch_id[kept]
            more_b, more_j = held.pop(absorbed)
            held[kept][0].extend(more_b)
            held[kept][1].extend(more_j)
    idx = start.points()
    covered = reconstruction(start.mask.shape, start.rows[idx], start.cols[idx], start.r2[idx])
    miss_r, miss_c = np.nonzero(start.mask & ~covered)
    miss_r, miss_c = comp.image_coordinates(miss_r, miss_c)
    gone = np.ones(start.rows.size, bool)
    gone[idx] = False
    gone_r, gone_c = comp.image_coordinates(start.rows[gone], start.cols[gone])
    radii = np.sqrt(start.r2[gone].astype(float))
    return {
        "start": "medial_axis" if not gone.any() else "coarse",
        "nodes": nodes,
        "branches": branches,
        "uncovered": [[float(x), float(y)] for y, x in zip(miss_r, miss_c, strict=True)],
        "coarse_removed": [
            [float(x), float(y), float(r)] for y, x, r in zip(gone_r, gone_c, radii, strict=True)
        ],
    }


def _map(frame: PixelFrame, nodes: list[dict[str, Any]], branches: list[dict[str, Any]]) -> None:
    def mapped(pts: list[list[float]]) -> list[list[float]]:
        return [[*frame.point(x, y), frame.distance(r)] for x, y, r in pts]

    for n in nodes:
        n["x"], n["y"] = frame.point(n["x"], n["y"])
        n["radius"] = frame.distance(n["radius"])
        n["points"] = mapped(n["points"])
    for b in branches:
        b["length"] = frame.distance(b["length"])
        b["points"] = mapped(b["points"])
        b["off_path"] = mapped(b["off_path"])


def component_dict(comp: ComponentResult, frame: PixelFrame = IDENTITY) -> dict[str, Any]:
    """The component's ``skeleton`` (its nodes and branches) and ``sequence`` parts of
    the document, in ``frame``'s coordinates."""
    nodes, branches, _, _ = _graph_table(comp.skeleton, comp.margins)
    _map(frame, nodes, branches)
    seq = _sequence(comp)
    _map(frame, seq["nodes"], seq["branches"])
    seq["uncovered"] = [list(frame.point(x, y)) for x, y in seq["uncovered"]]
    seq["coarse_removed"] = [
        [*frame.point(x, y), frame.distance(r)] for x, y, r in seq["coarse_removed"]
    ]
    return {"nodes": nodes, "branches": branches, "sequence": seq}


def branch_line(nodes: list[dict[str, Any]], branch: dict[str, Any]) -> list[list[float]]:
    """A document branch's polyline from its source node to its target node."""
    line = [list(p) for p in branch["points"]]
    for end, nid in ((0, branch["source"]), (-1, branch["target"])):
        node = nodes[nid]
        if line[end][:2] != [node["x"], node["y"]] or (end == -1 and len(line) == 1):
            line.insert(len(line) if end == -1 else 0, [node["x"], node["y"], node["radius"]])
    return line


def volume_skeleton_dict(comp: VolumeComponent) -> dict[str, Any]:
    """A volume component's ``nodes`` and ``branches``, walked voxel by voxel as the
    volume's document was built before it read a branch table: junctions at their voxel
    of largest radius (ties: the smaller point index), then free ends as met; a loop
    without junction has no node (null ends); branch ids the graph's own."""
    s = comp.skeleton
    g, r2, (oz, oy, ox) = s.graph, s.r2, s.origin

    def where(p: int) -> list[float]:
        return [float(s.x[p] + ox), float(s.y[p] + oy), float(s.z[p] + oz), float(np.sqrt(r2[p]))]

    def node(p: int, kind: str, points: list[list[float]]) -> dict[str, Any]:
        x, y, z, radius = where(p)
        n = len(nodes)
        return {"id": n, "x": x, "y": y, "z": z, "radius": radius, "kind": kind, "points": points}

    nodes: list[dict[str, Any]] = []
    of_junction: dict[int, int] = {}
    for j, junc in enumerate(g.junctions):
        if junc.alive:
            of_junction[j] = len(nodes)
            centre = max(junc.points, key=lambda p: (r2[p], -p))
            nodes.append(node(centre, "junction", [where(p) for p in sorted(junc.points)]))
    branches = []
    for b, br in enumerate(g.branches):
        if not br.alive:
            continue
        path = g.path(b)
        ends: list[int | None] = []
        for e in (0, 1):
            if br.loop:
                ends.append(None)
            elif br.node[e] is not None:
                ends.append(of_junction[br.node[e]])
            elif e == 1 and len(path) == 1 and br.node[0] is None:
                ends.append(ends[0])  # a lone voxel: one end point
            else:
                ends.append(len(nodes))
                nodes.append(node(path[0] if e == 0 else path[-1], "endpoint", []))
        length = 0.0
        for c, w in zip(br.steps, s.step_weights.tolist(), strict=True):
            length += c * w
        branches.append(
            {
                "id": b,
                "source": ends[0],
                "target": ends[1],
                "length": length,
                "points": [where(p) for p in path],
                "off_path": [where(p) for p in br.side],
                "margin": comp.margins.margin.get(b),
                "removed_at": comp.margins.removed_at.get(b),
            }
        )
    return {"nodes": nodes, "branches": branches}
