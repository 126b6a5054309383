"""Polygons for GIS users: the fitted pixel size, warnings instead of silent splits, lines
for maps (simplified, inside, connected), the cut-end rule and the one-call prune."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import networkx as nx
import numpy as np
import pytest
import shapely
from shapely.geometry import LineString, MultiPolygon, Point, Polygon, box, mapping

import skelprune
from skelprune.io.fit import narrowest_width
from skelprune.io.polygon import polygon_raster
from testkit.rivers import river


def dumbbell(neck: float = 4.0) -> Polygon:
    """Two 1000 × 1000 squares joined by a neck ``neck`` wide and 400 long."""
    return shapely.union_all(
        [
            box(0, 0, 1000, 1000),
            box(1400, 0, 2400, 1000),
            box(990, 500 - neck / 2, 1410, 500 + neck / 2),
        ]
    )


def lines_of(geo: dict) -> list[LineString]:
    return [
        LineString(f["geometry"]["coordinates"])
        for f in geo["features"]
        if f["geometry"]["type"] == "LineString"
    ]


def endpoints_of(geo: dict) -> list[tuple[float, float]]:
    return [
        tuple(f["geometry"]["coordinates"])
        for f in geo["features"]
        if f["properties"]["kind"] == "endpoint"
    ]


# ------------------------------------------------------------------ resolution
def test_pixel_size_comes_from_the_narrowest_part() -> None:
    strip = MultiPolygon([box(0, 0, 10_000, 60)])
    assert narrowest_width(strip) == pytest.approx(60, rel=0.05)
    raster = polygon_raster(strip)
    assert raster.fitted
    assert raster.frame.pixel_size == pytest.approx(20, rel=0.05)  # 3 px across 60
    assert raster.warnings == []


def test_compact_polygon_keeps_512_pixels_and_overrides_win() -> None:
    square = MultiPolygon([box(0, 0, 100, 100)])
    assert polygon_raster(square).frame.pixel_size == pytest.approx(100 / 512)
    assert polygon_raster(square, pixel_size=7.0).frame.pixel_size == 7.0
    assert not polygon_raster(square, pixel_size=7.0).fitted
    assert polygon_raster(square, longest_side=50).frame.pixel_size == pytest.approx(2.0)


def test_pixels_per_width_and_budget_bound_the_size() -> None:
    strip = MultiPolygon([box(0, 0, 10_000, 60)])
    assert polygon_raster(strip, pixels_per_width=6).frame.pixel_size == pytest.approx(10, rel=0.05)
    small = polygon_raster(strip, pixels_per_width=60, pixel_budget=100_000)
    assert small.mask.size <= 100_000
    assert small.frame.pixel_size > 1.0  # the budget, not the 60 px a width, decided


def test_river_at_default_options_is_one_line() -> None:
    r = river(8_000, 20, 120, seed=2)
    res = skelprune.prune(r.polygon)
    doc = res.to_dict(curve=False)
    assert doc["warnings"] == []
    assert doc["raster"]["pixel_size"] <= 20 / 2.5
    assert len(doc["components"]) == 1
    # two ends, each at most a fork to the cut's corners
    assert 2 <= len(doc["components"][0]["skeleton"]["endpoints"]) <= 4


# ------------------------------------------------------------------ warnings
def test_a_split_is_never_silent_and_names_a_size_that_holds() -> None:
    shape = dumbbell(neck=4.0)
    res = skelprune.prune(shape, longest_side=128)  # ~19 px: the neck is lost
    assert len(res.components) == 2
    (warning,) = res.warnings
    assert warning["kind"] == "split"
    assert warning["pixel_size"] is not None and warning["pixel_size"] < res.frame.pixel_size
    assert f"{warning['pixel_size']:.4g}" in warning["message"]
    fixed = skelprune.prune(shape, pixel_size=warning["pixel_size"])
    assert fixed.warnings == [] and len(fixed.components) == 1
    # the default size sees the neck
    assert skelprune.prune(shape).warnings == []


def test_a_vanished_part_and_a_lost_hole_are_reported() -> None:
    islands = MultiPolygon([box(0, 0, 1000, 1000), box(2000, 2000, 2001, 2001)])
    res = skelprune.prune(islands, longest_side=64)
    kinds = [w["kind"] for w in res.warnings]
    assert kinds == ["vanished"] and res.warnings[0]["part"] == 1
    ring = Polygon(box(0, 0, 1000, 1000).exterior, [box(500, 500, 501, 501).exterior])
    res = skelprune.prune(ring, longest_side=64)
    assert [w["kind"] for w in res.warnings] == ["holes"]
    assert res.to_dict()["warnings"] == res.to_geojson()["properties"]["warnings"]


def test_a_fitted_size_that_closes_an_inlet_is_refined() -> None:
    # a lagoon behind a mouth 1.5 wide: the width measure sees no narrow part (the mouth
    # is a gap, outside), the 512-pixel raster closes it, the check asks for less
    lagoon = box(0, 0, 1000, 1000).difference(
        shapely.union_all([box(400, 400, 600, 600), box(499.25, 600, 500.75, 1001)])
    )
    coarse = skelprune.prune(lagoon, longest_side=512)
    assert [w["kind"] for w in coarse.warnings] == ["holes"]
    res = skelprune.prune(lagoon)
    assert res.warnings == []
    assert res.frame.pixel_size <= coarse.warnings[0]["pixel_size"]


# ------------------------------------------------------------------ lines for maps
def test_map_lines_are_simplified_inside_and_connected() -> None:
    r = river(6_000, 20, 80, seed=4)
    res = skelprune.prune(r.polygon)
    geo = res.to_geojson()
    exact = res.to_geojson(simplify=0)
    lines, exact_lines = lines_of(geo), lines_of(exact)
    assert len(lines) == len(exact_lines)
    n, n_exact = sum(len(ln.coords) for ln in lines), sum(len(ln.coords) for ln in exact_lines)
    assert n < n_exact / 3
    pixel = res.frame.pixel_size
    grown = r.polygon.buffer(pixel * 1e-3)  # coordinates are rounded to 1/1000 pixel
    assert all(grown.covers(ln) for ln in lines)
    # the lines meet at their nodes: one connected network
    g = nx.Graph()
    for ln in lines:
        g.add_edge(ln.coords[0], ln.coords[-1])
    assert nx.is_connected(g)
    # the simplified line stays within the tolerance of the medial line, which lies
    # within a pixel of the pixel path; and as close to the true centre line as that path
    for a, b in zip(lines, exact_lines, strict=True):
        assert a.hausdorff_distance(b) <= 1.5 * pixel

    def offset(ls: list[LineString]) -> float:
        t = np.linspace(0, 1, 2000)
        pts = shapely.line_interpolate_point(shapely.MultiLineString(ls), t, normalized=True)
        return float(np.median(shapely.distance(pts, r.centre))) / pixel

    assert offset(lines) <= min(0.25, offset(exact_lines) + 0.02)


def test_simplified_lines_do_not_cross_and_keep_branch_ends() -> None:
    m = np.zeros((120, 160), bool)
    m[20:100, 20:140] = True
    m[50:70, 60:100] = False  # a hole: lines around it
    res = skelprune.prune(m)
    geo = res.to_geojson(simplify=2.0)
    lines = lines_of(geo)
    nodes = {
        f["properties"]["id"]: tuple(f["geometry"]["coordinates"])
        for f in geo["features"]
        if f["geometry"]["type"] == "Point"
    }
    for f, ln in zip(
        [f for f in geo["features"] if f["properties"]["kind"] == "branch"], lines, strict=True
    ):
        assert ln.coords[0] == nodes[f["properties"]["source"]]
        assert ln.coords[-1] == nodes[f["properties"]["target"]]
    for i, a in enumerate(lines):
        for b in lines[i + 1 :]:
            meet = a.intersection(b)
            ends = {a.coords[0], a.coords[-1]} & {b.coords[0], b.coords[-1]}
            assert all(tuple(p) in ends for p in shapely.get_coordinates(meet).tolist())
    # every line on the shape's pixels
    for ln in lines:
        for t in np.linspace(0, 1, 200):
            p = ln.interpolate(t, normalized=True)
            assert m[round(p.y), round(p.x)]


# ------------------------------------------------------------------ cut ends
def test_cut_ends_end_a_reach_at_the_middle_of_its_cut() -> None:
    reach = box(0, 0, 3000, 800)  # a straight reach cut square at both ends
    res = skelprune.prune(reach)
    doc = res.to_dict()
    assert len(doc["components"][0]["skeleton"]["endpoints"]) == 4  # the paper's forks
    geo = res.to_geojson(cut_ends=True)
    ends = endpoints_of(geo)
    assert len(ends) == 2
    pixel = res.frame.pixel_size
    for x, y in ends:
        assert math.isclose(y, 400, abs_tol=pixel)
        assert min(abs(x), abs(x - 3000)) <= pixel
    lines = lines_of(geo)
    assert len(lines) == 1  # one line end to end
    assert len(endpoints_of(res.to_geojson())) == 4  # off by default


def test_cut_ends_leave_a_pointed_end_alone() -> None:
    arrow = Polygon([(0, 0), (2000, 0), (2800, 400), (2000, 800), (0, 800)])
    res = skelprune.prune(arrow)
    assert res.n_endpoints() == 3  # the square end's fork and the point
    ends = sorted(endpoints_of(res.to_geojson(cut_ends=True)))
    assert len(ends) == 2  # the square end is cut at its middle, the point stays
    pixel = res.frame.pixel_size
    assert ends[0][0] <= pixel and math.isclose(ends[0][1], 400, abs_tol=pixel)
    point = max(endpoints_of(res.to_geojson()))  # the tip towards the point, as pruned
    assert ends[1] == point and point[0] > 2500


# ------------------------------------------------------------------ one call
def test_prune_takes_a_mapping_or_a_shapely_geometry() -> None:
    poly = Polygon(
        [(10, 10), (510, 10), (510, 90), (10, 90)], [[(200, 40), (300, 40), (300, 60), (200, 60)]]
    )
    a = skelprune.prune(poly)
    b = skelprune.prune(mapping(poly))
    c = skelprune.prune({"type": "Feature", "properties": {}, "geometry": mapping(poly)})
    assert a.to_dict() == b.to_dict() == c.to_dict()
    assert a.to_geojson() == b.to_geojson()
    doc = a.to_dict()
    assert doc["foreground"]["shape"] == "polygon"
    for comp in doc["components"]:
        for node in comp["skeleton"]["nodes"]:
            assert poly.buffer(a.frame.pixel_size).contains(Point(node["x"], node["y"]))
    # the raster's own pixels on request
    pixels = a.to_dict(frame=skelprune.io.frame.PixelFrame())
    assert pixels["components"][0]["skeleton"]["nodes"][0]["x"] == int(
        pixels["components"][0]["skeleton"]["nodes"][0]["x"]
    )


def test_polygon_options_are_checked() -> None:
    with pytest.raises(skelprune.InvalidOptionError, match="pixels_per_width"):
        skelprune.prune(box(0, 0, 10, 10), pixels_per_width=0.5)
    with pytest.raises(skelprune.InvalidOptionError, match="not both"):
        skelprune.prune(box(0, 0, 10, 10), pixel_size=1.0, longest_side=64)
    with pytest.raises(skelprune.InvalidPolygonError):
        skelprune.prune({"type": "Point", "coordinates": [0, 0]})


# ------------------------------------------------------------------ command line
def test_cli_prints_map_lines_and_warnings(tmp_path: Path) -> None:
    path = tmp_path / "islands.geojson"
    islands = MultiPolygon([box(0, 0, 1000, 1000), box(2000, 2000, 2001, 2001)])
    path.write_text(json.dumps(mapping(islands)))
    cmd = [sys.executable, "-m", "skelprune.cli", "prune", str(path)]
    run = subprocess.run([*cmd, "--longest-side", "64"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    doc = json.loads(run.stdout)
    assert [w["kind"] for w in doc["warnings"]] == ["vanished"]
    assert run.stderr.startswith(f"warning: {path}: part #1 of 2 ")
    reach = tmp_path / "reach.geojson"
    reach.write_text(json.dumps(mapping(box(0, 0, 3000, 800))))
    run = subprocess.run(
        [sys.executable, "-m", "skelprune.cli", "prune", str(reach), "--geojson", "--cut-ends"],
        capture_output=True,
        text=True,
    )
    assert run.returncode == 0, run.stderr
    geo = json.loads(run.stdout)
    assert geo["type"] == "FeatureCollection" and len(endpoints_of(geo)) == 2
    assert run.stderr == ""
