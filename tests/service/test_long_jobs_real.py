"""Long jobs end to end: a real ``python -m service`` on loopback, as a user runs it.

Submitted with ``Prefer: respond-async`` or to ``POST /v1/jobs``, a job answers 202
with its URL, its progress while it runs, and the synchronous route's answer byte for
byte; it can be cancelled (its worker stopped and replaced); the server refuses more
jobs than its limit, keeps results a bounded time and size, and fails a job over the
long-job time limit with the synchronous route's problem document.
"""

from __future__ import annotations

import io
import time
from collections.abc import Callable, Iterator
from typing import Any

import httpx
import numpy as np
import pytest
from PIL import Image

from testkit import DATA
from testkit.label_volumes import npy_bytes, touching_tubes
from testkit.procs import descendants
from testkit.realserver import Running, running_server

pytestmark = pytest.mark.timeout(300)

BIRD = (DATA / "kimia216" / "bird-10.png").read_bytes()
PNG = {"content-type": "image/png"}
NPY = {"content-type": "application/x-npy"}
ASYNC = {"prefer": "respond-async"}
#: Headers that differ between any two answers.
PER_ANSWER = {"x-request-id", "date"}


@pytest.fixture(scope="module")
def tubes() -> bytes:
    """A label volume of 25 touching tubes: several seconds of work, 25 components."""
    return npy_bytes(touching_tubes(160, 5))


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Running]:
    """Two workers, one long job at a time."""
    log = tmp_path_factory.mktemp("long") / "server.log"
    with running_server(log, workers="2", long_jobs="1") as running:
        yield running


@pytest.fixture(scope="module")
def tight(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Running]:
    """A 1-s long-job limit (no time screen), 8000 bytes of results kept 2 s."""
    log = tmp_path_factory.mktemp("tight") / "server.log"
    with running_server(
        log,
        workers="2",
        long_job_timeout="1",
        time_estimate_scale="0",
        long_job_results_bytes="8000",
        long_job_ttl="2",
    ) as running:
        yield running


def wait_for(
    client: httpx.Client, url: str, until: Callable[[dict[str, Any]], bool], seconds: float = 120
) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """Poll the job's status until ``until`` holds; the last status and all seen."""
    seen = []
    deadline = time.monotonic() + seconds
    while True:
        status = client.get(url)
        assert status.status_code == 200, status.text
        seen.append(status.json())
        if until(seen[-1]):
            return seen[-1], seen
        assert time.monotonic() < deadline, seen[-1]
        time.sleep(0.05)


def finished(status: dict[str, Any]) -> bool:
    return status["state"] not in ("queued", "running")


def same_answer(a: httpx.Response, b: httpx.Response) -> None:
    assert (a.status_code, a.content) == (b.status_code, b.content)
    assert {k: v for k, v in a.headers.items() if k not in PER_ANSWER} == {
        k: v for k, v in b.headers.items() if k not in PER_ANSWER
    }


@pytest.mark.parametrize(
    ("path", "headers"),
    [
        ("/v1/prune", {**ASYNC}),
        ("/v1/jobs", {"accept": "image/png"}),
        ("/v1/jobs", {"accept": "text/csv"}),
    ],
)
def test_result_is_the_synchronous_answer(
    server: Running, path: str, headers: dict[str, str]
) -> None:
    _, base = server
    with httpx.Client(base_url=base, timeout=60) as client:
        accepted = client.post(path, content=BIRD, headers={**PNG, **headers})
        assert accepted.status_code == 202, accepted.text
        url = accepted.headers["location"]
        body = accepted.json()
        assert url == body["url"] == f"/v1/jobs/{body['id']}" and len(body["id"]) >= 22
        assert body["state"] in ("queued", "running")
        assert (accepted.headers.get("preference-applied") == "respond-async") == (
            path == "/v1/prune"
        )
        status, _ = wait_for(client, url, finished)
        assert status["state"] == "done" and status["progress"] == {"done": 1, "total": 1}
        assert status["result"] == url + "/result"
        sync = client.post("/v1/prune", content=BIRD, headers={**PNG, **headers, "prefer": ""})
        assert sync.status_code == 200
        same_answer(client.get(url + "/result"), sync)
        same_answer(client.get(url + "/result"), sync)  # read again: kept


