"""The red team's small files and requests: each answers the 4xx that names its problem
(or its documented success), and the service answers the next small job.

The cases are :data:`testkit.hostile_cases.CASES`; ``python -m testkit.hostile_measure``
sends the same to a real server and measures the time, ``/healthz`` and memory
(docs/hostile-input.md).
"""

from __future__ import annotations

import io
import json

import numpy as np
import pytest
from fastapi.testclient import TestClient
from PIL import Image

from service.http.schemas import Problem
from testkit.hostile_cases import CASES, Case

#: Default limits but one worker.
SETTINGS = {"workers": 1, "queue_size": 8}


def _small_png() -> bytes:
    buf = io.BytesIO()
    Image.fromarray(np.pad(np.full((20, 40), 255, np.uint8), 5)).save(buf, "PNG")
    return buf.getvalue()


SMALL = _small_png()


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_each_hostile_request_gets_the_answer_that_names_its_problem(
    client: TestClient, case: Case
) -> None:
    body, ctype = case.body()
    headers = {"content-type": ctype, **({"accept": case.accept} if case.accept else {})}
    resp = client.post(case.path, content=body, params=case.params, headers=headers)
    assert resp.status_code in case.statuses, resp.text[:500]
    if resp.status_code >= 400:
        assert resp.headers["content-type"] == "application/problem+json"
        doc = resp.json()
        Problem.model_validate(doc)
        text = doc["detail"] + json.dumps(doc.get("errors", []))
        assert " at 0x" not in text and "np.float" not in text
    else:
        text = resp.text
    for word in case.words:
        assert word in text, text[:500]
    after = client.post("/v1/prune", content=SMALL, headers={"content-type": "image/png"})
    assert after.status_code == 200, after.text


def test_a_flat_coordinates_list_makes_one_short_answer(client: TestClient) -> None:
    # a body under the values bound goes to validation, which stops at a list's first
    # bad item: one error, not one per number
    body = b'{"type":"Polygon","coordinates":[' + b",".join([b"0"] * 60_000) + b"]}"
    resp = client.post("/v1/prune", content=body, headers={"content-type": "application/json"})
    assert resp.status_code == 422, resp.text[:300]
    doc = resp.json()
    assert doc["error_count"] == len(doc["errors"]) == 1
    assert len(resp.content) < 2000


def test_validation_errors_are_listed_up_to_twenty_with_their_count(client: TestClient) -> None:
    features = [{"type": "Feature", "properties": {}, "geometry": {"type": "Point"}}] * 1
    shapes = {"type": "FeatureCollection", "features": features}
    params = "&".join(f"nope{i}=1" for i in range(40))
    resp = client.post(
        f"/v1/prune?{params}",
        content=json.dumps(shapes),
        headers={"content-type": "application/json"},
    )
    assert resp.status_code == 422
    doc = resp.json()
    assert doc["error_count"] == 40 and len(doc["errors"]) == 20
    assert "(and 35 more)" in doc["detail"]


def test_a_label_image_read_without_labels_says_so_in_a_header(client: TestClient) -> None:
    lab = np.zeros((30, 60), np.uint8)
    lab[5:25, 5:25], lab[5:25, 30:55], lab[10:20, 26:29] = 60, 120, 180
    buf = io.BytesIO()
    Image.fromarray(lab).save(buf, "PNG")
    resp = client.post("/v1/prune", content=buf.getvalue(), headers={"content-type": "image/png"})
    assert resp.status_code == 200, resp.text
    assert "labels=true" in resp.headers["x-skelprune-warning"]
    plain = client.post("/v1/prune", content=SMALL, headers={"content-type": "image/png"})
    assert "x-skelprune-warning" not in plain.headers


def test_a_gif_mask_is_pruned_as_the_same_png_is(client: TestClient) -> None:
    mask = np.zeros((30, 60), np.uint8)
    mask[5:25, 5:55] = 255
    answers = []
    for fmt, ctype in (("PNG", "image/png"), ("GIF", "image/gif")):
        buf = io.BytesIO()
        Image.fromarray(mask).save(buf, fmt)
        resp = client.post("/v1/prune", content=buf.getvalue(), headers={"content-type": ctype})
        assert resp.status_code == 200, resp.text
        answers.append(resp.json()["components"])
    assert answers[0] == answers[1]


def test_an_animated_gif_is_refused_naming_its_frames(client: TestClient) -> None:
    frames = [Image.fromarray(np.full((8, 8), v, np.uint8)) for v in (0, 255)]
    buf = io.BytesIO()
    frames[0].save(buf, "GIF", save_all=True, append_images=frames[1:])
    resp = client.post("/v1/prune", content=buf.getvalue(), headers={"content-type": "image/gif"})
    assert resp.status_code == 400 and "more than 1 frame" in resp.json()["detail"]


def test_the_main_process_over_its_memory_budget_takes_no_new_body() -> None:
    from service.app import create_app
    from service.settings import Settings

    app = create_app(Settings(workers=1, main_memory_mb=128))  # less than it holds
    with TestClient(app, raise_server_exceptions=False) as c:
        resp = c.post("/v1/prune", content=SMALL, headers={"content-type": "image/png"})
        assert resp.status_code == 503, resp.text
        assert resp.json()["type"] == "urn:skelprune:problem:main-memory"
        assert "Retry-After" in resp.headers
        assert c.get("/healthz").status_code == 200
        assert "skelprune_main_resident_bytes" in c.get("/metrics").text
