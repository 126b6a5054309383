"""Every answer the library gives, the service gives: the map lines (``lines=map``,
``lines=main-path``) are the bytes ``skelprune centerlines`` writes for the same polygons
and options, and a volume's SWC is the library's ``to_swc()``; each refused where it
does not apply."""

from __future__ import annotations

import io
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from fastapi.testclient import TestClient
from shapely.geometry import box, mapping

import skelprune
from testkit import awkward

pytest.importorskip("geopandas", reason="the geo extra")  # make test installs it

pytestmark = pytest.mark.timeout(900)

CLI = [sys.executable, "-m", "skelprune.cli", "centerlines"]
GEOJSON = {"accept": "application/geo+json"}


def lakes() -> dict:
    """A GIS user's layer: a lake with islands and a river reach, with attributes, in
    UTM metres (what QGIS or GDAL writes)."""
    lake = awkward.lake_with_islands()
    reach = mapping(box(502_000, 5_000_000, 506_000, 5_000_080))
    return {
        "type": "FeatureCollection",
        "crs": awkward.CRS,
        "features": [
            {"type": "Feature", "properties": {"name": "lake", "depth": 12.5}, "geometry": lake},
            {"type": "Feature", "properties": {"name": "reach", "depth": 2.0}, "geometry": reach},
        ],
    }


