"""The tables people measure (docs/tables.md): one row per branch, or per component.

Every number is read from the components' branch tables (:mod:`skelprune.output.table`),
in pixels, and scaled to the result's unit: the polygon's units, a ``pixel_size`` given
for an image, or pixels. Angles are degrees, counter-clockwise from the +x axis as the
picture is seen (y up: an image's rows are flipped), in ``(-180, 180]``.

- ``length``: the branch's path, from where it leaves its source node to where it meets
  its target node (at a junction: the cluster pixel the path touches), smoothed over five
  pixels so that the pixel staircase of a straight or slanted line does not count (the
  document's ``length`` counts the steps, as the pruning does). ``chord``: the straight
  distance between the same two ends; ``tortuosity`` = length / chord, null for a loop.
- ``width_*``: 2 × radius over the path's pixels (the radius of the largest disk centred
  on each that stays inside the shape).
- ``angle_source`` / ``angle_target``: the direction in which the branch leaves the
  node, from the node's position to the path's point three node radii (at least 3 px)
  along it, or its far end if nearer; ``junction_angle_*``: at a junction, the smallest
  angle between that direction and another branch's leaving the same junction.
- ``strahler``: the Horton–Strahler order: a branch splits the tree in two, the order
  of each side follows Strahler's rule (an end is 1; where branches meet, their largest
  order, plus one where two or more share it), and the branch takes the lesser (the
  tree rooted at its centre). End branches are 1. A skeleton with cycles (a vessel
  network's loops) is read on its widest spanning tree, which drops from every cycle
  its narrowest branch: those branches, and loop branches, are null.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..io.frame import IDENTITY, PixelFrame
from .finite import finite, rows_csv, rows_frame
from .table import ENDPOINT, JUNCTION, LOOP, BranchTable

#: A :class:`~skelprune.output.document.PruneResult` (which imports this module).
PruneResult = Any

__all__ = [
    "BRANCH_COLUMNS",
    "COMPONENT_COLUMNS",
    "branch_rows",
    "component_rows",
    "geojson_numbers",
    "graphml",
    "skeleton_mask",
    "table",
    "table_csv",
    "unit_of",
]

BRANCH_COLUMNS = (
    "component",
    "label",
    "branch",
    "source",
    "target",
    "kind",
    "length",
    "chord",
    "tortuosity",
    "width_mean",
    "width_median",
    "width_min",
    "width_max",
    "width_std",
    "angle_source",
    "angle_target",
    "junction_angle_source",
    "junction_angle_target",
    "strahler",
    "margin",
    "unit",
)
COMPONENT_COLUMNS = (
    "component",
    "label",
    "area",
    "length",
    "branches",
    "ends",
    "junctions",
    "cycles",
    "width_mean",
    "rer",
    "ss",
    "unit",
)
#: Half the window (pixels) over which a path is smoothed before its length is measured.
SMOOTH = 2
#: A branch's direction at a node is read this many node radii along it (at least 3 px).
ANGLE_RADII = 3.0


def unit_of(result: PruneResult) -> tuple[float, str]:
    """The size of a pixel in the tables' unit, and the unit's name: ``px`` (an image's
    pixels), ``polygon`` (the polygon's units), ``pixel_size`` (the units of a pixel size
    given for an image) or ``frame`` (the units of an input's own frame)."""
    if result.raster is not None:
        return result.frame.pixel_size, "polygon"
    if result.input.pixel_size is not None:
        return result.input.pixel_size, "pixel_size"
    if result.frame != IDENTITY:
        return result.frame.pixel_size, "frame"
    return 1.0, "px"


def _smooth(xy: np.ndarray) -> np.ndarray:
    """A polyline smoothed by a centred moving average of ±:data:`SMOOTH` points (the
    window shrinks at the ends, which stay where they are)."""
    n = len(xy)
    if n < 3:
        return xy.astype(np.float64)
    c = np.concatenate([np.zeros((1, 2)), np.cumsum(xy, axis=0)])
    i = np.arange(n)
    h = np.minimum(SMOOTH, np.minimum(i, n - 1 - i))
    return (c[i + h + 1] - c[i - h]) / (2 * h + 1)[:, None]


def _length(xy: np.ndarray) -> float:
    return float(np.hypot(*np.diff(xy, axis=0).T).sum()) if len(xy) > 1 else 0.0


def _ends(t: BranchTable, j: int, idx: np.ndarray) -> np.ndarray:
    """The branch's path as ``(m, 2)`` x, y, with the junction pixel each end touches
    added (the path then runs exactly as its step length counts it)."""
    xy = np.column_stack([t.x[idx], t.y[idx]])
    parts = [xy]
    for end, node in ((0, t.source[j]), (-1, t.target[j])):
        if t.node_kind[node] != JUNCTION:
            continue
        m = t.members[t.member_offsets[node] : t.member_offsets[node + 1]]
        cluster = np.column_stack([t.x[m], t.y[m]])
        d = np.abs(cluster - xy[end]).max(axis=1)
        near = cluster[np.argmin(d)][None]
        parts.insert(0 if end == 0 else len(parts), near)
    return np.concatenate(parts)


def _direction(path: np.ndarray, radius: float) -> float:
    """Degrees (y flipped) of the line fitted to the path's points from one node radius
    to :data:`ANGLE_RADII` + 1 radii (at least 3 px) along it from the node, pointing
    away from the node: outside the node's own disk, where the arms of a junction blend."""
    steps = np.hypot(*np.diff(path, axis=0).T) if len(path) > 1 else np.zeros(0)
    along = np.concatenate([[0.0], np.cumsum(steps)])
    near, far = radius, radius + max(ANGLE_RADII * radius, 3.0)
    if along[-1] < far:  # a short branch: its last part
        near, far = along[-1] - (far - near), along[-1]
    pts = path[(along >= near) & (along <= far)]
    if len(pts) < 2:
        pts = path[[0, -1]]
    centred = pts - pts.mean(axis=0)
    d = np.linalg.svd(centred, full_matrices=False)[2][0]
    if np.dot(pts[-1] - pts[0], d) < 0:
        d = -d
    if not np.any(np.abs(pts[-1] - pts[0]) > 1e-9):
        return float("nan")
    return float(math.degrees(math.atan2(-d[1], d[0])))


def _combine(orders: list[int]) -> int:
    """Strahler's rule: 1 with nothing feeding; else the largest order feeding, plus one
    where two or more share it."""
    if not orders:
        return 1
    top = max(orders)
    return top + 1 if orders.count(top) >= 2 else top


def _spanning_tree(t: BranchTable) -> list[bool]:
    """Which branches the Strahler orders are read on: all of a tree's; in a skeleton with
    cycles, the widest spanning tree (Kruskal's, branches by mean radius, widest first,
    ties by id), which drops from every cycle its narrowest branch (in a vessel network
    the thin anastomosis that closes a loop, not the trunk). A loop branch is never in it."""
    src, dst = t.source.tolist(), t.target.tolist()
    if t.n_branches == t.n_nodes - 1 and all(s != d for s, d in zip(src, dst, strict=True)):
        return [True] * t.n_branches
    width = [
        float(t.radius[t.paths[t.path_offsets[j] : t.path_offsets[j + 1]]].mean())
        for j in range(t.n_branches)
    ]
    root = list(range(t.n_nodes))

    def find(v: int) -> int:
        while root[v] != v:
            root[v] = root[root[v]]
            v = root[v]
        return v

    kept = [False] * t.n_branches
    for j in sorted(range(t.n_branches), key=lambda j: (-width[j], j)):
        a, b = find(src[j]), find(dst[j])
        if a != b:
            root[a] = b
            kept[j] = True
    return kept


def _strahler(t: BranchTable) -> list[int | None]:
    """Horton–Strahler orders of the branches (module docstring): each branch's order is
    the lesser of the orders computed from its two sides of the tree, which is the tree
    rooted at its centre; on a skeleton with cycles, the tree of :func:`_spanning_tree`,
    the branches it drops None."""
    n, nb = t.n_nodes, t.n_branches
    src, dst = t.source.tolist(), t.target.tolist()
    kept = _spanning_tree(t)
    at: list[list[int]] = [[] for _ in range(n)]
    for b, (s, d) in enumerate(zip(src, dst, strict=True)):
        if kept[b]:
            at[s].append(b)
            at[d].append(b)
    # a breadth-first order from node 0: each node's branch toward the root
    up_branch = [-1] * n
    seen = [False] * n
    seen[0] = True
    order_nodes = [0]
    for v in order_nodes:
        for b in at[v]:
            w = dst[b] if src[b] == v else src[b]
            if not seen[w]:
                seen[w] = True
                up_branch[w] = b
                order_nodes.append(w)
    if len(order_nodes) != n:  # not connected: not one tree
        return [None] * nb
    below = [0] * nb  # the order seen from the branch's far side from the root
    for w in reversed(order_nodes[1:]):
        b = up_branch[w]
        below[b] = _combine([below[c] for c in at[w] if c != b])
    above = [0] * nb  # the order seen from the root's side
    for v in order_nodes:
        for b in at[v]:
            if b == up_branch[v]:
                continue
            feeding = [below[c] for c in at[v] if c not in (b, up_branch[v])]
            if up_branch[v] >= 0:
                feeding.append(above[up_branch[v]])
            above[b] = _combine(feeding)
    return [min(below[b], above[b]) if kept[b] else None for b in range(nb)]


def _component_branches(
    t: BranchTable, ci: int, label: int | None, scale: float, unit: str
) -> list[dict[str, Any]]:
    rows = []
    margins = t.margins()
    strahler = _strahler(t)
    kinds = t.node_kind
    node_r = t.radius[t.node_point]
    paths: list[np.ndarray] = []
    angles: list[tuple[float, float]] = []
    for j in range(t.n_branches):
        idx = t.paths[t.path_offsets[j] : t.path_offsets[j + 1]]
        full = _smooth(_ends(t, j, idx))
        paths.append(full)
        s, d = int(t.source[j]), int(t.target[j])
        a = _direction(full, float(node_r[s]))
        b = _direction(full[::-1], float(node_r[d]))
        angles.append((a, b))
    # every branch end's direction at each junction, for the junction angles
    leaving: dict[int, list[tuple[int, int, float]]] = {}
    for j, (a, b) in enumerate(angles):
        leaving.setdefault(int(t.source[j]), []).append((j, 0, a))
        leaving.setdefault(int(t.target[j]), []).append((j, 1, b))

    def junction_angle(node: int, j: int, end: int, angle: float) -> float | None:
        if kinds[node] != JUNCTION:
            return None
        others = [
            abs((angle - a + 180.0) % 360.0 - 180.0)
            for k, e, a in leaving[node]
            if (k, e) != (j, end)
        ]
        return min(others) if others else None

    for j in range(t.n_branches):
        s, d = int(t.source[j]), int(t.target[j])
        idx = t.paths[t.path_offsets[j] : t.path_offsets[j + 1]]
        width = 2.0 * t.radius[idx] * scale
        loop = s == d
        ks, kd = kinds[s], kinds[d]
        kind = (
            "loop"
            if loop or LOOP in (ks, kd)
            else {0: "end-end", 1: "end-junction", 2: "junction-junction"}[
                int(ks == JUNCTION) + int(kd == JUNCTION)
            ]
        )
        full = paths[j]
        length = _length(full) * scale
        chord = float(np.hypot(*(full[-1] - full[0]))) * scale
        a, b = angles[j]
        rows.append(
            {
                "component": ci,
                "label": label,
                "branch": j,
                "source": s,
                "target": d,
                "kind": kind,
                "length": length,
                "chord": chord,
                "tortuosity": None if kind == "loop" or chord == 0 else length / chord,
                "width_mean": float(width.mean()),
                "width_median": float(np.median(width)),
                "width_min": float(width.min()),
                "width_max": float(width.max()),
                "width_std": float(width.std()),
                "angle_source": None if loop else a,
                "angle_target": None if loop else b,
                "junction_angle_source": None if loop else junction_angle(s, j, 0, a),
                "junction_angle_target": None if loop else junction_angle(d, j, 1, b),
                "strahler": strahler[j],
                "margin": margins[j],
                "unit": unit,
            }
        )
    return rows


def branch_rows(
    result: PruneResult, scale: float | None = None, unit: str | None = None
) -> list[dict[str, Any]]:
    """One row per branch of every component (:data:`BRANCH_COLUMNS`), in the result's
    unit (:func:`unit_of`) unless a pixel's size ``scale`` and its ``unit`` are given."""
    if scale is None or unit is None:
        scale, unit = unit_of(result)
    out: list[dict[str, Any]] = []
    for ci, c in enumerate(result.components):
        t = c.table
        out += _component_branches(t, ci, c.label, scale, unit)
    return [{k: finite(v) for k, v in row.items()} for row in out]


def component_rows(result: PruneResult) -> list[dict[str, Any]]:
    """One row per component (:data:`COMPONENT_COLUMNS`)."""
    scale, unit = unit_of(result)
    out = []
    for ci, c in enumerate(result.components):
        t = c.table
        mine = _component_branches(t, ci, c.label, scale, unit)
        idx = t.paths
        width = 2.0 * t.radius[idx] * scale
        kinds = t.node_kind
        out.append(
            {
                "component": ci,
                "label": c.label,
                "area": float(c.area * scale * scale) if unit != "px" else c.area,
                "length": float(sum(b["length"] for b in mine)),
                "branches": t.n_branches,
                "ends": int((kinds == ENDPOINT).sum()),
                "junctions": int((kinds == JUNCTION).sum()),
                "cycles": t.n_branches - t.n_nodes + 1,
                "width_mean": float(width.mean()) if width.size else None,
                "rer": float(c.rer),
                "ss": float(c.ss),
                "unit": unit,
            }
        )
    return [{k: finite(v) for k, v in row.items()} for row in out]


def table(result: PruneResult, level: str = "branch") -> Any:
    """The branch or component table: a pandas DataFrame when pandas is installed
    (``attrs["unit"]`` says the unit), else a list of row dicts."""
    if level not in ("branch", "component"):
        raise ValueError(f"level must be 'branch' or 'component', got {level!r}")
    rows = branch_rows(result) if level == "branch" else component_rows(result)
    frame = rows_frame(rows, BRANCH_COLUMNS if level == "branch" else COMPONENT_COLUMNS)
    if frame is not rows:  # a DataFrame
        frame.attrs["unit"] = unit_of(result)[1]
    return frame


def table_csv(result: PruneResult, level: str = "branch") -> str:
    """The table as CSV text (a header row; empty cells for null)."""
    if level not in ("branch", "component"):
        raise ValueError(f"level must be 'branch' or 'component', got {level!r}")
    rows = branch_rows(result) if level == "branch" else component_rows(result)
    return rows_csv(rows, BRANCH_COLUMNS if level == "branch" else COMPONENT_COLUMNS)


def skeleton_mask(result: PruneResult) -> np.ndarray:
    """The pruned skeleton as an image of the input's size: boolean, or for a label
    image the component's label on each skeleton pixel (0 elsewhere)."""
    labelled = result.input.labels is not None
    out = np.zeros(result.mask.shape, np.int64 if labelled else bool)
    for c in result.components:
        rows, cols, _ = c.points()
        out[rows, cols] = c.label if labelled else True
    return out


def graphml(result: PruneResult) -> str:
    """The skeleton as GraphML: nodes ``c<component>n<node>`` with ``component``,
    ``label``, ``x``, ``y``, ``radius`` and ``kind``; one edge per branch with the branch
    table's numbers (null ones left out), in the result's own frame."""
    from xml.sax.saxutils import quoteattr

    node_keys = {"component": "int", "label": "long", "x": "double", "y": "double"}
    node_keys |= {"radius": "double", "kind": "string"}
    edge_keys = {c: "double" for c in BRANCH_COLUMNS if c not in ("unit", "kind")}
    edge_keys |= {"component": "int", "label": "long", "branch": "int", "kind": "string"}
    edge_keys |= {"source": "int", "target": "int", "strahler": "int"}
    lines = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        '<graphml xmlns="http://graphml.graphdrawing.org/xmlns">',
    ]
    for scope, keys in (("node", node_keys), ("edge", edge_keys)):
        for name, kind in keys.items():
            lines.append(
                f'  <key id="{scope[0]}_{name}" for="{scope}" attr.name="{name}" '
                f'attr.type="{kind}"/>'
            )
    lines.append('  <graph id="skeleton" edgedefault="undirected">')

    def data(scope: str, values: dict[str, Any]) -> str:
        return "".join(
            f'<data key="{scope}_{k}">{v if not isinstance(v, str) else quoteattr(v)[1:-1]}</data>'
            for k, v in values.items()
            if finite(v) is not None
        )

    rows = branch_rows(result)
    for ci, c in enumerate(result.components):
        t = c.table.framed(result.frame)
        for i, kind in enumerate(t.kinds()):
            p = t.node_point[i]
            values = {"component": ci, "label": c.label, "x": float(t.x[p]), "y": float(t.y[p])}
            values |= {"radius": float(t.radius[p]), "kind": kind}
            lines.append(f'    <node id="c{ci}n{i}">{data("n", values)}</node>')
    for row in rows:
        ci = row["component"]
        values = {k: v for k, v in row.items() if k != "unit"}
        lines.append(
            f'    <edge id="c{ci}b{row["branch"]}" source="c{ci}n{row["source"]}" '
            f'target="c{ci}n{row["target"]}">{data("e", values)}</edge>'
        )
    lines += ["  </graph>", "</graphml>", ""]
    return "\n".join(lines)


#: The branch table's numbers a GeoJSON line carries besides its own properties, from
#: ``chord`` to ``strahler`` (its ``length`` stays the document's step length; the
#: table's ``kind`` is ``branch_kind``; its ``margin`` is the document's already).
GEOJSON_NUMBERS = BRANCH_COLUMNS[
    BRANCH_COLUMNS.index("chord") : BRANCH_COLUMNS.index("strahler") + 1
]


def geojson_numbers(
    result: PruneResult, collection: dict[str, Any], frame: PixelFrame
) -> dict[str, Any]:
    """The skeleton's GeoJSON with each line's branch-table numbers (and, for a label
    image, every feature's ``label``) added to its properties, in the units of the
    GeoJSON's ``frame``."""
    rows = {(r["component"], r["branch"]): r for r in branch_rows(result, frame.pixel_size, "")}
    for feature in collection["features"]:
        props = feature["properties"]
        label = result.components[props["component"]].label
        if label is not None:
            props["label"] = label
        if props["kind"] != "branch":
            continue
        row = rows[(props["component"], props["id"])]
        props["branch_kind"] = row["kind"]
        props.update((k, row[k]) for k in GEOJSON_NUMBERS)
    return collection
