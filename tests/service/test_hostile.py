"""Hostile input: bounded memory, no 5xx, no stalls (the in-process app).

Each test is one way a hostile or careless client once got a 5xx, a stall or a wrong
answer; the adversarial masks run small here (``python -m benchmarks adversarial`` runs
them at the pixel limit against the real server).
"""

from __future__ import annotations

import io
import json
import struct
import zlib
from typing import Any

import numpy as np
import pytest
from fastapi.testclient import TestClient
from PIL import Image

import skelprune
from service.http.schemas import Problem
from service.worker.jobs import Job, run_job
from skelprune.budget import (
    Estimate,
    JobTooLargeError,
    check_budget,
    estimate,
    shape_counts,
)
from skelprune.limits import Limits
from testkit.adversarial import CORPUS, checkerboard, dots, noise
from testkit.pngfile import chunk

pytestmark = pytest.mark.timeout(300)

#: A budget a warm worker (~300 MiB) fits under with room for small shapes only.
SETTINGS = {"workers": 1, "queue_size": 8, "job_memory_mb": 512, "max_pixels": 1_000_000}
PNG = {"content-type": "image/png"}
JSON = {"content-type": "application/json"}
SQUARE = {"type": "Polygon", "coordinates": [[[0, 0], [10, 0], [10, 10], [0, 10], [0, 0]]]}


def png(mask: np.ndarray) -> bytes:
    buf = io.BytesIO()
    Image.fromarray(mask.astype(np.uint8) * 255).save(buf, "PNG")
    return buf.getvalue()


def problem(resp: Any, status: int, slug: str) -> dict[str, Any]:
    assert resp.status_code == status, resp.text
    assert resp.headers["content-type"] == "application/problem+json"
    body = resp.json()
    Problem.model_validate(body)
    assert body["type"] == f"urn:skelprune:problem:{slug}"
    return body


# ------------------------------------------------------------ the adversarial corpus
@pytest.mark.parametrize("name", sorted(CORPUS))
def test_every_adversarial_mask_is_pruned_small(name: str) -> None:
    """At 40 px each mask of the corpus prunes (the coarse stage's pair table made pixel
    noise need gigabytes at 1024 px), and the estimate is above zero in both units."""
    mask = CORPUS[name](40)
    result = skelprune.prune(mask)
    assert result.components
    cost = estimate(mask)
    assert cost.bytes > 0 and cost.seconds > 0


@pytest.mark.parametrize("name", sorted(CORPUS))
def test_every_adversarial_mask_is_answered_by_the_service(client: TestClient, name: str) -> None:
    resp = client.post("/v1/prune", content=png(CORPUS[name](40)), headers=PNG)
    assert resp.status_code == 200, resp.text


def test_shape_counts_see_what_makes_a_mask_expensive() -> None:
    pixels, fg, boundary, n_components = shape_counts(dots(40))
    assert (pixels, fg, n_components) == (1600, 19 * 19, 19 * 19)
    assert boundary == 4 * fg  # isolated pixels: four sides each
    _, _, boundary, n_components = shape_counts(checkerboard(40))
    assert n_components == 1 and boundary == 2 * 40 * 39 + 4 * 20  # every pair differs


# ------------------------------------------------------------ memory and time budget
def test_a_mask_over_the_memory_budget_is_refused_before_work(client: TestClient) -> None:
    """22,500 isolated dots: a 2-KB PNG whose components alone are estimated at
    ~350 MiB: 413 naming the budget, at once."""
    body = problem(
        client.post("/v1/prune", content=png(dots(300)), headers=PNG), 413, "job-too-large"
    )
    assert "memory budget of 512 MiB" in body["detail"]
    # the worker is fine, and a small shape still fits
    assert client.post("/v1/prune", json=SQUARE).status_code == 200


def test_the_match_job_is_held_to_the_same_budget(client: TestClient) -> None:
    files = {
        "a": ("a.png", png(dots(300)), "image/png"),
        "b": ("b.png", png(dots(20)), "image/png"),
    }
    problem(client.post("/v1/match", files=files), 413, "job-too-large")


def test_a_job_estimated_past_the_time_limit_is_refused() -> None:
    cost = estimate(noise(200, 0.5))
    check_budget(cost, None, cost.seconds + 1)
    with pytest.raises(JobTooLargeError, match=r"over the job time limit of 0.01 s"):
        check_budget(cost, None, 0.01)
    with pytest.raises(JobTooLargeError, match=r"memory budget of 1 MiB"):
        check_budget(Estimate(0, 0.0), 2**20, None)  # the worker alone holds more


def test_memory_error_in_a_job_is_the_budget_problem(monkeypatch: pytest.MonkeyPatch) -> None:
    def exhausted(*args: Any, **kwargs: Any) -> None:
        raise MemoryError

    monkeypatch.setattr(skelprune.api, "prune_input", exhausted)
    job = Job(media="json", kind="image", data=png(dots(20)), limits=Limits(memory_mb=2048))
    with pytest.raises(JobTooLargeError, match="more than the memory budget of 2,048 MiB"):
        run_job(job)


