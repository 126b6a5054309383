"""Polygons over HTTP: the raster and its warnings in every answer, the map options."""

from __future__ import annotations

import io

import numpy as np
from fastapi.testclient import TestClient
from PIL import Image
from shapely.geometry import box, mapping

from service.http.schemas import PruneDocument, SkeletonGeoJSON

STRIP = mapping(box(0, 0, 10_000, 60))
ISLANDS = {
    "type": "MultiPolygon",
    "coordinates": [
        [[[0, 0], [1000, 0], [1000, 1000], [0, 1000], [0, 0]]],
        [[[2000, 2000], [2001, 2000], [2001, 2001], [2000, 2001], [2000, 2000]]],
    ],
}


def test_fitted_raster_in_the_document(client: TestClient) -> None:
    resp = client.post("/v1/prune", json=STRIP, params={"curve": "false"})
    assert resp.status_code == 200, resp.text
    doc = resp.json()
    PruneDocument.model_validate(doc)
    assert doc["raster"]["fitted"] and 18 < doc["raster"]["pixel_size"] < 22
    assert doc["warnings"] == []


def test_warnings_in_json_geojson_and_png_answers(client: TestClient) -> None:
    doc = client.post("/v1/prune", json=ISLANDS, params={"longest_side": 64}).json()
    assert [w["kind"] for w in doc["warnings"]] == ["vanished"]
    assert "pixel_size" in doc["warnings"][0]["message"]
    geo = client.post(
        "/v1/prune",
        json=ISLANDS,
        params={"longest_side": 64},
        headers={"accept": "application/geo+json"},
    )
    SkeletonGeoJSON.model_validate(geo.json())
    assert geo.json()["properties"]["warnings"] == doc["warnings"]
    png = client.post(
        "/v1/prune", json=ISLANDS, params={"longest_side": 64}, headers={"accept": "image/png"}
    )
    assert png.headers["x-skelprune-warnings"] == "1"


def test_map_options_shape_the_geojson_and_are_refused_elsewhere(client: TestClient) -> None:
    reach = mapping(box(0, 0, 3000, 800))
    geo = {"accept": "application/geo+json"}

    def vertices(params: dict) -> tuple[int, int]:
        body = client.post("/v1/prune", json=reach, params=params, headers=geo).json()
        feats = body["features"]
        lines = [f for f in feats if f["geometry"]["type"] == "LineString"]
        ends = [f for f in feats if f["properties"]["kind"] == "endpoint"]
        return sum(len(f["geometry"]["coordinates"]) for f in lines), len(ends)

    exact, _ = vertices({"simplify": 0})
    simple, ends = vertices({})
    assert simple < exact
    assert ends == 4 and vertices({"cut_ends": "true"})[1] == 2
    resp = client.post("/v1/prune", json=reach, params={"simplify": 1})
    assert resp.status_code == 422 and "GeoJSON answer" in resp.text
    resp = client.post("/v1/prune", json=reach, params={"simplify": -1}, headers=geo)
    assert resp.status_code == 422


def test_map_options_in_the_body_and_for_png_input(client: TestClient) -> None:
    geo = {"accept": "application/geo+json"}
    reach = mapping(box(0, 0, 3000, 800))

    def vertices(body: dict) -> int:
        feats = body["features"]
        return sum(
            len(f["geometry"]["coordinates"])
            for f in feats
            if f["geometry"]["type"] == "LineString"
        )

    exact = client.post("/v1/prune", json={"geojson": reach, "simplify": 0}, headers=geo)
    simple = client.post("/v1/prune", json={"geojson": reach}, headers=geo)
    assert exact.status_code == simple.status_code == 200
    assert vertices(simple.json()) < vertices(exact.json())
    mask = np.zeros((60, 200), np.uint8)
    mask[10:50, 10:190] = 255
    buf = io.BytesIO()
    Image.fromarray(mask).save(buf, "PNG")
    forms = [
        client.post(
            "/v1/prune",
            data=data,
            files={"file": ("r.png", buf.getvalue(), "image/png")},
            headers=geo,
        )
        for data in ({"simplify": "0"}, {})
    ]
    assert all(r.status_code == 200 for r in forms)
    assert vertices(forms[1].json()) < vertices(forms[0].json())
    assert "warnings" not in forms[1].json()["properties"]  # images have none to give
