"""`python -m service` as a real process on 127.0.0.1, spoken to over HTTP."""

from __future__ import annotations

import signal
import time
from collections.abc import Callable
from typing import Any

import httpx
import pytest

from testkit import DATA
from testkit.realserver import stop

pytestmark = pytest.mark.timeout(180)

BIRD = (DATA / "kimia216" / "bird-10.png").read_bytes()


def test_real_server_round_trip(real_server: Callable[..., Any]) -> None:
    with real_server(ready="/healthz", workers="1") as (proc, base):
        with httpx.Client(base_url=base, timeout=30) as client:
            # live at once; ready once the worker has warmed up (503 "starting" till then)
            for _ in range(600):
                ready = client.get("/readyz")
                if ready.status_code == 200:
                    break
                assert ready.status_code == 503, ready.text
                assert ready.json()["type"] == "urn:skelprune:problem:starting", ready.text
                time.sleep(0.1)
            assert ready.json()["workers"] == 1
            doc = client.post(
                "/v1/prune", content=BIRD, headers={"content-type": "image/png"}
            ).json()
            assert (doc["width"], doc["height"]) == (116, 103)
            assert len(doc["components"]) == 1
            png = client.post(
                "/v1/prune",
                files={"file": ("b.png", BIRD, "image/png")},
                headers={"accept": "image/png"},
            )
            assert png.status_code == 200 and png.content.startswith(b"\x89PNG")
            poly = client.post(
                "/v1/prune",
                json={"type": "Polygon", "coordinates": [[[0, 0], [4, 0], [4, 2], [0, 2], [0, 0]]]},
                headers={"accept": "application/geo+json"},
            )
            assert poly.headers["content-type"] == "application/geo+json"
            bad = client.post("/v1/prune", content=b"nope", headers={"content-type": "image/png"})
            assert bad.status_code == 400
            assert bad.headers["content-type"] == "application/problem+json"
            assert "http_requests_total" in client.get("/metrics").text
        code = stop(proc, signal.SIGINT, 30)  # uvicorn's graceful shutdown, pool closed
    assert code == 0