def test_a_failed_job_answers_the_synchronous_problem(server: Running) -> None:
    _, base = server
    buf = io.BytesIO()
    Image.fromarray(np.zeros((40, 60), np.uint8)).save(buf, format="PNG")  # no shape
    with httpx.Client(base_url=base, timeout=60) as client:
        accepted = client.post("/v1/prune", content=buf.getvalue(), headers={**PNG, **ASYNC})
        sync = client.post("/v1/prune", content=buf.getvalue(), headers=PNG)
        assert accepted.status_code == 202, accepted.text  # found out by the worker
        status, _ = wait_for(client, accepted.headers["location"], finished)
        result = client.get(accepted.headers["location"] + "/result")
        assert status["state"] == "failed" and result.status_code == sync.status_code == 422
        mine, theirs = result.json(), sync.json()
        assert mine.pop("request_id") != theirs.pop("request_id")
        assert status["problem"]["type"] == mine["type"] and mine == theirs


def test_unknown_job_is_404(server: Running) -> None:
    _, base = server
    with httpx.Client(base_url=base, timeout=30) as client:
        for method, path in (
            ("GET", "/v1/jobs/nosuchjob"),
            ("GET", "/v1/jobs/nosuchjob/result"),
            ("DELETE", "/v1/jobs/nosuchjob"),
        ):
            resp = client.request(method, path)
            assert resp.status_code == 404, (method, path)
            assert resp.json()["type"] == "urn:skelprune:problem:job-not-found"


def test_progress_limit_and_cancel(server: Running, tubes: bytes) -> None:
    proc, base = server
    with httpx.Client(base_url=base, timeout=60) as client:
        accepted = client.post("/v1/prune", content=tubes, headers={**NPY, **ASYNC})
        assert accepted.status_code == 202, accepted.text
        url = accepted.headers["location"]
        # one long job at a time: the next is refused until it ends
        refused = client.post("/v1/jobs", content=BIRD, headers=PNG)
        assert refused.status_code == 503 and "retry-after" in refused.headers
        assert refused.json()["type"] == "urn:skelprune:problem:too-many-jobs"
        # synchronous requests still find a worker meanwhile
        assert client.post("/v1/prune", content=BIRD, headers=PNG).status_code == 200
        status, seen = wait_for(client, url, lambda s: s["progress"]["done"] >= 2)
        assert status["state"] == "running" and status["progress"]["total"] == 25
        assert client.get(url + "/result").status_code == 409
        before = set(descendants(proc.pid))
        cancelled = client.delete(url)
        assert cancelled.status_code == 200 and cancelled.json()["state"] == "cancelled"
        after = set(descendants(proc.pid))
        assert before - after and after - before  # its worker was stopped and replaced
        result = client.get(url + "/result")
        assert result.status_code == 409 and result.json()["type"].endswith("job-cancelled")
        again = client.post("/v1/jobs", content=BIRD, headers=PNG)
        assert again.status_code == 202  # the slot is free again
        wait_for(client, again.headers["location"], finished)
    dones = [s["progress"]["done"] for s in seen]
    assert dones == sorted(dones)


def test_over_the_long_job_time_limit(tight: Running, tubes: bytes) -> None:
    _, base = tight
    with httpx.Client(base_url=base, timeout=60) as client:
        accepted = client.post("/v1/jobs", content=tubes, headers=NPY)
        assert accepted.status_code == 202, accepted.text
        status, _ = wait_for(client, accepted.headers["location"], finished)
        result = client.get(accepted.headers["location"] + "/result")
        assert status["state"] == "failed" and result.status_code == 504
        assert result.json()["type"] == status["problem"]["type"]
        assert "time limit of 1 s" in result.json()["detail"]


def test_results_kept_a_bounded_size_and_time(tight: Running) -> None:
    _, base = tight
    with httpx.Client(base_url=base, timeout=60) as client:
        urls = []
        for _ in range(2):  # two PNG answers of about 4 KB: the first is dropped
            accepted = client.post("/v1/jobs", content=BIRD, headers={**PNG, "accept": "image/png"})
            urls.append(accepted.headers["location"])
            wait_for(client, urls[-1], finished)
        assert client.get(urls[0]).status_code == 404
        assert client.get(urls[1] + "/result").status_code == 200
        # a JSON answer of about 10 KB cannot be kept: the job fails, the others stay
        accepted = client.post("/v1/jobs", content=BIRD, headers=PNG)
        status, _ = wait_for(client, accepted.headers["location"], finished)
        assert status["state"] == "failed"
        assert status["problem"]["type"] == "urn:skelprune:problem:result-too-large"
        assert client.get(urls[1]).status_code == 200
        time.sleep(2.5)  # past SKELPRUNE_LONG_JOB_TTL
        assert client.get(urls[1]).status_code == 404
        assert client.get(urls[1] + "/result").status_code == 404
