"""The document as a graph: ordered branch paths, lines meeting at nodes (docs/graph.md)."""

from __future__ import annotations

from itertools import pairwise

import networkx as nx
import numpy as np
import pytest
from shapely import LineString
from shapely.ops import unary_union

import skelprune
from skelprune.api import components
from skelprune.io.polygon import polygon_mask
from testkit import graphcheck
from testkit.graphcheck import check_document, check_network, network
from testkit.shapes import (
    blobs,
    dataset,
    load,
    rectangle_with_holes,
    touching_border,
    two_components,
)

CONFIGS = {"default": {}, "coarse_none": {"coarse": None}, "dce": {"method": "dce"}}


@pytest.mark.parametrize("config", CONFIGS)
@pytest.mark.parametrize("name", ["kimia216", "kimia99"])
def test_every_dataset_branch_is_an_attached_path(name: str, config: str) -> None:
    """Ordered, adjacent, attached to both nodes, length = steps, reconstruction exact,
    lines connected per component with cycles = holes: on every dataset shape."""
    for path in dataset(name):
        mask = load(path)
        check_document(mask, skelprune.prune(mask, **CONFIGS[config]).to_dict(curve=False))


@pytest.mark.parametrize("config", CONFIGS)
def test_synthetic_shapes_with_holes_and_components(config: str) -> None:
    masks = [rectangle_with_holes(), touching_border(), two_components()]
    masks += [blobs(seed, size=72, n=5, holes=4) for seed in range(40)]
    assert sum(int(m.any()) for m in masks) == len(masks)
    for mask in masks:
        check_document(mask, skelprune.prune(mask, **CONFIGS[config]).to_dict(curve=False))


def test_several_components_and_holes_are_really_exercised() -> None:
    mask = np.zeros((90, 150), bool)
    mask[5:45, 5:70] = True
    mask[15:22, 15:25] = False
    mask[15:30, 40:50] = False
    mask[50:85, 80:140] = True
    mask[60:70, 100:115] = False
    doc = skelprune.prune(mask).to_dict(curve=False)
    assert len(doc["components"]) == 2
    cycles = []
    for comp in doc["components"]:
        g = network(comp["skeleton"])
        cycles.append(g.number_of_edges() - g.number_of_nodes() + 1)
        check_network(mask, comp)
    assert sorted(cycles) == [1, 2]
    check_document(mask, doc)


def test_even_width_band_keeps_its_side_pixels_apart() -> None:
    """On an even-width band the axis keeps pixels beside its path; they are listed in
    ``off_path``, not in ``points``, and reconstruction needs them."""
    found = False
    for path in dataset("kimia216"):
        doc = skelprune.prune(load(path)).to_dict(curve=False)
        for comp in doc["components"]:
            for br in comp["skeleton"]["branches"]:
                if br["off_path"]:
                    found = True
                    on = {tuple(p[:2]) for p in br["points"]}
                    assert not on & {tuple(p[:2]) for p in br["off_path"]}
    assert found


def geojson_components(gj: dict) -> dict[int, tuple[list, list]]:
    """Per component: its LineString coordinate lists and its node Points."""
    out: dict[int, tuple[list, list]] = {}
    for f in gj["features"]:
        lines, points = out.setdefault(f["properties"]["component"], ([], []))
        if f["geometry"]["type"] == "LineString":
            lines.append(f["geometry"]["coordinates"])
        else:
            points.append(f["geometry"]["coordinates"])
    return out


