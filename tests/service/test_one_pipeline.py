"""The service runs the library's one pipeline: for the same input and options, its
answers are the library's, byte for byte once serialised."""

from __future__ import annotations

import io
import json
import subprocess
import sys

import numpy as np
import pytest
from fastapi.testclient import TestClient
from PIL import Image

import skelprune

L_SHAPE = {
    "type": "Polygon",
    "coordinates": [
        [
            [5000, 3000],
            [5400, 3000],
            [5400, 3060],
            [5060, 3060],
            [5060, 3300],
            [5000, 3300],
            [5000, 3000],
        ]
    ],
}


def rectangle_png() -> bytes:
    a = np.zeros((30, 60), np.uint8)
    a[5:25, 5:55] = 255
    buf = io.BytesIO()
    Image.fromarray(a).save(buf, "PNG")
    return buf.getvalue()


def same(doc: dict) -> dict:
    return json.loads(json.dumps(doc))


@pytest.mark.parametrize(
    "options",
    [
        {"min_margin": 0.05, "curve": False},
        {"method": "dce", "dce_threshold": 0.02, "sequence": True},
    ],
)
def test_service_cli_and_library_give_the_same_document(
    client: TestClient, tmp_path, options: dict
) -> None:
    png = rectangle_png()
    params = {k: json.dumps(v) if isinstance(v, bool) else str(v) for k, v in options.items()}
    resp = client.post(
        "/v1/prune", content=png, params=params, headers={"content-type": "image/png"}
    )
    assert resp.status_code == 200, resp.text
    library = same(skelprune.prune(png, **options).to_dict())
    assert resp.json() == library
    for name in ("min_margin", "dce_threshold"):
        assert resp.json()[name] == library[name]
    path = tmp_path / "rect.png"
    path.write_bytes(png)
    flags = [
        f"--{k.replace('_', '-')}"
        if v is True
        else f"--no-{k.replace('_', '-')}"
        if v is False
        else f"--{k.replace('_', '-')}={v}"
        for k, v in options.items()
    ]
    run = subprocess.run(
        [sys.executable, "-m", "skelprune.cli", "prune", str(path), *flags],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr
    assert json.loads(run.stdout) == library


def test_service_answers_a_polygon_as_the_library_does(client: TestClient) -> None:
    params = {"longest_side": "80", "beta": "6"}
    doc = client.post("/v1/prune", json=L_SHAPE, params=params)
    assert doc.status_code == 200, doc.text
    res = skelprune.prune(L_SHAPE, longest_side=80, beta=6.0)
    assert doc.json() == same(res.to_dict())
    geo = client.post(
        "/v1/prune",
        json=L_SHAPE,
        params={**params, "simplify": "0"},
        headers={"accept": "application/geo+json"},
    )
    assert geo.json() == same(res.to_geojson(simplify=0.0))
    assert geo.json()["properties"]["simplify"] == 0.0


def test_the_match_job_answers_as_the_library(client: TestClient) -> None:
    moved = json.loads(json.dumps(L_SHAPE))
    moved["coordinates"][0] = [[x - 5000, y - 3000] for x, y in moved["coordinates"][0]]
    resp = client.post("/v1/match", json={"a": L_SHAPE, "b": moved}, params={"beta": "6"})
    assert resp.status_code == 200, resp.text
    a, b = skelprune.prune(L_SHAPE, beta=6.0), skelprune.prune(moved, beta=6.0)
    assert resp.json() == same(skelprune.match(a, b).to_dict())
    assert all(p["a"]["x"] >= 5000 for p in resp.json()["correspondence"])
