"""POST /v1/prune/batch: several shapes, NDJSON in input order, one line each."""

from __future__ import annotations

import io
import json

import numpy as np
import pytest
from fastapi.testclient import TestClient
from PIL import Image

from service.http.bodies import BATCH_MAX_ITEMS
from service.http.schemas import Problem, PruneDocument

pytestmark = pytest.mark.timeout(300)

SETTINGS = {"workers": 1, "queue_size": 8}


def png(h: int, w: int) -> bytes:
    mask = np.zeros((h, w), np.uint8)
    mask[4 : h - 4, 4 : w - 4] = 255
    buf = io.BytesIO()
    Image.fromarray(mask).save(buf, "PNG")
    return buf.getvalue()


def rect(w: float, h: float) -> dict:
    return {"type": "Polygon", "coordinates": [[[0, 0], [w, 0], [w, h], [0, h], [0, 0]]]}


def lines(resp) -> list[dict]:
    assert resp.status_code == 200, resp.text
    assert resp.headers["content-type"].startswith("application/x-ndjson")
    return [json.loads(line) for line in resp.text.splitlines()]


def test_multipart_pngs_in_input_order_with_a_bad_one(client: TestClient) -> None:
    sizes = [(30, 50), (40, 30), (20, 60)]
    files = [("file", (f"{i}.png", png(*hw), "image/png")) for i, hw in enumerate(sizes)]
    files.insert(1, ("file", ("bad.png", b"not a png", "image/png")))
    got = lines(client.post("/v1/prune/batch", files=files, data={"beta": "4"}))
    assert [g["index"] for g in got] == [0, 1, 2, 3]
    assert "problem" in got[1] and Problem.model_validate(got[1]["problem"]).status == 400
    docs = [PruneDocument.model_validate(g["result"]) for g in (got[0], got[2], got[3])]
    assert [(d.height, d.width) for d in docs] == sizes
    assert all(d.beta == 4.0 for d in docs)
    # each line is what POST /v1/prune gives for that shape alone
    single = client.post(
        "/v1/prune",
        params={"beta": "4"},
        content=png(*sizes[0]),
        headers={"content-type": "image/png"},
    ).json()
    assert got[0]["result"] == single


def test_json_list_of_polygons(client: TestClient) -> None:
    items = [rect(40, 20), {"type": "Point", "coordinates": [0, 0]}, rect(10, 30)]
    got = lines(client.post("/v1/prune/batch", json=items, params={"curve": "false"}))
    assert [g["index"] for g in got] == [0, 1, 2]
    assert got[1]["problem"]["status"] == 422 and "'Point'" in got[1]["problem"]["detail"]
    assert all("curve" not in g["result"]["components"][0] for g in (got[0], got[2]))


@pytest.mark.parametrize(
    ("kwargs", "status", "fragment"),
    [
        ({"json": [rect(4, 2)] * (BATCH_MAX_ITEMS + 1)}, 413, f"at most {BATCH_MAX_ITEMS}"),
        ({"json": []}, 422, "empty"),
        ({"json": {"type": "Polygon"}}, 422, "JSON list"),
        ({"json": [rect(4, 2)], "params": {"beta": "-1"}}, 422, "beta"),
        (
            {"json": [rect(4, 2)], "params": {"foreground": "zero"}},
            422,
            "only apply to image input",
        ),
        ({"content": b"x", "headers": {"content-type": "text/plain"}}, 415, "not supported"),
        (
            {
                "content": b"[]",
                "headers": {"content-type": "application/json", "content-encoding": "gzip"},
            },
            415,
            "Content-Encoding 'gzip'",
        ),
    ],
)
def test_a_bad_batch_is_refused_whole(client: TestClient, kwargs, status, fragment) -> None:
    resp = client.post("/v1/prune/batch", **kwargs)
    assert resp.status_code == status, resp.text
    assert resp.headers["content-type"] == "application/problem+json"
    assert fragment in resp.json()["detail"]


def slow(job):
    import time

    from service.worker.jobs import run_job

    time.sleep(0.5)
    return run_job(job)


def test_a_batch_never_starves_single_requests() -> None:
    """Two workers, a batch of 8 slow shapes: a single request sent meanwhile is answered
    long before the batch ends, because the batch holds one worker at a time."""
    import threading
    import time

    from service.app import create_app
    from service.http.routes.prune import job_function
    from service.settings import Settings

    app = create_app(Settings(workers=2, queue_size=8))
    app.dependency_overrides[job_function] = lambda: slow
    with TestClient(app) as client:
        done: dict[str, float] = {}
        t0 = time.perf_counter()

        def batch() -> None:
            items = [rect(10 + i, 5) for i in range(8)]
            resp = client.post("/v1/prune/batch", json=items)
            done["batch"] = time.perf_counter() - t0
            done["lines"] = len(lines(resp))

        thread = threading.Thread(target=batch)
        thread.start()
        time.sleep(0.7)
        assert client.get("/readyz").json()["busy"] <= 1  # the batch holds one worker at most
        resp = client.post("/v1/prune", json=rect(4, 2))
        done["single"] = time.perf_counter() - t0
        thread.join(120)
    app.dependency_overrides.clear()
    assert resp.status_code == 200 and done["lines"] == 8
    assert done["single"] < done["batch"]
