"""Checks of a result document as a graph other programs build on (docs/graph.md).

Each function asserts on the document alone (plus the mask it came from), the way a
user's program would read it.
"""

from __future__ import annotations

import math
from itertools import pairwise
from typing import Any

import networkx as nx
import numpy as np
from scipy import ndimage

from skelprune.grid.reconstruction import reconstruction
from testkit.document_oracle import branch_line

EIGHT = np.ones((3, 3), bool)


def step(a: tuple[int, int], b: tuple[int, int]) -> float:
    """Step length between two 8-neighbours (x, y): 1 axial, √2 diagonal."""
    assert max(abs(a[0] - b[0]), abs(a[1] - b[1])) == 1, (a, b)
    return math.sqrt(2.0) if a[0] != b[0] and a[1] != b[1] else 1.0


def xy(p: list[float]) -> tuple[int, int]:
    assert p[0] == int(p[0]) and p[1] == int(p[1]), p  # exact integer pixel centres
    return int(p[0]), int(p[1])


def node_pixels(node: dict[str, Any]) -> list[tuple[int, int]]:
    return (
        [xy(p) for p in node["points"]]
        if node["kind"] == "junction"
        else [xy([node["x"], node["y"]])]
    )


def check_paths(skeleton: dict[str, Any]) -> None:
    """Every branch an ordered 8-path from its source node to its target node, its
    ``length`` the path's step length (with the step into each junction cluster)."""
    nodes = skeleton["nodes"]
    for br in skeleton["branches"]:
        path = [xy(p) for p in br["points"]]
        assert path, br["id"]
        length = sum(step(a, b) for a, b in pairwise(path))
        src, dst = nodes[br["source"]], nodes[br["target"]]
        for end, node in ((path[0], src), (path[-1], dst)):
            if node["kind"] == "junction":
                # adjacent to the cluster; the step into it is counted
                near = [
                    step(end, q)
                    for q in node_pixels(node)
                    if max(abs(end[0] - q[0]), abs(end[1] - q[1])) == 1
                ]
                assert near, (br["id"], end)
                length += min(near)
            else:  # endpoint or loop: the path starts (ends) on the node's pixel
                assert end == node_pixels(node)[0] or node["kind"] == "loop", (br["id"], end)
        if src["kind"] == "loop":
            assert br["source"] == br["target"]
            assert path[0] == node_pixels(src)[0]
            length += step(path[-1], path[0])  # the closing step
        assert math.isclose(length, br["length"], rel_tol=0, abs_tol=1e-9), (
            br["id"],
            length,
            br["length"],
        )
    assert math.isclose(
        sum(b["length"] for b in skeleton["branches"]),
        skeleton["length"],
        rel_tol=1e-12,
        abs_tol=1e-9,
    )


def skeleton_pixels(skeleton: dict[str, Any]) -> list[list[float]]:
    """Branch points, their off-path pixels and junction pixels: the whole skeleton."""
    pts = [p for b in skeleton["branches"] for p in b["points"] + b["off_path"]]
    pts += [p for n in skeleton["nodes"] if n["kind"] == "junction" for p in n["points"]]
    return pts


def check_reconstruction(mask: np.ndarray, comp: dict[str, Any]) -> None:
    """The documented pixels, each once, reconstruct exactly the reported ``rer``."""
    pts = skeleton_pixels(comp["skeleton"])
    keys = [xy(p) for p in pts]
    assert len(keys) == len(set(keys))
    cols = np.array([k[0] for k in keys])
    rows = np.array([k[1] for k in keys])
    r2 = np.array([round(p[2] ** 2) for p in pts])
    labels, _ = ndimage.label(mask, structure=EIGHT)
    shape = labels == labels[rows[0], cols[0]]
    assert shape[rows, cols].all()
    rec = reconstruction(mask.shape, rows, cols, r2)
    assert int(shape.sum()) == comp["area"]
    assert (shape & ~rec).sum() / shape.sum() == comp["rer"]


def holes(shape: np.ndarray) -> int:
    """Holes of one 8-connected component: 4-connected background parts off the border."""
    _, n = ndimage.label(~np.pad(shape, 1))
    return n - 1


def network(skeleton: dict[str, Any]) -> nx.Graph:
    """The branches' GeoJSON lines as a graph on their coordinates."""
    g = nx.Graph()
    for n in skeleton["nodes"]:
        g.add_node((n["x"], n["y"]))
    for br in skeleton["branches"]:
        line = [tuple(p[:2]) for p in branch_line(skeleton["nodes"], br)]
        g.add_edges_from((a, b) for a, b in pairwise(line) if a != b)
    return g


def check_network(mask: np.ndarray, comp: dict[str, Any]) -> None:
    """The lines meet at the nodes, form one connected network per component, and have
    as many independent cycles as the component has holes."""
    sk = comp["skeleton"]
    for br in sk["branches"]:
        line = branch_line(sk["nodes"], br)
        src, dst = sk["nodes"][br["source"]], sk["nodes"][br["target"]]
        assert line[0][:2] == [src["x"], src["y"]] and line[-1][:2] == [dst["x"], dst["y"]]
        assert len(line) >= 2
    g = network(sk)
    assert nx.is_connected(g)
    p = sk["branches"][0]["points"][0]
    labels, _ = ndimage.label(mask, structure=EIGHT)
    shape = labels == labels[int(p[1]), int(p[0])]
    assert g.number_of_edges() - g.number_of_nodes() + 1 == holes(shape)


def check_document(mask: np.ndarray, doc: dict[str, Any]) -> None:
    for comp in doc["components"]:
        check_paths(comp["skeleton"])
        check_reconstruction(mask, comp)
        check_network(mask, comp)
