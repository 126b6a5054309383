"""POST /v1/match through the app on its real worker pool."""

from __future__ import annotations

import io

import numpy as np
from fastapi.testclient import TestClient
from PIL import Image

import skelprune
from skelprune.io.png import read_mask
from testkit import DATA

HAMMER = (DATA / "kimia216" / "hammer-1.png").read_bytes()
BIRD = (DATA / "kimia216" / "bird-2.png").read_bytes()
# an L: two arms of different lengths, in polygon units
L_SHAPE = {
    "type": "Polygon",
    "coordinates": [[[0, 0], [100, 0], [100, 20], [20, 20], [20, 60], [0, 60], [0, 0]]],
}


def png(mask: np.ndarray) -> bytes:
    buf = io.BytesIO()
    Image.fromarray(mask.astype(np.uint8) * 255).save(buf, format="PNG")
    return buf.getvalue()


def post_pngs(client: TestClient, a: bytes, b: bytes, **params):
    return client.post(
        "/v1/match",
        params=params,
        files={"a": ("a.png", a, "image/png"), "b": ("b.png", b, "image/png")},
    )


def test_same_png_is_distance_zero_with_identity(client: TestClient) -> None:
    resp = post_pngs(client, HAMMER, HAMMER)
    assert resp.status_code == 200, resp.text
    doc = resp.json()
    assert doc["distance"] == 0.0
    assert doc["endpoints"][0] == doc["endpoints"][1] == len(doc["correspondence"])
    for pair in doc["correspondence"]:
        assert pair["a"] == pair["b"]


def test_answer_agrees_with_the_library_and_the_prune_document(client: TestClient) -> None:
    doc = post_pngs(client, HAMMER, BIRD).json()
    lib = skelprune.match(read_mask(HAMMER), read_mask(BIRD))
    assert doc["distance"] == lib.distance > 0
    nodes = client.post("/v1/prune", files={"file": ("a.png", HAMMER, "image/png")}).json()[
        "components"
    ][0]["skeleton"]["nodes"]
    for pair in doc["correspondence"]:
        node = nodes[pair["a"]["node"]]
        assert node["kind"] == "endpoint"
        assert (node["x"], node["y"]) == (pair["a"]["x"], pair["a"]["y"])


def test_mirrored_png_matches_mirrored(client: TestClient) -> None:
    mask = np.asarray(Image.open(io.BytesIO(HAMMER))) != 0
    doc = post_pngs(client, png(mask), png(mask[:, ::-1])).json()
    assert doc["distance"] < 1e-9 and doc["mirrored"]
    w = mask.shape[1] - 1
    for pair in doc["correspondence"]:
        assert pair["b"]["x"] == w - pair["a"]["x"] and pair["b"]["y"] == pair["a"]["y"]


def test_polygons_in_their_own_units(client: TestClient) -> None:
    moved = {
        "type": "Polygon",
        "coordinates": [[[x + 1000, y + 500] for x, y in L_SHAPE["coordinates"][0]]],
    }
    resp = client.post("/v1/match", json={"a": L_SHAPE, "b": moved})
    assert resp.status_code == 200, resp.text
    doc = resp.json()
    assert doc["distance"] < 1e-6
    for pair in doc["correspondence"]:
        a, b = pair["a"], pair["b"]
        assert -1 <= a["x"] <= 101 and -1 <= a["y"] <= 61
        assert abs(b["x"] - a["x"] - 1000) < 1 and abs(b["y"] - a["y"] - 500) < 1


def test_options_apply_to_both(client: TestClient) -> None:
    doc = post_pngs(client, HAMMER, BIRD, method="dce").json()
    lib = skelprune.match(
        skelprune.prune(read_mask(HAMMER), method="dce"),
        skelprune.prune(read_mask(BIRD), method="dce"),
    )
    assert doc["distance"] == lib.distance


def problem(resp, status: int, slug: str) -> dict:
    assert resp.status_code == status, resp.text
    assert resp.headers["content-type"].startswith("application/problem+json")
    body = resp.json()
    assert body["type"].endswith(slug)
    return body


def test_errors(client: TestClient) -> None:
    problem(
        client.post("/v1/match", files={"a": ("a.png", HAMMER, "image/png")}),
        422,
        "validation-error",
    )
    problem(post_pngs(client, HAMMER, b"not a png"), 400, "invalid-image")
    problem(post_pngs(client, HAMMER, png(np.zeros((20, 20), bool))), 422, "empty-mask")
    ring = np.zeros((60, 60), np.uint8)
    yy, xx = np.mgrid[:60, :60]
    rr = np.hypot(yy - 30, xx - 30)
    ring[(rr < 25) & (rr > 12)] = 1
    body = problem(post_pngs(client, HAMMER, png(ring.astype(bool))), 422, "unmatchable-shape")
    assert "endpoint" in body["detail"]
    problem(post_pngs(client, HAMMER, BIRD, beta=-1), 422, "validation-error")
    problem(post_pngs(client, HAMMER, BIRD, overlay="true"), 422, "invalid-option")
    body = problem(post_pngs(client, HAMMER, BIRD, spacing="2,1,1"), 422, "invalid-option")
    assert "spacing" in body["detail"]
    problem(
        client.post("/v1/match", content=HAMMER, headers={"content-type": "image/png"}),
        415,
        "unsupported-media-type",
    )
    problem(client.post("/v1/match", json={"a": L_SHAPE}), 422, "validation-error")
    problem(
        client.post("/v1/match", json={"a": L_SHAPE, "b": L_SHAPE, "beta": 3}),
        422,
        "validation-error",
    )
    problem(
        client.post("/v1/match", json={"a": L_SHAPE, "b": L_SHAPE}, params={"foreground": "zero"}),
        422,
        "invalid-option",
    )
