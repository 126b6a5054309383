"""Pool failures as HTTP answers: 504 on time limit, 500 on a crash, 503 when full.

The worker-side job is swapped through FastAPI's dependency override for functions of
our own that hang, crash or fail; then the real one is put back to show the service
still serves.
"""

from __future__ import annotations

import json
import logging
import os
import threading
import time
from collections.abc import Iterator

import pytest
from fastapi.testclient import TestClient

from service.app import create_app
from service.http.routes.prune import job_function
from service.logs import JsonFormatter
from service.settings import Settings
from service.worker.jobs import Job, JobResult, run_job
from testkit import DATA

pytestmark = pytest.mark.timeout(300)

BIRD = (DATA / "kimia216" / "bird-10.png").read_bytes()
PNG = {"content-type": "image/png"}
#: The pool's job time limit here. A real job takes milliseconds, but a fresh worker on a
#: loaded 2-core CI machine can need a second more; ``slow`` leaves it that margin.
TIME_LIMIT = 4.0


def hang(job: Job) -> JobResult:
    time.sleep(3600)
    raise AssertionError("unreachable")


def crash(job: Job) -> JobResult:
    os._exit(9)


def buggy(job: Job) -> JobResult:
    raise KeyError("secret-internal-key")


def slow(job: Job) -> JobResult:
    time.sleep(TIME_LIMIT / 2)
    return run_job(job)


@pytest.fixture(scope="module")
def setup() -> Iterator[tuple[TestClient, object]]:
    app = create_app(Settings(workers=1, queue_size=0, job_timeout=TIME_LIMIT, retry_after=7))
    with TestClient(app) as client:
        yield client, app
    app.dependency_overrides.clear()


def use(app: object, fn: object) -> None:
    app.dependency_overrides[job_function] = lambda: fn  # type: ignore[attr-defined]


def problem(resp, status: int, slug: str) -> dict:
    assert resp.status_code == status, resp.text
    assert resp.headers["content-type"] == "application/problem+json"
    body = resp.json()
    assert body["type"] == f"urn:skelprune:problem:{slug}"
    assert "Traceback" not in resp.text
    return body


def test_time_limit_gives_504_and_a_fresh_worker(setup) -> None:
    client, app = setup
    pool = app.state.pool
    before = pool.restarts
    use(app, hang)
    body = problem(client.post("/v1/prune", content=BIRD, headers=PNG), 504, "job-timeout")
    assert f"time limit of {TIME_LIMIT:g} s" in body["detail"]
    assert pool.restarts == before + 1
    use(app, run_job)
    assert client.post("/v1/prune", content=BIRD, headers=PNG).status_code == 200
    assert client.get("/readyz").status_code == 200


def test_crash_gives_500_and_the_service_keeps_serving(setup) -> None:
    client, app = setup
    use(app, crash)
    body = problem(client.post("/v1/prune", content=BIRD, headers=PNG), 500, "worker-crashed")
    assert "exit code 9" in body["detail"] and "replaced" in body["detail"]
    use(app, run_job)
    assert client.post("/v1/prune", content=BIRD, headers=PNG).status_code == 200
    metrics = client.get("/metrics").text
    assert "skelprune_worker_restarts" in metrics


def test_unexpected_error_is_a_500_without_internals(setup) -> None:
    client, app = setup
    use(app, buggy)
    resp = client.post("/v1/prune", content=BIRD, headers=PNG)
    body = problem(resp, 500, "internal-error")
    assert "secret" not in resp.text and "KeyError" not in resp.text
    assert body["detail"] == "the job failed with an internal error"
    use(app, run_job)


def test_every_log_line_of_a_failed_job_names_its_request(setup) -> None:
    """The pool logs from its job thread: those lines carry the request's ID too."""
    client, app = setup
    lines: list[str] = []
    handler = logging.Handler()
    handler.emit = lambda record: lines.append(JsonFormatter().format(record))  # type: ignore
    logger = logging.getLogger("service")
    logger.addHandler(handler)
    try:
        use(app, buggy)
        resp = client.post("/v1/prune", content=BIRD, headers=PNG)
    finally:
        logger.removeHandler(handler)
        use(app, run_job)
    rid = problem(resp, 500, "internal-error")["request_id"]
    docs = [json.loads(line) for line in lines]
    assert any("job failed in worker" in d["message"] for d in docs), docs
    assert all(d.get("request_id") == rid for d in docs), docs


def test_full_queue_gives_503_with_retry_after(setup) -> None:
    client, app = setup
    pool = app.state.pool
    use(app, slow)
    results: list[int] = []
    first = threading.Thread(
        target=lambda: results.append(
            client.post("/v1/prune", content=BIRD, headers=PNG).status_code
        )
    )
    first.start()
    deadline = time.monotonic() + 30
    while pool.busy == 0 and time.monotonic() < deadline:
        time.sleep(0.01)
    assert pool.busy == 1
    resp = client.post("/v1/prune", content=BIRD, headers=PNG)
    body = problem(resp, 503, "queue-full")
    assert resp.headers["retry-after"] == "7"
    assert "busy" in body["detail"]
    ready = client.get("/readyz")
    problem(ready, 503, "queue-full")
    assert ready.headers["retry-after"] == "7"
    first.join(60)
    assert results == [200]
    use(app, run_job)
    assert client.get("/readyz").status_code == 200
