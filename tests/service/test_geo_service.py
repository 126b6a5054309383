"""Standard GeoJSON over HTTP: foreign members, any id, null geometries, the CRS."""

from __future__ import annotations

from fastapi.testclient import TestClient
from shapely.geometry import box, mapping

from service.http.schemas import PruneDocument, SkeletonGeoJSON
from testkit.rivers import on_earth

GEO = {"accept": "application/geo+json"}


def _feature(geometry: object, **members: object) -> dict[str, object]:
    return {"type": "Feature", "properties": {"name": "reach"}, "geometry": geometry, **members}


def test_what_gdal_and_geopandas_write_is_accepted(client: TestClient) -> None:
    utm = {
        "type": "FeatureCollection",
        "name": "reaches",
        "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::32633"}},
        "bbox": [500_000, 6_600_000, 503_000, 6_600_800],
        "features": [
            _feature(mapping(box(500_000, 6_600_000, 503_000, 6_600_800)), id=1.5),
            _feature(None, id="empty"),
        ],
    }
    resp = client.post("/v1/prune", json=utm, headers=GEO)
    assert resp.status_code == 200, resp.text
    geo = resp.json()
    SkeletonGeoJSON.model_validate(geo)
    # the answer says its CRS, so that it is not read back as longitude/latitude
    assert geo["crs"] == {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::32633"}}
    assert geo["properties"]["crs"] == "urn:ogc:def:crs:EPSG::32633"
    (skipped,) = geo["properties"]["warnings"]
    assert skipped["kind"] == "skipped" and "features[1]" in skipped["message"]
    doc = client.post("/v1/prune", json=utm).json()
    PruneDocument.model_validate(doc)
    assert doc["raster"]["crs"] == "urn:ogc:def:crs:EPSG::32633"


def test_lonlat_by_the_crs_option_comes_back_in_lonlat_with_metres(client: TestClient) -> None:
    reach = mapping(on_earth(box(0, 0, 3000, 800), 10.0, 60.0))
    resp = client.post("/v1/prune", json=reach, params={"crs": "EPSG:4326"}, headers=GEO)
    assert resp.status_code == 200, resp.text
    geo = resp.json()
    lines = [f for f in geo["features"] if f["geometry"]["type"] == "LineString"]
    longest = max(lines, key=lambda f: f["properties"]["length"])
    assert 2000 < longest["properties"]["length"] < 3000  # metres
    lon, lat = longest["geometry"]["coordinates"][0]
    assert 9.9 < lon < 10.1 and 59.9 < lat < 60.1
    bad = client.post("/v1/prune", json=reach, params={"crs": "EPSG:999999"})
    assert bad.status_code == 422 and "crs" in bad.text


def test_an_option_inside_the_geojson_is_refused_not_ignored(client: TestClient) -> None:
    square = {**mapping(box(0, 0, 10, 10)), "beta": 3}
    resp = client.post("/v1/prune", json=square)
    assert resp.status_code == 422
    assert "beta" in resp.text and "option" in resp.text


def test_only_null_geometries_is_a_clear_problem(client: TestClient) -> None:
    resp = client.post(
        "/v1/prune", json={"type": "FeatureCollection", "features": [_feature(None)]}
    )
    assert resp.status_code == 422
    assert "null" in resp.text
