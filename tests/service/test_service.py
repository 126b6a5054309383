"""POST /v1/prune and the ops endpoints through the ASGI client (real worker pool)."""

from __future__ import annotations

import base64
import io
import json
import math
import struct
from collections.abc import Iterator

import numpy as np
import pytest
import shapely
from fastapi.testclient import TestClient
from PIL import Image

import skelprune
from service.http.schemas import Problem, PruneDocument, Readiness, SkeletonGeoJSON
from skelprune.io.png import read_mask
from testkit import DATA

pytestmark = pytest.mark.timeout(300)

BIRD = (DATA / "kimia216" / "bird-10.png").read_bytes()
RECT = [[0.0, 0.0], [40.0, 0.0], [40.0, 20.0], [0.0, 20.0], [0.0, 0.0]]
HOLE = [[10.0, 5.0], [10.0, 15.0], [30.0, 15.0], [30.0, 5.0], [10.0, 5.0]]
LIMITS = {"max_pixels": 1_000_000, "max_body_bytes": 400_000, "max_vertices": 2000}


SETTINGS = {"workers": 2, "queue_size": 8, **LIMITS}


def png_bytes(arr: np.ndarray, mode: str | None = None) -> bytes:
    buf = io.BytesIO()
    Image.fromarray(arr, mode).save(buf, "PNG")
    return buf.getvalue()


def post_png(client: TestClient, data: bytes, params: dict | None = None, **headers: str):
    return client.post(
        "/v1/prune", content=data, params=params, headers={"content-type": "image/png", **headers}
    )


def assert_problem(resp, status: int, *fragments: str) -> dict:
    assert resp.status_code == status, resp.text
    assert resp.headers["content-type"] == "application/problem+json"
    body = resp.json()
    Problem.model_validate(body)
    assert body["status"] == status
    for fragment in fragments:
        assert fragment in body["detail"], body["detail"]
    assert "Traceback" not in resp.text and 'File "' not in resp.text
    return body


def library_document(png: bytes, **opts: object) -> dict:
    return json.loads(json.dumps(skelprune.prune(png, **opts).to_dict()))


# ----------------------------------------------------------------------- inputs
def test_raw_png_equals_library_call(client: TestClient) -> None:
    resp = post_png(client, BIRD)
    assert resp.status_code == 200 and resp.headers["content-type"] == "application/json"
    doc = resp.json()
    PruneDocument.model_validate(doc)  # strict: no extra keys, right types
    assert doc == library_document(BIRD)
    assert (doc["width"], doc["height"]) == (116, 103)


def test_multipart_png(client: TestClient) -> None:
    resp = client.post("/v1/prune", files={"file": ("bird.png", BIRD, "image/png")})
    assert resp.status_code == 200, resp.text
    assert resp.json() == library_document(BIRD)


def test_multipart_without_file_field(client: TestClient) -> None:
    resp = client.post("/v1/prune", data={"other": "x"}, files={"image": ("a.png", BIRD)})
    body = assert_problem(resp, 422, "multipart field 'file'")
    assert body["errors"][0]["loc"] == ["body", "file"]


@pytest.mark.parametrize("mode", ["L", "RGB", "RGBA", "P", "1"])
def test_png_colour_modes(client: TestClient, mode: str) -> None:
    grey = np.asarray(Image.open(io.BytesIO(BIRD)))
    buf = io.BytesIO()
    Image.fromarray(grey).convert(mode).save(buf, "PNG")
    resp = post_png(client, buf.getvalue())
    assert resp.status_code == 200, resp.text
    got, expected = resp.json(), library_document(BIRD)
    # the mid-range split is reported in the image's own sample values: 0/1 for 1-bit
    assert got["foreground"].pop("threshold") == (0.5 if mode == "1" else 127.5)
    expected["foreground"].pop("threshold")
    assert got == expected


