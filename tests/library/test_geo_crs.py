"""Coordinates on the Earth: longitude/latitude pruned on the ground, in metres."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from shapely.geometry import MultiLineString, box

import skelprune
from skelprune.errors import InvalidOptionError, InvalidPolygonError
from testkit.rivers import on_earth, river

pyproj = pytest.importorskip("pyproj", reason="the geo extra")  # make test installs it

RIVER = river(10_000, 30, 90, seed=3)


def _lines(geo: dict) -> MultiLineString:
    return MultiLineString(
        [
            f["geometry"]["coordinates"]
            for f in geo["features"]
            if f["geometry"]["type"] == "LineString"
        ]
    )


def _apart(a: MultiLineString, b: MultiLineString) -> np.ndarray:
    """Distances from points along ``a`` to ``b``, over the river's local width there."""
    pts = shapely.points(shapely.get_coordinates(shapely.segmentize(a, 5.0)))
    width = 2 * shapely.distance(RIVER.polygon.exterior, pts)
    return shapely.distance(b, pts) / width


@pytest.mark.parametrize("lat", [0.0, 45.0, 70.0])
def test_river_in_lonlat_gives_the_line_in_metres(lat: float) -> None:
    metres = _lines(skelprune.prune(RIVER.polygon).to_geojson())
    res = skelprune.prune(on_earth(RIVER.polygon, 10.0, lat), crs="EPSG:4326")
    geo = res.to_geojson()
    assert geo["properties"]["crs"] == "EPSG:4326"
    assert geo["crs"] == {"type": "name", "properties": {"name": "EPSG:4326"}}
    # lengths in metres: the pixel fits the river's 30 m narrowest width
    assert 5 < res.to_dict()["raster"]["pixel_size"] < 15
    # back on the ground where the river was made
    local = pyproj.CRS.from_proj4(f"+proj=aeqd +lat_0={lat} +lon_0=10 +datum=WGS84 +units=m")
    to = pyproj.Transformer.from_crs("EPSG:4326", local, always_xy=True)
    ground = shapely.transform(_lines(geo), lambda xy: np.column_stack(to.transform(*xy.T)))
    for d in (_apart(ground, metres), _apart(metres, ground)):
        assert np.median(d) <= 0.01
        assert np.quantile(d, 0.9) <= 0.1
    # and as far from the true centre line as the line in metres
    true = MultiLineString([RIVER.centre])
    assert abs(np.median(_apart(ground, true)) - np.median(_apart(metres, true))) <= 0.01
    branch = next(f for f in geo["features"] if f["properties"]["kind"] == "branch")
    assert branch["properties"]["length"] > 1000  # metres, not degrees


def test_crs_member_of_the_geojson_is_read() -> None:
    square = on_earth(box(0, 0, 3000, 800), 25.0, 60.0)
    doc = {
        "type": "Feature",
        "properties": {},
        "geometry": square.__geo_interface__,
        "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:OGC:1.3:CRS84"}},
    }
    res = skelprune.prune(doc)
    raster = res.to_dict()["raster"]
    assert raster["crs"] == "urn:ogc:def:crs:OGC:1.3:CRS84"
    assert raster["projection"].startswith("+proj=aeqd")
    branches = [f for f in res.to_geojson()["features"] if f["properties"]["kind"] == "branch"]
    line = max(branches, key=lambda f: f["properties"]["length"])
    assert 2000 < line["properties"]["length"] < 3000  # metres: the long side less its ends
    lon, lat = np.array(line["geometry"]["coordinates"]).T
    assert np.all((lon > 24.9) & (lon < 25.1) & (lat > 59.9) & (lat < 60.1))


def test_projected_crs_is_used_as_it_is() -> None:
    rect = box(500_000, 6_600_000, 503_000, 6_600_800)
    plain = skelprune.prune(rect).to_geojson()
    utm = skelprune.prune(rect, crs="EPSG:32633").to_geojson()
    assert utm["crs"]["properties"]["name"] == "EPSG:32633"
    assert utm["features"] == plain["features"]
    assert "crs" not in plain and "crs" not in plain["properties"]


def test_geometries_one_projection_cannot_hold_are_refused() -> None:
    with pytest.raises(InvalidPolygonError, match="antimeridian"):
        skelprune.prune(box(-179.5, 10, 179.5, 11), crs="EPSG:4326")
    with pytest.raises(InvalidPolygonError, match="km from its centre"):
        skelprune.prune(box(0, 0, 20, 20), crs="EPSG:4326")
    with pytest.raises(InvalidPolygonError, match="pole"):
        skelprune.prune(box(0, 80, 10, 90), crs="EPSG:4326")
    with pytest.raises(InvalidOptionError, match="not a CRS"):
        skelprune.prune(box(0, 0, 1, 1), crs="EPSG:999999")
