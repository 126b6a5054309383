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


def _geotiff(mask, *extra: tuple) -> bytes:
    """A GeoTIFF's bytes as GDAL writes its tags: 2 m pixels, UTM 33N, nodata 255."""
    import io

    import tifffile

    buf = io.BytesIO()
    tags = [
        (33550, 12, 3, (2.0, 2.0, 0.0)),
        (33922, 12, 6, (0.0, 0.0, 0.0, 500_000.0, 6_600_000.0, 0.0)),
        (34735, 3, 16, (1, 1, 0, 3, 1024, 0, 1, 1, 1025, 0, 1, 1, 3072, 0, 1, 32633)),
        (42113, 2, 0, "255"),
        *extra,
    ]
    tifffile.imwrite(buf, mask, extratags=tags)
    return buf.getvalue()


def test_a_geotiff_mask_answers_lines_in_its_crs_and_map_coordinates(client: TestClient) -> None:
    import numpy as np

    mask = np.zeros((60, 200), np.uint8)
    mask[20:40, 10:190] = 1  # a strip 40 m wide, 360 m long
    mask[0:5, 0:5] = 255  # nodata: not the shape
    body = _geotiff(mask)
    tiff = {"content-type": "image/tiff"}
    resp = client.post("/v1/prune", content=body, headers={**tiff, **GEO})
    assert resp.status_code == 200, resp.text
    geo = resp.json()
    SkeletonGeoJSON.model_validate(geo)
    assert geo["crs"] == {"type": "name", "properties": {"name": "EPSG:32633"}}
    assert geo["properties"]["crs"] == "EPSG:32633"
    branches = [f for f in geo["features"] if f["properties"]["kind"] == "branch"]
    assert len(branches) >= 1 and len(geo["properties"]["components"]) == 1  # no nodata
    xy = np.concatenate([np.asarray(f["geometry"]["coordinates"]) for f in branches])
    assert np.all((xy[:, 0] >= 500_020) & (xy[:, 0] <= 500_380))
    assert np.all((xy[:, 1] >= 6_599_920) & (xy[:, 1] <= 6_599_960))
    assert 250 < max(f["properties"]["length"] for f in branches) < 380  # metres
    # the document: the raster's pixels, and where they lie
    doc = client.post("/v1/prune", content=body, headers=tiff).json()
    PruneDocument.model_validate(doc)
    assert doc["georeference"] == {
        "crs": "EPSG:32633",
        "transform": [2.0, 0.0, 500_000.0, 0.0, -2.0, 6_600_000.0],
    }
    import skelprune

    assert doc == skelprune.prune(body).to_dict()  # the service is the library


def test_a_rotated_or_user_defined_geotiff_is_a_clear_problem(client: TestClient) -> None:
    import numpy as np

    mask = np.zeros((20, 30), np.uint8)
    mask[5:15, 5:25] = 1
    rotated = np.array([2, 0.5, 0, 500_000, 0.5, -2, 0, 6_600_000, 0, 0, 1, 0, 0, 0, 0, 1.0])
    user = (34735, 3, 8, (1, 1, 0, 1, 3072, 0, 1, 32767))
    for body, reason in [
        (_geotiff(mask, (34264, 12, 16, tuple(rotated))), "north-up with square pixels"),
        (_user_defined(mask, user), "user-defined"),
    ]:
        resp = client.post("/v1/prune", content=body, headers={"content-type": "image/tiff"})
        assert resp.status_code == 400, resp.text
        problem = resp.json()
        assert problem["type"].endswith("invalid-image") and reason in problem["detail"]


def _user_defined(mask, keys: tuple) -> bytes:
    import io

    import tifffile

    buf = io.BytesIO()
    tifffile.imwrite(
        buf,
        mask,
        extratags=[(33550, 12, 3, (2.0, 2.0, 0.0)), (33922, 12, 6, (0, 0, 0, 5e5, 6.6e6, 0)), keys],
    )
    return buf.getvalue()


def test_lonlat_without_a_crs_is_guessed_and_said_and_planar_is_an_option(
    client: TestClient,
) -> None:
    reach = mapping(on_earth(box(0, 0, 3000, 800), 10.0, 60.0))  # 0.05° × 0.007°
    geo = client.post("/v1/prune", json=reach, headers=GEO).json()
    assert geo["crs"] == {"type": "name", "properties": {"name": "OGC:CRS84"}}
    (warning,) = geo["properties"]["warnings"]
    assert warning["kind"] == "crs" and "longitude/latitude" in warning["message"]
    lines = [f for f in geo["features"] if f["geometry"]["type"] == "LineString"]
    assert max(f["properties"]["length"] for f in lines) > 2000  # metres
    planar = client.post("/v1/prune", json=reach, params={"crs": "planar"}, headers=GEO)
    assert planar.status_code == 200 and "crs" not in planar.json()
    assert planar.json()["properties"]["warnings"] == []
    pixels = {"type": "Polygon", "coordinates": [[[0, 0], [60, 0], [60, 50], [0, 0]]]}
    doc = client.post("/v1/prune", json=pixels).json()
    assert doc["raster"]["crs"] is None and doc["warnings"] == []