@pytest.mark.parametrize(
    "geojson",
    [
        {"type": "Polygon", "coordinates": [RECT, HOLE]},
        {
            "type": "Feature",
            "properties": {"name": "r"},
            "geometry": {"type": "Polygon", "coordinates": [RECT, HOLE]},
        },
        {
            "type": "FeatureCollection",
            "features": [
                {
                    "type": "Feature",
                    "properties": None,
                    "geometry": {"type": "MultiPolygon", "coordinates": [[RECT, HOLE]]},
                }
            ],
        },
    ],
    ids=["polygon", "feature", "collection"],
)
def test_polygon_forms_give_the_same_answer(client: TestClient, geojson: dict) -> None:
    resp = client.post("/v1/prune", json=geojson, params={"longest_side": 80})
    assert resp.status_code == 200, resp.text
    doc = resp.json()
    PruneDocument.model_validate(doc)
    reference = client.post(
        "/v1/prune",
        json={"type": "Polygon", "coordinates": [RECT, HOLE]},
        params={"longest_side": 80},
    ).json()
    assert doc == reference
    assert (doc["width"], doc["height"]) == (84, 44)  # 80 px across + 2 px margins
    comp = doc["components"][0]
    loops = [n for n in comp["skeleton"]["nodes"] if n["kind"] in ("junction", "loop")]
    assert loops, "a shape with a hole keeps its cycle"


def test_polygon_answer_is_in_polygon_units(client: TestClient) -> None:
    """Same shape at scale 1 and scale 1000 (and shifted): coordinates, radii, lengths scale."""
    scale, dx, dy = 1000.0, 5e5, -2e6
    big = [[x * scale + dx, y * scale + dy] for x, y in RECT]
    small_doc = client.post("/v1/prune", json={"type": "Polygon", "coordinates": [RECT]}).json()
    big_doc = client.post(
        "/v1/prune",
        content=json.dumps({"type": "Polygon", "coordinates": [big]}),
        headers={"content-type": "application/geo+json"},
    ).json()
    a, b = small_doc["components"][0], big_doc["components"][0]
    assert len(a["skeleton"]["endpoints"]) == len(b["skeleton"]["endpoints"]) == 4
    assert math.isclose(b["skeleton"]["length"], a["skeleton"]["length"] * scale, rel_tol=1e-9)
    for na, nb in zip(a["skeleton"]["nodes"], b["skeleton"]["nodes"], strict=True):
        assert math.isclose(nb["x"], na["x"] * scale + dx, rel_tol=1e-9)
        assert math.isclose(nb["y"], na["y"] * scale + dy, rel_tol=1e-9)
        assert math.isclose(nb["radius"], na["radius"] * scale, rel_tol=1e-9)
    # Every skeleton point lies inside the polygon, in the polygon's own frame (y up).
    poly = shapely.Polygon(big)
    pts = [p for br in b["skeleton"]["branches"] for p in br["points"] + br["off_path"]]
    assert all(poly.contains(shapely.Point(x, y)) for x, y, _ in pts)
    assert max(r for *_, r in pts) <= 10 * scale * 1.01  # half the rectangle's height


def test_polygon_pixel_size_and_envelope_options(client: TestClient) -> None:
    body = {
        "geojson": {"type": "Polygon", "coordinates": [RECT]},
        "pixel_size": 0.5,
        "beta": 4.5,
        "curve": False,
    }
    resp = client.post("/v1/prune", json=body)
    assert resp.status_code == 200, resp.text
    doc = resp.json()
    PruneDocument.model_validate(doc)
    assert (doc["width"], doc["height"]) == (84, 44) and doc["beta"] == 4.5
    assert "curve" not in doc["components"][0]
    assert doc["components"][0]["area"] == 80 * 40


def test_self_intersecting_polygon_repaired_or_refused(client: TestClient) -> None:
    bow = {"type": "Polygon", "coordinates": [[[0, 0], [10, 10], [10, 0], [0, 10], [0, 0]]]}
    assert client.post("/v1/prune", json=bow).status_code == 200
    resp = client.post("/v1/prune", json=bow, params={"repair": "false"})
    assert_problem(resp, 422, "Self-intersection")


