"""scope and window over HTTP: in the query and the form, recorded in the document,
refused with a problem when wrong."""

from __future__ import annotations

import dataclasses
import io

import numpy as np
import pytest
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


def test_the_memory_estimate_follows_the_scope() -> None:
    # the local scope never holds a whole-image pass but the cleaning and the stitching:
    # its estimate per pixel is lower, so a job the global estimate refuses fits
    from service.worker.jobs import Job, run_job
    from skelprune.budget import BYTES_PER_PIXEL, BYTES_PER_PIXEL_LOCAL, estimate, resident_bytes
    from skelprune.errors import JobTooLargeError
    from skelprune.limits import Limits
    from skelprune.options import PruneOptions

    mask = np.zeros((4096, 4096), np.uint8)
    mask[1000:1012, 100:4000] = 255  # a long straight road and a crossing one
    mask[200:3900, 2000:2010] = 255
    buf = io.BytesIO()
    Image.fromarray(mask).save(buf, format="PNG")
    local, whole = estimate(mask > 0, scope="local"), estimate(mask > 0)
    assert whole.bytes - local.bytes == (BYTES_PER_PIXEL - BYTES_PER_PIXEL_LOCAL) * mask.size
    budget = resident_bytes() + (local.bytes + whole.bytes) // 2
    limits = Limits(memory_mb=budget // 2**20)
    job = Job(media="json", kind="image", data=buf.getvalue(), limits=limits)
    with pytest.raises(JobTooLargeError, match="memory budget"):
        run_job(job)
    answer = run_job(dataclasses.replace(job, options=PruneOptions(scope="local")))
    assert answer.media_type == "application/json"