def test_overlay_pixels_count_against_the_pixel_limit(client: TestClient) -> None:
    square = np.zeros((100, 100), bool)
    square[10:90, 10:90] = True
    resp = client.post(
        "/v1/prune",
        content=png(square),
        params={"overlay_scale": "16"},
        headers={**PNG, "accept": "image/png"},
    )
    body = problem(resp, 413, "image-too-large")
    assert "overlay image would have 2560000 pixels" in body["detail"]
    assert "limit is 1000000" in body["detail"]
    # the JSON document's embedded overlay too; scale 8 fits
    resp = client.post(
        "/v1/prune",
        content=png(square),
        params={"overlay": "true", "overlay_scale": "16"},
        headers=PNG,
    )
    problem(resp, 413, "image-too-large")
    resp = client.post(
        "/v1/prune",
        content=png(square),
        params={"overlay_scale": "8"},
        headers={**PNG, "accept": "image/png"},
    )
    assert resp.status_code == 200 and resp.headers["content-type"] == "image/png"


# ------------------------------------------------------------ bodies that once gave 5xx
def test_batch_nested_too_deep_is_a_422(client: TestClient) -> None:
    body = b"[" * 5000 + b"]" * 5000
    problem(client.post("/v1/prune/batch", content=body, headers=JSON), 422, "validation-error")


def test_a_deep_batch_item_is_that_items_problem(client: TestClient) -> None:
    deep = {"type": "Polygon", "coordinates": json.loads("[" * 900 + "]" * 900)}
    resp = client.post("/v1/prune/batch", json=[deep, SQUARE])
    assert resp.status_code == 200
    lines = [json.loads(line) for line in resp.text.splitlines()]
    assert lines[0]["index"] == 0 and lines[0]["problem"]["status"] == 422
    assert lines[1]["index"] == 1 and "result" in lines[1]


def test_batch_refuses_utf16_json_as_prune_does(client: TestClient) -> None:
    body = json.dumps([SQUARE]).encode("utf-16")
    detail = problem(
        client.post("/v1/prune/batch", content=body, headers=JSON), 422, "validation-error"
    )
    assert "not UTF-8" in detail["detail"]
    resp = client.post("/v1/prune", content=json.dumps(SQUARE).encode("utf-16"), headers=JSON)
    assert resp.status_code == 422


def test_a_truncated_image_stream_is_a_400(client: TestClient) -> None:
    """Valid chunks and CRCs, but the IDAT holds 10 of the 60 rows the header promises."""
    width, height = 40, 60
    rows = b"".join(b"\x00" + bytes([255 * (x // 10 % 2) for x in range(width)]) for _ in range(10))
    data = (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0))
        + chunk(b"IDAT", zlib.compress(rows))
        + chunk(b"IEND", b"")
    )
    body = problem(client.post("/v1/prune", content=data, headers=PNG), 400, "invalid-image")
    assert "truncated PNG" in body["detail"] and "410 of the 2460 bytes" in body["detail"]


def test_decoder_details_hold_no_internals(client: TestClient) -> None:
    """A text chunk that inflates past the reader's limit, and a stream Pillow cannot
    identify: the detail says what is wrong, not where in Pillow."""
    ihdr = chunk(b"IHDR", struct.pack(">IIBBBBB", 4, 4, 8, 0, 0, 0, 0))
    idat = chunk(b"IDAT", zlib.compress(b"\x00\xff\xff\xff\xff" * 4))
    ztxt = chunk(b"zTXt", b"Comment\x00\x00" + zlib.compress(b"a" * (4 << 20)))
    for data in (
        b"\x89PNG\r\n\x1a\n" + ihdr + ztxt + idat + chunk(b"IEND", b""),
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", struct.pack(">IIBBBBB", 4, 4, 8, 9, 0, 0, 0))
        + idat
        + chunk(b"IEND", b""),
    ):
        resp = client.post("/v1/prune", content=data, headers=PNG)
        detail = problem(resp, 400, "invalid-image")["detail"]
        for internal in ("0x", "BytesIO", "PngImagePlugin", "MAX_TEXT_CHUNK", "Pillow", "<"):
            assert internal not in detail, detail


def test_a_huge_beta_is_refused_by_the_option_check(client: TestClient) -> None:
    body = problem(
        client.post("/v1/prune", json=SQUARE, params={"beta": "1e308"}), 422, "validation-error"
    )
    assert "beta" in body["detail"] and "1e+09" in body["detail"]
    assert client.post("/v1/prune", json=SQUARE, params={"beta": "1e9"}).status_code == 200


def test_a_polygon_thinner_than_a_pixel_gets_a_hint(client: TestClient) -> None:
    sliver = {
        "type": "Polygon",
        "coordinates": [[[0, 0], [100, 0], [100, 0.01], [0, 0.01], [0, 0]]],
    }
    # (the default pixel fits the sliver; a size given by the user may not)
    body = problem(client.post("/v1/prune?longest_side=64", json=sliver), 422, "empty-mask")
    assert "thinner than a pixel" in body["detail"] and "pixel_size" in body["detail"]


# ------------------------------------------------------------ headers and methods
def test_an_accept_of_only_commas_is_no_preference(client: TestClient) -> None:
    resp = client.post("/v1/prune", json=SQUARE, headers={"accept": ",,,"})
    assert resp.status_code == 200 and resp.headers["content-type"] == "application/json"


def test_head_is_get_without_the_body(client: TestClient) -> None:
    for path in ("/healthz", "/v1/version"):
        resp = client.head(path)
        assert resp.status_code == 200 and resp.content == b""
        assert resp.headers["content-type"] == "application/json"
    assert client.head("/nowhere").status_code == 404