# ---------------------------------------------------------------------- outputs
def test_png_output_is_the_overlay(client: TestClient) -> None:
    resp = post_png(client, BIRD, accept="image/png")
    assert resp.status_code == 200 and resp.headers["content-type"] == "image/png"
    im = Image.open(io.BytesIO(resp.content))
    assert im.size == (116 * 5, 103 * 5)  # the default scale: longer side >= 512 px
    assert resp.content == skelprune.prune(read_mask(BIRD)).overlay_png()


def test_geojson_output(client: TestClient) -> None:
    resp = client.post(
        "/v1/prune",
        json={"type": "Polygon", "coordinates": [RECT]},
        headers={"accept": "application/geo+json"},
    )
    assert resp.status_code == 200
    assert resp.headers["content-type"] == "application/geo+json"
    fc = resp.json()
    SkeletonGeoJSON.model_validate(fc)
    kinds = [f["geometry"]["type"] for f in fc["features"]]
    assert "LineString" in kinds and "Point" in kinds
    points = [f for f in fc["features"] if f["geometry"]["type"] == "Point"]
    assert sum(f["properties"]["kind"] == "endpoint" for f in points) == 4
    assert all(f["properties"]["radius"] > 0 for f in points)
    # Coordinates are in polygon units: inside the 40 × 20 rectangle.
    for f in fc["features"]:
        coords = f["geometry"]["coordinates"]
        for x, y in coords if f["geometry"]["type"] == "LineString" else [coords]:
            assert 0 < x < 40 and 0 < y < 20


def test_overlay_and_curve_options(client: TestClient) -> None:
    doc = post_png(client, BIRD, {"overlay": "true", "curve": "false"}).json()
    raw = base64.b64decode(doc["overlay_png"])
    assert Image.open(io.BytesIO(raw)).size == (116 * 5, 103 * 5)
    assert "curve" not in doc["components"][0]
    full = post_png(client, BIRD).json()
    curve = full["components"][0]["curve"]
    assert "overlay_png" not in full and curve[0]["step"] == 0
    assert full["components"][0]["objective"] == min(s["objective"] for s in curve)


def test_beta_and_coarse_none(client: TestClient) -> None:
    doc = post_png(client, BIRD, {"beta": "2.5", "coarse": "none", "method": "bayesian"}).json()
    assert doc["beta"] == 2.5 and doc["coarse"] is None and doc["method"] == "bayesian"
    assert doc == library_document(BIRD, beta=2.5, coarse=None)


def test_coarse_default_and_none_in_a_polygon_body(client: TestClient) -> None:
    assert post_png(client, BIRD).json()["coarse"] is None  # the library's default: none
    body = {"geojson": {"type": "Polygon", "coordinates": [RECT]}, "coarse": "none"}
    resp = client.post("/v1/prune", json=body)
    assert resp.status_code == 200, resp.text
    assert resp.json()["coarse"] is None
    body["coarse"] = "dce"
    assert client.post("/v1/prune", json=body).json()["coarse"] == "dce"


@pytest.mark.parametrize(
    "opts",
    [{"method": "dce"}, {"method": "dce", "dce_threshold": 0.05}, {"coarse": "dce"}],
)
def test_dce_method_and_coarse_stage(client: TestClient, opts: dict) -> None:
    doc = post_png(client, BIRD, {k: str(v) for k, v in opts.items()}).json()
    PruneDocument.model_validate(doc)
    assert doc["method"] == opts.get("method", "bayesian")
    assert doc["coarse"] == opts.get("coarse")
    assert doc == library_document(BIRD, **opts)


@pytest.mark.parametrize(
    ("accept", "expected"),
    [
        ("*/*", "application/json"),
        ("image/*", "image/png"),
        ("application/geo+json;q=0.9, image/png;q=0.5", "application/geo+json"),
        ("text/html, application/*;q=0.2", "application/json"),
        ("image/png, */*;q=0.1", "image/png"),
    ],
)
def test_accept_negotiation(client: TestClient, accept: str, expected: str) -> None:
    resp = post_png(client, BIRD, accept=accept)
    assert resp.status_code == 200 and resp.headers["content-type"] == expected
    assert resp.headers["vary"] == "Accept"


