"""Polygon bodies measured before they are decoded: the vertex limit, the time a
polygon's parts cost, and batches split, counted and validated off the event loop."""

from __future__ import annotations

import asyncio
import json
import time
from typing import Any

import pytest
from fastapi.testclient import TestClient

from service.http import bodies
from service.http.bodies import BATCH_MAX_ITEMS
from service.http.routes import prune
from service.http.scan import count_polygon, split_batch
from skelprune.budget import polygon_estimate
from testkit.adversarial import circle_polygon, unit_squares

pytestmark = pytest.mark.timeout(300)

SETTINGS = {"workers": 1, "queue_size": 8, "max_vertices": 1000}
JSON = {"content-type": "application/json"}
SQUARE = {"type": "Polygon", "coordinates": [[[0, 0], [10, 0], [10, 10], [0, 10], [0, 0]]]}


def problem(resp: Any, status: int, slug: str) -> str:
    assert resp.status_code == status, resp.text
    body = resp.json()
    assert body["type"] == f"urn:skelprune:problem:{slug}", body
    return body["detail"]


def test_positions_and_parts_are_counted_on_the_bytes() -> None:
    feature = {
        "type": "Feature",
        "bbox": [0, 0, 10, 10],
        "properties": {"name": "[not a position]", "tags": ["a", "b"]},
        "geometry": unit_squares(3),
    }
    counts = count_polygon(json.dumps(feature, indent=2).encode())
    assert counts.parts == 3
    assert counts.positions == 3 * 5 + 1  # the bbox is counted as one: an upper bound


def test_too_many_vertices_are_refused_before_any_object_is_built(
    client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    def never(body: bytes) -> Any:
        raise AssertionError("the body was decoded")

    monkeypatch.setattr(prune, "parse_polygon", never)
    detail = problem(
        client.post("/v1/prune", json=circle_polygon(1500, radius=100)), 422, "invalid-polygon"
    )
    assert "1501 positions, more than 1000 allowed" in detail


def test_many_small_parts_are_refused_at_once_by_their_estimated_time(
    client: TestClient,
) -> None:
    """The 20,000 unit squares (1.2 MB) took 20 s to read, fit and combine, holding a
    worker until the time limit: they are refused before any work, in a moment."""
    app = client.app
    app.state.settings.max_vertices = 100_000  # type: ignore[attr-defined]
    try:
        body = json.dumps(unit_squares(20_000)).encode()
        t0 = time.perf_counter()
        detail = problem(client.post("/v1/prune", content=body, headers=JSON), 413, "job-too-large")
        took = time.perf_counter() - t0
        assert "20000 parts and 100000 positions" in detail and "time limit of 30 s" in detail
        assert took < 10  # not the worker's 20 s
    finally:
        app.state.settings.max_vertices = 1000  # type: ignore[attr-defined]
    assert polygon_estimate(1_000, 5_000).seconds < 5  # an ordinary map's parts pass
    assert client.post("/v1/prune", json=unit_squares(100)).status_code == 200


def test_the_batch_limit_applies_while_the_list_is_read(client: TestClient) -> None:
    # 33 items, then what would not parse: the count stops the reading first
    body = json.dumps([SQUARE] * (BATCH_MAX_ITEMS + 1))[:-1].encode() + b", {oops"
    detail = problem(
        client.post("/v1/prune/batch", content=body, headers=JSON), 413, "body-too-large"
    )
    assert f"at most {BATCH_MAX_ITEMS} shapes" in detail
    with pytest.raises(OverflowError):
        split_batch(b"[" + b"0," * 150_000 + b"0]", BATCH_MAX_ITEMS)


def test_the_batch_is_split_and_validated_off_the_event_loop(
    client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    seen: list[bool] = []
    real = prune.parse_batch

    def spy(body: bytes) -> Any:
        try:
            asyncio.get_running_loop()
            seen.append(True)
        except RuntimeError:
            seen.append(False)
        return real(body)

    monkeypatch.setattr(prune, "parse_batch", spy)
    resp = client.post("/v1/prune/batch", json=[SQUARE])
    assert resp.status_code == 200 and seen == [False]


def test_a_batch_item_over_the_vertex_limit_is_its_own_problem_undecoded(
    client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    decoded: list[Any] = []
    real = bodies.polygon_item

    def spy(item: Any) -> Any:
        decoded.append(item)
        return real(item)

    monkeypatch.setattr(prune, "polygon_item", spy)
    resp = client.post("/v1/prune/batch", json=[circle_polygon(1500, radius=100), SQUARE])
    assert resp.status_code == 200
    lines = [json.loads(line) for line in resp.text.splitlines()]
    assert "more than 1000 allowed" in lines[0]["problem"]["detail"]
    assert "result" in lines[1]
    assert decoded == [SQUARE]  # the large one was never decoded


def test_a_match_body_counts_both_shapes(client: TestClient) -> None:
    resp = client.post(
        "/v1/match",
        json={"a": circle_polygon(900, radius=100), "b": circle_polygon(1200, radius=100)},
    )
    detail = problem(resp, 422, "invalid-polygon")
    assert "more than 2000 allowed" in detail


@pytest.mark.parametrize(
    ("accept", "status"),
    [
        ("application/x-ndjson", 200),
        ("application/json;q=0.5, text/html", 200),
        ("*/*", 200),
        ("application/x-ndjson;q=0, application/json;q=0", 406),
        ("application/x-ndjson;q=0", 406),
        ("text/application/x-ndjsonx", 406),  # contains the name, is not it
        ("image/png, text/*;q=0.9", 406),
    ],
)
def test_the_batch_negotiates_by_q_values_and_whole_media_types(
    client: TestClient, accept: str, status: int
) -> None:
    resp = client.post("/v1/prune/batch", json=[SQUARE], headers={"accept": accept})
    assert resp.status_code == status, resp.text
