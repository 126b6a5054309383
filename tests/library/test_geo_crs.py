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


def _crs_warnings(res: skelprune.PruneResult) -> list[dict]:
    return [w for w in res.to_dict()["warnings"] if w["kind"] == "crs"]


def test_lonlat_without_a_crs_is_read_as_rfc7946_with_a_warning() -> None:
    lonlat = on_earth(RIVER.polygon, 10.0, 60.0)  # 10 km: 0.18° × 0.09°
    guessed = skelprune.prune(shapely.geometry.mapping(lonlat))
    said = skelprune.prune(shapely.geometry.mapping(lonlat), crs="OGC:CRS84")
    (warning,) = _crs_warnings(guessed)
    assert "longitude/latitude" in warning["message"] and 'crs="planar"' in warning["message"]
    assert guessed.to_dict()["raster"]["crs"] == "OGC:CRS84"
    assert guessed.to_geojson()["crs"]["properties"]["name"] == "OGC:CRS84"
    # the same answer as when the CRS is given, but for the warning
    a, b = guessed.to_geojson(), said.to_geojson()
    a["properties"]["warnings"] = [w for w in a["properties"]["warnings"] if w["kind"] != "crs"]
    assert a == b and not _crs_warnings(said)
    branch = next(f for f in a["features"] if f["properties"]["kind"] == "branch")
    assert branch["properties"]["length"] > 1000  # metres, not degrees


def test_planar_says_no_crs_and_keeps_degrees_as_planar() -> None:
    lonlat = on_earth(RIVER.polygon, 10.0, 60.0)
    res = skelprune.prune(lonlat, crs="planar")
    assert res.to_dict()["raster"]["crs"] is None and not _crs_warnings(res)
    assert "crs" not in res.to_geojson()
    assert res.to_dict()["raster"]["pixel_size"] < 0.01  # in degrees


@pytest.mark.parametrize(
    "shape",
    [
        box(0, 0, 60, 50),  # pixels: examples/shape.geojson's extent, inside the bounds
        box(0, 0, 1.5, 0.5),  # more than a degree across
        box(500_000, 6_600_000, 503_000, 6_600_800),  # metres: outside the bounds
        box(170.5, 89.5, 171, 90.5),  # beyond a pole: not latitude
    ],
)
def test_coordinates_that_cannot_be_lonlat_stay_planar_byte_for_byte(shape) -> None:
    default = skelprune.prune(shape)
    planar = skelprune.prune(shape, crs="planar")
    assert default.to_dict() == planar.to_dict() and not _crs_warnings(default)
    assert default.to_dict()["raster"]["crs"] is None


def test_the_example_polygon_in_pixels_stays_planar() -> None:
    from testkit import REPO

    res = skelprune.prune(REPO / "examples" / "shape.geojson")
    assert res.to_dict()["raster"]["crs"] is None and not _crs_warnings(res)


def test_a_crs_member_or_option_is_not_second_guessed() -> None:
    lonlat = shapely.geometry.mapping(on_earth(box(0, 0, 3000, 800), 25.0, 60.0))
    utm = {**lonlat, "crs": {"type": "name", "properties": {"name": "EPSG:4326"}}}
    assert not _crs_warnings(skelprune.prune(utm))
    assert skelprune.prune(utm).to_dict()["raster"]["crs"] == "EPSG:4326"
    small = box(0.1, 0.1, 0.9, 0.6)  # within a degree, but said to be metres
    res = skelprune.prune(small, crs="EPSG:32633")
    assert res.to_dict()["raster"]["crs"] == "EPSG:32633" and not _crs_warnings(res)


def test_the_guess_is_at_most_a_degree_across() -> None:
    from skelprune.io.crs import GUESS_DEGREES, guess_crs

    assert GUESS_DEGREES == 1.0
    assert guess_crs(box(-180, -89.9, -179, -89)) == "OGC:CRS84"
    assert guess_crs(box(179, 0, 180, 1)) == "OGC:CRS84"
    assert guess_crs(box(0, 0, 1.001, 1)) is None
    assert guess_crs(box(179.5, 0, 180.5, 0.5)) is None  # beyond the antimeridian
    assert guess_crs(box(0, 0, 1e-6, 1e-7)) == "OGC:CRS84"
    assert guess_crs(box(0, 0, 9e-7, 9e-7)) is None  # under 11 cm: no map feature
    tiny = skelprune.prune(box(0, 0, 1e-9, 1e-9)).to_dict()  # as it always was: planar
    assert tiny["raster"]["crs"] is None and len(tiny["components"]) == 1


def test_centerlines_of_a_frame_without_crs_guess_as_prune_does() -> None:
    gpd = pytest.importorskip("geopandas")
    from skelprune.geo import centerlines

    lonlat = on_earth(box(0, 0, 3000, 800), 25.0, 60.0)
    out = centerlines(gpd.GeoDataFrame(geometry=[lonlat]))  # no CRS
    line = out[out["kind"] == "line"].iloc[0]
    assert 2500 < line["length"] < 3100 and 500 < line["width"] < 900  # metres
    assert lonlat.buffer(1e-9).contains(line.geometry)  # back in longitude/latitude
    planar = centerlines(gpd.GeoDataFrame(geometry=[lonlat]), crs="planar")
    assert planar[planar["kind"] == "line"].iloc[0]["length"] < 1  # degrees