# ----------------------------------------------------------------------- errors
def _header_only_png(width: int, height: int) -> bytes:
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    import zlib

    chunk = struct.pack(">I", 13) + b"IHDR" + ihdr + struct.pack(">I", zlib.crc32(b"IHDR" + ihdr))
    return b"\x89PNG\r\n\x1a\n" + chunk + b"\x00" * 64


@pytest.mark.parametrize(
    ("kwargs", "status", "fragment"),
    [
        ({"content": BIRD[:200]}, 400, "truncated PNG"),
        ({"content": b"BM" + b"\x00" * 64}, 400, "PNG, TIFF or GIF"),
        ({"content": b"GIF89a" + b"\x00" * 64}, 415, "image/gif"),
        ({"content": png_bytes(np.zeros((20, 20), np.uint8))}, 422, "no foreground"),
        ({"content": _header_only_png(5000, 5000)}, 413, "limit is 1000000"),
        ({"content": BIRD, "params": {"beta": "0"}}, 422, "beta"),
        ({"content": BIRD, "params": {"beta": "nan"}}, 422, "beta"),
        ({"content": BIRD, "params": {"method": "magic"}}, 422, "method"),
        ({"content": BIRD, "params": {"betta": "9"}}, 422, "betta"),
        (
            {"content": BIRD, "params": {"pixel_size": "2"}},
            422,
            "of image input (PNG or TIFF), not to the JSON",
        ),
        ({"content": BIRD, "headers": {"accept": "text/html"}}, 406, "text/html"),
        ({"content": b"x" * 500_000}, 413, "exceeds the limit of 400000 bytes"),
    ],
)
def test_png_errors(client: TestClient, kwargs: dict, status: int, fragment: str) -> None:
    headers = {"content-type": "image/png", **kwargs.pop("headers", {})}
    resp = client.post("/v1/prune", headers=headers, **kwargs)
    assert_problem(resp, status, fragment)


def test_chunked_body_over_the_limit(client: TestClient) -> None:
    def chunks() -> Iterator[bytes]:
        for _ in range(50):
            yield b"\x00" * 10_000

    resp = client.post("/v1/prune", content=chunks(), headers={"content-type": "image/png"})
    assert_problem(resp, 413, "exceeds the limit of 400000 bytes")


