"""The answer of :func:`skelprune.prune` as napari layer data, read from the result's
document and tables only: the branch paths (Shapes, with the branch table as their
features), the nodes (Points, sized by their radius), the pruned skeleton (Labels) and,
for an image, the skeleton at each step of the pruning sequence.

Every function returns ``(data, keyword arguments, layer type)`` tuples, napari's layer
data tuples, so that the widget adds them and a test reads them without a viewer.
Coordinates are napari's: ``(row, column)`` for an image, ``(z, y, x)`` for a volume, in
pixels or voxels (the layer's ``scale`` puts them in the source layer's units).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..output.document import PruneResult
from ..output.volume import VolumeResult

__all__ = ["LayerData", "colour_columns", "result_layers", "sequence_paths", "sequence_steps"]

LayerData = tuple[Any, dict[str, Any], str]
#: The nodes' features.
NODE_COLUMNS = ("component", "label", "node", "kind", "radius")
#: The branch table's column the paths are coloured by at first.
COLOUR_BY = "length"


def colour_columns(features: Any) -> list[str]:
    """The branch table's columns that can colour the paths: numbers, none missing."""
    return [
        str(name)
        for name in features.columns
        if features[name].dtype.kind in "fiu" and not features[name].isna().any()
    ]


def _table(result: PruneResult | VolumeResult) -> Any:
    import pandas as pd  # napari depends on pandas: the features are a DataFrame

    rows = result.summary("branch") if isinstance(result, PruneResult) else result.summary()
    return rows if isinstance(rows, pd.DataFrame) else pd.DataFrame(rows)


def _where(point: list[float], volume: bool) -> list[float]:
    """A document point (``[x, y, radius]`` or ``[x, y, z, radius]``) in napari's order."""
    return [point[2], point[1], point[0]] if volume else [point[1], point[0]]


def result_layers(
    result: PruneResult | VolumeResult, name: str, scale: tuple[float, ...]
) -> list[LayerData]:
    """The Shapes of the branch paths, the Points of the nodes and the Labels of the
    pruned skeleton, named after the source layer ``name``, in its ``scale``."""
    volume = isinstance(result, VolumeResult)
    doc = result.to_dict(curve=False) if isinstance(result, PruneResult) else result.to_dict()
    paths: list[np.ndarray] = []
    nodes: list[list[float]] = []
    node_rows: list[dict[str, Any]] = []
    for ci, comp in enumerate(doc["components"]):
        sk = comp["skeleton"]
        for br in sk["branches"]:
            pts = np.array([_where(p, volume) for p in br["points"]], np.float64)
            paths.append(pts if len(pts) > 1 else np.concatenate([pts, pts]))
        for node in sk["nodes"]:
            at = [node["z"], node["y"], node["x"]] if volume else [node["y"], node["x"]]
            nodes.append(at)
            node_rows.append({"component": ci, "label": comp["label"], "node": node["id"],
                              "kind": node["kind"], "radius": node["radius"]})  # fmt: skip
    import pandas as pd

    features = _table(result)
    # a volume's radii are in the units of its spacing; the points' size is in voxels
    unit = float(scale[-1]) if volume else 1.0
    node_features = pd.DataFrame(node_rows, columns=list(NODE_COLUMNS))
    sizes = np.maximum(2.0 * node_features["radius"].to_numpy(np.float64) / unit, 1.0)
    ndim = 3 if volume else 2
    kinds = node_features["kind"].tolist()
    return [
        (
            paths,
            {
                "name": f"{name} branches",
                "shape_type": "path",
                "features": features,
                "edge_color": COLOUR_BY,
                "edge_colormap": "viridis",
                "edge_width": 1.0,
                "scale": scale,
                "ndim": ndim,
            },
            "shapes",
        ),
        (
            np.array(nodes, np.float64).reshape(-1, ndim),
            {
                "name": f"{name} nodes",
                "size": sizes,
                "features": node_features,
                "face_color": [_NODE_COLOURS.get(k, "white") for k in kinds],
                "scale": scale,
                "ndim": ndim,
                "opacity": 0.6,
            },
            "points",
        ),
        (_skeleton(result, doc), {"name": f"{name} skeleton", "scale": scale}, "labels"),
    ]


_NODE_COLOURS = {"endpoint": "royalblue", "junction": "orange", "loop": "magenta"}


def _skeleton(result: PruneResult | VolumeResult, doc: dict[str, Any]) -> np.ndarray:
    """The pruned skeleton as labels: each component's label (its index + 1 where it has
    none) on its pixels or voxels."""
    if isinstance(result, PruneResult):
        mask = result.skeleton_mask()
        return mask.astype(np.uint8) if mask.dtype == bool else mask
    out = np.zeros(result.shape, np.int64)
    for ci, comp in enumerate(doc["components"]):
        value = comp["label"] if comp["label"] is not None else ci + 1
        sk = comp["skeleton"]
        points = [p for br in sk["branches"] for p in br["points"] + br["off_path"]]
        points += [p for node in sk["nodes"] for p in node["points"]]
        if points:
            xyz = np.rint(np.array(points)[:, :3]).astype(np.int64)
            out[xyz[:, 2], xyz[:, 1], xyz[:, 0]] = value
    return out


def sequence_steps(doc: dict[str, Any]) -> int:
    """The last step of the pruning sequences of a document made with ``sequence=True``
    (0 where nothing is removed)."""
    steps = [
        b["removed_at"]
        for comp in doc["components"]
        for b in comp["sequence"]["branches"]
        if b["removed_at"] is not None
    ]
    return max(steps, default=0)


def sequence_paths(doc: dict[str, Any], step: int) -> list[np.ndarray]:
    """The branches of the skeleton ``S(step)`` of every component's pruning sequence
    (those no step up to ``step`` removes), as ``(row, column)`` paths."""
    out = []
    for comp in doc["components"]:
        for b in comp["sequence"]["branches"]:
            if b["removed_at"] is None or b["removed_at"] > step:
                pts = np.array([[p[1], p[0]] for p in b["points"]], np.float64)
                out.append(pts if len(pts) > 1 else np.concatenate([pts, pts]))
    return out