@pytest.mark.parametrize("name", ["kimia216", "kimia99"])
def test_geojson_lines_form_one_network_per_component(name: str) -> None:
    """As a GIS tool sees it: every line ends on node Points, and per component the lines'
    union is one connected network with as many rings as the component has holes."""
    masks = [load(p) for p in dataset(name)]
    masks += [two_components(), rectangle_with_holes()] + [blobs(s, 72, 5, 4) for s in range(10)]
    for mask in masks:
        res = skelprune.prune(mask)
        holes = [graphcheck.holes(crop) for crop, _ in components(mask)]
        for ci, (lines, points) in geojson_components(res.to_geojson()).items():
            nodes = {tuple(p) for p in points}
            assert all(tuple(c[0]) in nodes and tuple(c[-1]) in nodes for c in lines)
            g = nx.Graph()
            g.add_nodes_from(nodes)
            for c in lines:
                g.add_edges_from((tuple(a), tuple(b)) for a, b in pairwise(c) if a != b)
            assert nx.is_connected(g)
            assert g.number_of_edges() - g.number_of_nodes() + 1 == holes[ci]
            # shapely: the lines never cross away from their nodes, so their thin buffer
            # is one polygon with one interior ring per hole
            net = unary_union([LineString(c) for c in lines]).buffer(0.05)
            assert net.geom_type == "Polygon" and len(net.interiors) == holes[ci]


def test_to_networkx_is_the_documented_graph() -> None:
    mask = two_components()
    res = skelprune.prune(mask)
    doc = res.to_dict(curve=False)
    g = res.to_networkx()
    assert isinstance(g, nx.MultiGraph)
    assert nx.number_connected_components(g) == len(doc["components"]) == 2
    for ci, comp in enumerate(doc["components"]):
        sk = comp["skeleton"]
        assert sum(1 for n in g if n[0] == ci) == len(sk["nodes"])
        for br in sk["branches"]:
            data = g.get_edge_data((ci, br["source"]), (ci, br["target"]), key=br["id"])
            assert data["length"] == br["length"] and data["points"] == br["points"]
        sub = g.subgraph([n for n in g if n[0] == ci])
        cycles = sub.number_of_edges() - sub.number_of_nodes() + 1
        assert cycles == graphcheck.holes(components(mask)[ci][0])
    assert sum(d for _, _, d in g.edges(data="length")) == pytest.approx(
        sum(c["skeleton"]["length"] for c in doc["components"])
    )
    endpoints = [n for n, kind in g.nodes(data="kind") if kind == "endpoint"]
    assert all(g.degree(n) == 1 for n in endpoints)


def test_polygon_coordinates_are_rounded_to_a_thousandth_of_a_pixel() -> None:
    """No float noise: every mapped value is rounded to the frame's decimals, within half
    a unit of that place of the exact mapping, and pixel documents stay integers."""
    ring = [[0.1, 0.25], [40.3, 0.25], [40.3, 15.15], [20.2, 9.05], [0.1, 15.15], [0.1, 0.25]]
    mask, frame = polygon_mask({"type": "Polygon", "coordinates": [ring]}, pixel_size=0.1)
    assert frame.decimals == 4
    res = skelprune.prune(mask)
    pixel = res.to_dict(curve=False)["components"][0]["skeleton"]
    mapped = res.to_dict(curve=False, frame=frame)["components"][0]["skeleton"]
    values = 0
    for pn, mn in zip(pixel["nodes"], mapped["nodes"], strict=True):
        x = frame.x0 + pn["x"] * frame.pixel_size
        y = frame.y0 - pn["y"] * frame.pixel_size
        for got, exact in ((mn["x"], x), (mn["y"], y), (mn["radius"], pn["radius"] * 0.1)):
            assert got == round(got, 4) and abs(got - exact) <= 0.5e-4 + 1e-12
            assert len(repr(got).split(".")[1]) <= 4
            values += 1
    for pb, mb in zip(pixel["branches"], mapped["branches"], strict=True):
        assert all(p[0] == int(p[0]) and p[1] == int(p[1]) for p in pb["points"])
        for (px, py, _), (mx, my, _) in zip(pb["points"], mb["points"], strict=True):
            assert abs(mx - (frame.x0 + px * 0.1)) <= 0.5e-4 + 1e-12
            assert abs(my - (frame.y0 - py * 0.1)) <= 0.5e-4 + 1e-12
            assert len(repr(mx).split(".")[1]) <= 4 and len(repr(my).split(".")[1]) <= 4
            values += 1
    assert values > 50