@pytest.mark.parametrize(
    ("body", "params", "fragment"),
    [
        ({"type": "Polygon", "coordinates": [RECT[:-1]]}, {}, "ring is not closed"),
        ({"type": "Polygon", "coordinates": [RECT[:3]]}, {}, "at least 4 items"),
        ({"type": "Point", "coordinates": [0, 0]}, {}, "'Point'"),
        # a foreign member is GeoJSON (RFC 7946 §6.1), an option there would be ignored
        ({"type": "Polygon", "coordinates": [RECT], "trim": False}, {}, "trim: an option"),
        (
            {"type": "Polygon", "coordinates": [[[0, 0], [1, "a"], [1, 1], [0, 0]]]},
            {},
            "valid number",
        ),
        (
            {"geojson": {"type": "Polygon", "coordinates": [RECT]}, "beta": 2},
            {"beta": "3"},
            "both in the query and the body",
        ),
        (
            {"type": "Polygon", "coordinates": [RECT]},
            {"pixel_size": "1", "longest_side": "64"},
            "not both",
        ),
        ({"type": "Polygon", "coordinates": [RECT]}, {"longest_side": "4"}, "longest_side"),
        (
            {"type": "Polygon", "coordinates": [[[i % 7, i // 7] for i in range(2500)]]},
            {},
            "2500 positions, more than 2000 allowed",
        ),
    ],
)
def test_polygon_errors(client: TestClient, body: dict, params: dict, fragment: str) -> None:
    resp = client.post("/v1/prune", json=body, params=params)
    assert_problem(resp, 422, fragment)


def test_polygon_raster_too_large(client: TestClient) -> None:
    resp = client.post(
        "/v1/prune", json={"type": "Polygon", "coordinates": [RECT]}, params={"pixel_size": "0.01"}
    )
    assert_problem(resp, 413, "exceeds the limit of 1000000")


def test_malformed_json(client: TestClient) -> None:
    resp = client.post(
        "/v1/prune", content=b'{"type": "Polygon", ', headers={"content-type": "application/json"}
    )
    assert_problem(resp, 422, "JSON")


def test_unsupported_media_type(client: TestClient) -> None:
    resp = client.post("/v1/prune", content=b"hello", headers={"content-type": "text/plain"})
    assert_problem(resp, 415, "'text/plain' is not supported")


def test_framework_errors_are_problems(client: TestClient) -> None:
    assert_problem(client.get("/v2/nothing"), 404, "/v2/nothing")
    resp = client.get("/v1/prune")
    assert_problem(resp, 405, "method GET is not allowed on /v1/prune")
    assert resp.headers["allow"] == "POST"


# --------------------------------------------------------------------------- ops
def test_health_ready_metrics(client: TestClient) -> None:
    assert client.get("/healthz").json()["status"] == "ok"
    ready = Readiness.model_validate(client.get("/readyz").json())
    assert ready.workers == 2 and ready.queue_size == 8 and ready.queued == 0
    post_png(client, BIRD)
    text = client.get("/metrics").text
    for name in (
        "http_requests_total",
        "http_request_duration_seconds",
        "skelprune_prune_seconds_count",
        "skelprune_queue_depth",
        "skelprune_workers_busy",
        "skelprune_job_seconds_bucket",
    ):
        assert name in text, name
    count = [line for line in text.splitlines() if line.startswith("skelprune_prune_seconds_count")]
    assert float(count[0].split()[-1]) >= 1


def test_openapi_lists_every_response_with_examples(client: TestClient) -> None:
    schema = client.get("/openapi.json").json()
    op = schema["paths"]["/v1/prune"]["post"]
    assert set(op["requestBody"]["content"]) == {
        "image/png",
        "image/gif",
        "image/tiff",
        "application/x-npy",
        "multipart/form-data",
        "application/json",
        "application/geo+json",
    }
    assert set(op["responses"]) == {
        "200",
        "400",
        "401",
        "406",
        "413",
        "415",
        "422",
        "500",
        "503",
        "504",
    }
    for path, ops in schema["paths"].items():
        for method, operation in ops.items():
            for status, resp in operation["responses"].items():
                for media, content in resp["content"].items():
                    where = (method, path, status, media)
                    assert media == "image/png" or "example" in content, where
    assert set(op["responses"]["200"]["content"]) == {
        "application/json",
        "image/png",
        "application/geo+json",
    }
    # The documented examples satisfy the documented models.
    PruneDocument.model_validate(op["responses"]["200"]["content"]["application/json"]["example"])
    for status in ("400", "401", "413", "422", "503", "504"):
        Problem.model_validate(
            op["responses"][status]["content"]["application/problem+json"]["example"]
        )


def test_malformed_multipart_is_a_400_problem(client: TestClient) -> None:
    resp = client.post(
        "/v1/prune", content=b"--x\r\nnot a part", headers={"content-type": "multipart/form-data"}
    )
    body = assert_problem(resp, 400)
    assert "boundary" in body["detail"].lower()


def test_errors_are_problems_whatever_the_accept_header(client: TestClient) -> None:
    resp = post_png(client, b"\x89PNG\r\n\x1a\n", accept="image/png")
    assert_problem(resp, 400, "truncated PNG")


def test_big_polygon_body(client: TestClient) -> None:
    """A polygon large enough to be validated off the event loop (> 256 KiB of JSON)."""
    t = np.linspace(0, 2 * np.pi, 1999, endpoint=False)
    ring = [[float(100 * np.cos(a)) + 0.123456789, float(50 * np.sin(a)) + 0.123456789] for a in t]
    body = json.dumps(
        {
            "geojson": {"type": "Polygon", "coordinates": [[*ring, ring[0]]]},
            "longest_side": 64,
            "curve": False,
        },
        indent=8,
    )
    assert 256 * 1024 < len(body) < 400_000
    resp = client.post("/v1/prune", content=body, headers={"content-type": "application/json"})
    assert resp.status_code == 200, resp.text
    doc = resp.json()
    assert doc["width"] == 68 and len(doc["components"][0]["skeleton"]["endpoints"]) >= 2
