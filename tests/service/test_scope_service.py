"""scope and window over HTTP: in the query and the form, recorded in the document,
refused with a problem when wrong."""

from __future__ import annotations

import io

import numpy as np
from fastapi.testclient import TestClient
from PIL import Image

SETTINGS = {"workers": 1, "queue_size": 8, "max_pixels": 200_000}


def t_shape() -> bytes:
    m = np.zeros((60, 300), np.uint8)
    m[20:32, 5:295] = 255
    m[32:50, 150:160] = 255
    buf = io.BytesIO()
    Image.fromarray(m).save(buf, "PNG")
    return buf.getvalue()


def test_scope_in_query_and_form(client: TestClient) -> None:
    data = t_shape()
    q = client.post(
        "/v1/prune",
        content=data,
        headers={"content-type": "image/png"},
        params={"scope": "local", "window": 128, "curve": "false"},
    )
    assert q.status_code == 200, q.text
    doc = q.json()
    assert (doc["scope"], doc["window"]) == ("local", 128)
    assert len(doc["components"][0]["skeleton"]["endpoints"]) == 3
    form = client.post(
        "/v1/prune",
        files={"file": ("m.png", data, "image/png")},
        data={"scope": "local", "window": "128", "curve": "false"},
    )
    assert form.json()["components"] == doc["components"]
    plain = client.post("/v1/prune", content=data, headers={"content-type": "image/png"}).json()
    assert "scope" not in plain


def test_scope_refused_when_wrong(client: TestClient) -> None:
    data = t_shape()
    for params, name in (
        ({"scope": "tiles"}, "scope"),
        ({"window": 256}, "window"),
        ({"scope": "local", "window": 3}, "window"),
    ):
        bad = client.post(
            "/v1/prune", content=data, headers={"content-type": "image/png"}, params=params
        )
        assert bad.status_code in (400, 422), bad.text
        assert name in bad.text
