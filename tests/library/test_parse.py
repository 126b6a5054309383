"""GeoJSON parsing: invalid geometry refused or repaired honestly, standard GeoJSON
(foreign members, any id, null geometries) accepted, many parts in about linear time."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from shapely.geometry import MultiPolygon, Polygon, box

import skelprune
from skelprune.errors import InvalidPolygonError
from skelprune.io.fit import covered_xy
from skelprune.io.parse import parse_geojson, parse_polygon

SHELL = [[0, 0], [10, 0], [10, 5], [0, 5], [0, 0]]


def test_overlapping_multipolygon_parts_refused_without_repair() -> None:
    overlapping = MultiPolygon([box(0, 0, 2, 2), box(1, 1, 3, 3)]).__geo_interface__
    with pytest.raises(InvalidPolygonError, match="parts overlap"):
        parse_geojson(overlapping, repair=False)
    # repaired (the default): their union
    assert parse_geojson(overlapping).area == pytest.approx(7.0)
    # parts that merely do not touch are valid as they are
    apart = MultiPolygon([box(0, 0, 1, 1), box(2, 2, 3, 3)]).__geo_interface__
    assert parse_geojson(apart, repair=False).area == pytest.approx(2.0)


def test_hole_equal_to_shell_has_no_area() -> None:
    empty = {"type": "Polygon", "coordinates": [SHELL, SHELL]}
    with pytest.raises(InvalidPolygonError, match="zero area"):
        parse_geojson(empty)
    with pytest.raises(InvalidPolygonError, match="invalid polygon"):
        parse_geojson(empty, repair=False)
    # beside a real part, it adds nothing (not the whole rectangle)
    multi = {
        "type": "MultiPolygon",
        "coordinates": [[SHELL, SHELL], [[[20, 0], [22, 0], [22, 2], [20, 2], [20, 0]]]],
    }
    assert parse_geojson(multi).area == pytest.approx(4.0)


def test_repaired_hole_is_cut_from_its_repaired_shell() -> None:
    # a bow-tie shell (two triangles) with a hole in its left triangle
    bow = [[0, 0], [4, 4], [4, 0], [0, 4], [0, 0]]
    hole = [[0.5, 1.5], [1.2, 2], [0.5, 2.5], [0.5, 1.5]]
    geom = parse_geojson({"type": "Polygon", "coordinates": [bow, hole]})
    expected = 8.0 - Polygon(hole).area
    assert geom.area == pytest.approx(expected)


def test_many_parts_keep_their_order_and_union_only_what_touches() -> None:
    n = 2500
    side = 50
    squares = [
        box(2 * (k // side), 2 * (k % side), 2 * (k // side) + 1, 2 * (k % side) + 1)
        for k in range(n)
    ]
    # two that overlap each other: merged into one, in the place of the first
    squares[10] = box(200, 0, 201.5, 1)
    squares[11] = box(201, 0, 202, 1)
    geom = parse_geojson(MultiPolygon(squares).__geo_interface__)
    assert len(geom.geoms) == n - 1
    assert geom.geoms[10].area == pytest.approx(2.0)
    kept = [s for i, s in enumerate(squares) if i not in (10, 11)]
    rest = [g for i, g in enumerate(geom.geoms) if i != 10]
    assert all(a.equals(b) for a, b in zip(kept, rest, strict=True))


def test_covered_xy_agrees_with_shapely() -> None:
    rng = np.random.default_rng(3)
    parts = [shapely.Point(rng.uniform(0, 100, 2)).buffer(rng.uniform(0.5, 4)) for _ in range(60)]
    geom = shapely.union_all(parts)
    geom = geom if isinstance(geom, MultiPolygon) else MultiPolygon([geom])
    xs, ys = rng.uniform(-5, 105, (2, 20_000))
    for strict, test in ((False, shapely.intersects_xy), (True, shapely.contains_xy)):
        assert np.array_equal(covered_xy(geom, xs, ys, strict=strict), test(geom, xs, ys))
    # points on a part's boundary count unless strict
    corner = MultiPolygon([box(0, 0, 1, 1), box(3, 3, 4, 4)])
    assert covered_xy(corner, np.array([1.0]), np.array([0.5])).tolist() == [True]
    assert covered_xy(corner, np.array([1.0]), np.array([0.5]), strict=True).tolist() == [False]


def _feature(geometry: object, **members: object) -> dict[str, object]:
    return {"type": "Feature", "properties": None, "geometry": geometry, **members}


def test_standard_geojson_members_and_null_geometries() -> None:
    square = box(0, 0, 40, 40).__geo_interface__
    fc = {
        "type": "FeatureCollection",
        "name": "lakes",  # GDAL writes it
        "bbox": [0, 0, 40, 40],
        "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::32633"}},
        "features": [
            _feature(square, id=1.5, bbox=[0, 0, 40, 40]),
            _feature(None, id="gone"),
        ],
    }
    parsed = parse_polygon(fc)
    assert parsed.crs == "urn:ogc:def:crs:EPSG::32633"
    assert parsed.geometry.area == pytest.approx(1600.0)
    (warning,) = parsed.warnings
    assert warning.kind == "skipped" and "$.features[1]" in warning.message
    # the warning reaches the answer
    res = skelprune.prune(fc, pixel_size=2.0)
    assert [w["kind"] for w in res.to_dict()["warnings"]] == ["skipped"]
    # every geometry null: a clear error
    with pytest.raises(InvalidPolygonError, match="null"):
        parse_polygon({"type": "FeatureCollection", "features": [_feature(None)]})


def test_a_crs_member_is_a_name_never_a_path_or_proj_string() -> None:
    square = box(0, 0, 40, 40).__geo_interface__
    for name in ("/etc/passwd", "+proj=longlat +init=x", "../epsg", "epsg:4326 "):
        doc = {**square, "crs": {"type": "name", "properties": {"name": name}}}
        with pytest.raises(InvalidPolygonError, match="authority code"):
            parse_polygon(doc)