def written(tmp_path: Path, layer: dict, *flags: str) -> bytes:
    """What ``skelprune centerlines`` writes for ``layer`` (OUT named as the service
    names its collection: ``centerlines``)."""
    source, target = tmp_path / "lakes.geojson", tmp_path / "centerlines.geojson"
    source.write_text(json.dumps(layer))
    run = subprocess.run(
        [*CLI, str(source), str(target), "--no-progress", *flags],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, run.stderr
    return target.read_bytes()


def features(body: bytes) -> list[bytes]:
    """The feature lines of GDAL's GeoJSON text, byte for byte."""
    return [line for line in body.splitlines() if line.startswith(b'{ "type": "Feature"')]


@pytest.mark.parametrize(
    ("query", "flags"),
    [
        ({"lines": "map"}, ()),
        ({"lines": "main-path"}, ("--main-path",)),
        ({"lines": "map", "pixel_size": "8"}, ("--pixel-size", "8")),
    ],
)
def test_map_lines_are_what_skelprune_centerlines_writes(
    client: TestClient, tmp_path: Path, query: dict, flags: tuple
) -> None:
    layer = lakes()
    resp = client.post("/v1/prune", json=layer, params=query, headers=GEOJSON)
    assert resp.status_code == 200, resp.text
    assert resp.headers["content-type"] == "application/geo+json"
    cli = written(tmp_path, layer, *flags)
    assert resp.content == cli  # the whole file: its name, its CRS, every feature
    doc = awkward.assert_finite_json(resp.content)
    rows = [f["properties"] for f in doc["features"]]
    assert {r["feature"] for r in rows} == {0, 1}  # each Feature pruned on its own
    assert {(r["name"], r["depth"]) for r in rows} == {("lake", 12.5), ("reach", 2.0)}
    lake_lines = [r for r in rows if r["name"] == "lake"]
    if query["lines"] == "main-path":
        assert len(lake_lines) == 1  # one network: its longest path
    else:
        assert len(lake_lines) > 2  # round the islands
    # the options in the JSON envelope give the same answer
    options = {k: float(v) if k == "pixel_size" else v for k, v in query.items()}
    envelope = client.post("/v1/prune", json={"geojson": layer, **options}, headers=GEOJSON)
    assert envelope.content == resp.content


def test_a_bare_polygon_is_one_feature_without_attributes(
    client: TestClient, tmp_path: Path
) -> None:
    square = {**mapping(box(500_000, 5_000_000, 500_600, 5_000_300)), "crs": awkward.CRS}
    resp = client.post("/v1/prune", json=square, params={"lines": "map"}, headers=GEOJSON)
    assert resp.status_code == 200, resp.text
    layer = {
        "type": "FeatureCollection",
        "crs": awkward.CRS,
        "features": [{"type": "Feature", "properties": {}, "geometry": square}],
    }
    assert features(resp.content) == features(written(tmp_path, layer))
    (row,) = [f["properties"] for f in json.loads(resp.content)["features"]]
    assert (row["feature"], row["kind"], round(row["length"])) == (0, "line", 600)


@pytest.mark.parametrize(
    ("query", "headers", "fragment"),
    [
        ({"lines": "map", "simplify": "1"}, GEOJSON, "simplify only apply to the skeleton's"),
        ({"lines": "main-path", "cut_ends": "true"}, GEOJSON, "cut_ends only apply"),
        ({"lines": "map"}, {}, "lines only apply to the GeoJSON answer"),
        ({"lines": "map"}, {"accept": "text/csv"}, "lines only apply to the GeoJSON answer"),
        ({"lines": "maps"}, GEOJSON, "query.lines: Input should be 'branches', 'map' or"),
        ({}, {"accept": "text/x-swc"}, "has no SWC answer"),
    ],
)
def test_map_lines_and_swc_are_refused_where_they_do_not_apply(
    client: TestClient, query: dict, headers: dict, fragment: str
) -> None:
    square = mapping(box(0, 0, 60, 20))
    resp = client.post("/v1/prune", json=square, params=query, headers=headers)
    assert resp.status_code == 422, resp.text
    assert fragment in resp.json()["detail"]


def test_map_lines_of_an_image_are_refused(client: TestClient) -> None:
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(np.pad(np.full((20, 60), 255, np.uint8), 4)).save(buf, "PNG")
    resp = client.post(
        "/v1/prune",
        content=buf.getvalue(),
        params={"lines": "map"},
        headers={"content-type": "image/png", **GEOJSON},
    )
    assert resp.status_code == 422, resp.text
    assert "of polygon input (GeoJSON)" in resp.json()["detail"]
    # the skeleton's branches of an image, as before
    resp = client.post(
        "/v1/prune",
        content=buf.getvalue(),
        params={"lines": "branches"},
        headers={"content-type": "image/png", **GEOJSON},
    )
    assert resp.status_code == 200, resp.text


@pytest.mark.parametrize("name", sorted(awkward.volumes()))
def test_a_volume_answers_the_librarys_swc(client: TestClient, name: str) -> None:
    volume = awkward.volumes()[name]
    buf = io.BytesIO()
    np.save(buf, volume)
    resp = client.post(
        "/v1/prune",
        content=buf.getvalue(),
        params={"spacing": "2,1,1"},
        headers={"content-type": "application/x-npy", "accept": "text/x-swc"},
    )
    assert resp.status_code == 200, resp.text
    assert resp.headers["content-type"].startswith("text/x-swc")
    res = skelprune.prune(volume, spacing=(2.0, 1.0, 1.0))
    assert resp.text == res.to_swc()
    # and refused where a volume has none
    resp = client.post(
        "/v1/prune",
        content=buf.getvalue(),
        headers={"content-type": "application/x-npy", **GEOJSON},
    )
    assert resp.status_code == 422 and "text/x-swc" in resp.json()["detail"]


def test_a_collection_of_map_lines_is_screened_as_the_sum_of_its_features() -> None:
    """Each Feature is pruned on its own, one after the other: the job's time estimate
    is their sum, screened before any is pruned."""
    from service.app import create_app
    from service.settings import Settings
    from skelprune.budget import estimate
    from skelprune.options import RasterOptions

    def square(x0: float) -> dict:
        return {**mapping(box(x0, 0, x0 + 400, 400)), "crs": awkward.CRS}

    def layer(*geoms: dict) -> dict:
        feats = [{"type": "Feature", "properties": {}, "geometry": g} for g in geoms]
        return {"type": "FeatureCollection", "crs": awkward.CRS, "features": feats}

    shape = skelprune.read_input(square(0), raster=RasterOptions(pixel_size=1.0))
    one = estimate(shape.mask).seconds
    # a budget of one and a half squares (the job's own time limit stays a minute)
    settings = Settings(workers=1, queue_size=4, job_timeout=60, time_estimate_scale=40 / one)
    query = {"lines": "map", "pixel_size": "1"}
    with TestClient(create_app(settings), raise_server_exceptions=False) as c:
        alone = c.post("/v1/prune", json=layer(square(0)), params=query, headers=GEOJSON)
        assert alone.status_code == 200, alone.text
        both = layer(square(0), square(600))
        resp = c.post("/v1/prune", json=both, params=query, headers=GEOJSON)
        assert resp.status_code == 413, resp.text
        assert "would take about" in resp.json()["detail"]
