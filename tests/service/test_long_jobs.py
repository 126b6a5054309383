"""Long jobs in-process: the pool's progress, cancel, own time limit and unqueued jobs
(real worker processes, job functions of our own); the store's limits, time to live and
byte bound; ``Prefer`` parsing; the settings; the routes on the in-process app."""

from __future__ import annotations

import asyncio
import os
import threading
import time
from collections.abc import Awaitable, Callable
from typing import Any

import pytest
from fastapi.testclient import TestClient
from starlette.requests import Request

import skelprune
from service.http.long_job import prefers_async
from service.http.routes.prune import job_function
from service.settings import Settings
from service.worker.jobs import Job, run_job
from service.worker.long_jobs import (
    JobNotFoundError,
    LongJobs,
    ResultTooLargeError,
    StoredAnswer,
    TooManyJobsError,
    run_reporting,
)
from service.worker.pool import (
    JobCancelledError,
    JobTimeoutError,
    QueueFullError,
    WorkerPool,
)
from service.worker.process import report_progress
from testkit import DATA
from testkit.label_volumes import touching_tubes

pytestmark = pytest.mark.timeout(180)

BIRD = (DATA / "kimia216" / "bird-10.png").read_bytes()


# Job functions: module level, so that the workers can unpickle them.
def report_steps(steps: int, pause: float) -> int:
    for k in range(steps):
        time.sleep(pause)
        report_progress(k + 1, steps)
    return os.getpid()


def count_to(n: int, progress: Callable[[int, int], None] | None = None) -> int:
    assert progress is not None
    for k in range(n):
        progress(k + 1, n)
    return n


def pid_after(seconds: float) -> int:
    time.sleep(seconds)
    return os.getpid()


def slow_job(job: Job, progress: Callable[[int, int], None] | None = None) -> Any:
    """The real job after ten reported steps of 0.3 s (a long job to watch and cancel)."""
    for k in range(10):
        time.sleep(0.3)
        if progress is not None:
            progress(k + 1, 10)
    return run_job(job)


def with_pool(body: Callable[[WorkerPool], Awaitable[Any]], size: int = 1, **kwargs: Any) -> Any:
    async def go() -> Any:
        pool = WorkerPool(size, queue_size=kwargs.pop("queue_size", 2), **kwargs)
        await pool.start()
        try:
            return await body(pool)
        finally:
            await pool.close()

    kwargs.setdefault("job_timeout", 10.0)
    kwargs.setdefault("context", "forkserver")
    return asyncio.run(go())


# --------------------------------------------------------------------------- the pool


def test_progress_reaches_the_callback_before_the_answer() -> None:
    seen: list[tuple[int, int]] = []

    async def body(pool: WorkerPool) -> int:
        return int(await pool.run(report_steps, 4, 0.01, progress=lambda d, t: seen.append((d, t))))

    pid = with_pool(body)
    assert seen == [(1, 4), (2, 4), (3, 4), (4, 4)]
    assert pid != os.getpid()


def test_run_reporting_throttles_and_sends_the_last_call() -> None:
    seen: list[tuple[int, int]] = []

    async def body(pool: WorkerPool) -> Any:
        return await pool.run(
            run_reporting, count_to, 200_000, progress=lambda d, t: seen.append((d, t))
        )

    assert with_pool(body) == 200_000
    assert seen[-1] == (200_000, 200_000)
    assert 1 <= len(seen) < 100  # throttled: not one message a call


def test_cancel_kills_and_replaces_the_worker() -> None:
    async def body(pool: WorkerPool) -> tuple[int, int, int]:
        first = await pool.run(os.getpid)
        cancel = threading.Event()
        job = asyncio.create_task(pool.run(pid_after, 3600, cancel=cancel))
        await asyncio.sleep(0.3)
        t0 = time.monotonic()
        cancel.set()
        with pytest.raises(JobCancelledError):
            await job
        assert time.monotonic() - t0 < 5
        return first, await pool.run(os.getpid), pool.restarts

    first, second, restarts = with_pool(body, memory_limit=None)
    assert first != second and restarts == 1
    with pytest.raises(ProcessLookupError):  # the cancelled job's process is gone
        os.kill(first, 0)


def test_a_job_cancelled_before_it_starts_keeps_the_worker() -> None:
    async def body(pool: WorkerPool) -> tuple[int, int, int]:
        first = await pool.run(os.getpid)
        cancel = threading.Event()
        cancel.set()
        with pytest.raises(JobCancelledError, match="before it started"):
            await pool.run(os.getpid, cancel=cancel)
        return first, await pool.run(os.getpid), pool.restarts

    first, second, restarts = with_pool(body)
    assert first == second and restarts == 0


def test_a_job_has_its_own_time_limit() -> None:
    async def body(pool: WorkerPool) -> None:
        await pool.run(pid_after, 1.0, timeout=5.0)  # past the pool's 0.5 s
        with pytest.raises(JobTimeoutError, match=r"time limit of 0\.5 s"):
            await pool.run(pid_after, 1.0)

    with_pool(body, job_timeout=0.5)


def test_unqueued_jobs_wait_without_taking_the_queue() -> None:
    async def body(pool: WorkerPool) -> tuple[Any, Any]:
        busy = asyncio.create_task(pool.run(pid_after, 0.6))
        while pool.busy == 0:
            await asyncio.sleep(0.01)
        unqueued = asyncio.create_task(pool.run(pid_after, 0.0, queue=False))
        while pool.waiting_unqueued == 0:
            await asyncio.sleep(0.01)
        assert pool.waiting == 0
        with pytest.raises(QueueFullError):  # the queue holds none: a synchronous job is refused
            await pool.run(pid_after, 0.0)
        return await busy, await unqueued

    a, b = with_pool(body, queue_size=0)
    assert a == b  # the one worker ran both


def test_cancel_a_long_job_still_waiting_for_a_worker() -> None:
    async def body(pool: WorkerPool) -> None:
        store = LongJobs(pool, max_jobs=2, slots=1, timeout=60.0, ttl=60.0, max_bytes=100)
        busy = asyncio.create_task(pool.run(pid_after, 4.0))  # the only worker
        while pool.busy == 0:
            await asyncio.sleep(0.01)
        job = store.new()
        job.task = asyncio.create_task(store.run(job, count_to, 5))
        while pool.waiting_unqueued == 0:
            await asyncio.sleep(0.01)
        assert job.state == "running"  # it holds its slot, not a worker
        await store.cancel(job)
        assert job.task.cancelled() and pool.waiting_unqueued == 0
        pid = await busy
        assert await pool.run(os.getpid) == pid and pool.restarts == 0  # nobody killed

    with_pool(body)


def test_a_volume_reports_its_components_as_they_are_pruned() -> None:
    seen: list[tuple[int, int]] = []
    volume = touching_tubes(48, 3)
    res = skelprune.prune(volume, progress=lambda d, t: seen.append((d, t)))
    assert seen == [(k, 9) for k in range(10)] and len(res.components) == 9


# --------------------------------------------------------------------------- the store


def _store(**kwargs: Any) -> LongJobs:
    limits = {"max_jobs": 2, "slots": 1, "timeout": 60.0, "ttl": 60.0, "max_bytes": 100}
    limits.update(kwargs)
    return LongJobs(WorkerPool(1, queue_size=0, job_timeout=1.0), **limits)


def _answer(size: int) -> StoredAnswer:
    return StoredAnswer(200, b"x" * size, [(b"content-type", b"application/json")])


def test_at_most_max_jobs_queued_or_running() -> None:
    store = _store()
    a, b = store.new(), store.new()
    with pytest.raises(TooManyJobsError, match="2 long jobs are queued or running"):
        store.new()
    store.finish(a, "done", _answer(10))  # finished jobs do not count
    c = store.new()
    assert len({a.id, b.id, c.id}) == 3 and all(len(j.id) >= 22 for j in (a, b, c))


def test_results_are_kept_within_their_bytes_the_oldest_dropped() -> None:
    store = _store(max_jobs=5)
    first, second = store.new(), store.new()
    store.finish(first, "done", _answer(60))
    time.sleep(0.01)
    store.finish(second, "done", _answer(60))
    assert store.held_bytes == 60
    with pytest.raises(JobNotFoundError):
        store.get(first.id)
    assert store.get(second.id).answer == _answer(60)
    with pytest.raises(ResultTooLargeError, match="101 bytes"):
        store.finish(store.new(), "done", _answer(101))
    store.discard(second)
    assert store.held_bytes == 0


def test_finished_jobs_expire_after_their_ttl() -> None:
    store = _store(ttl=0.05)
    job = store.new()
    store.finish(job, "done", _answer(5))
    assert store.get(job.id).status()["state"] == "done"
    time.sleep(0.1)
    with pytest.raises(JobNotFoundError, match="expired"):
        store.get(job.id)
    assert store.held_bytes == 0


@pytest.mark.parametrize(
    ("values", "expected"),
    [
        (["respond-async"], True),
        (["Respond-Async, wait=10"], True),
        (["return=minimal", "respond-async; x=1"], True),
        (["return=representation"], False),
        ([], False),
        (["respond-asynchronously"], False),
    ],
)
def test_prefer_respond_async(values: list[str], expected: bool) -> None:
    headers = [(b"prefer", v.encode()) for v in values]
    request = Request({"type": "http", "method": "POST", "path": "/", "headers": headers})
    assert prefers_async(request) is expected


@pytest.mark.parametrize(
    ("workers", "long_job_workers", "slots"), [(4, None, 3), (1, None, 1), (4, 2, 2), (2, 9, 2)]
)
def test_long_job_slots_leave_a_worker_to_synchronous_requests(
    workers: int, long_job_workers: int | None, slots: int
) -> None:
    settings = Settings(workers=workers, long_job_workers=long_job_workers)
    assert settings.long_job_slots == slots


# --------------------------------------------------------------------------- the routes

SETTINGS = {"workers": 2, "queue_size": 4, "long_jobs": 2}


def _wait_for(client: TestClient, url: str, until: Callable[[dict[str, Any]], bool]) -> dict:
    deadline = time.monotonic() + 60
    while True:
        status = client.get(url).json()
        if until(status) or time.monotonic() > deadline:
            return status
        time.sleep(0.05)


def test_progress_and_cancel_through_the_app(client: TestClient) -> None:
    client.app.dependency_overrides[job_function] = lambda: slow_job  # type: ignore[attr-defined]
    try:
        resp = client.post("/v1/jobs", content=BIRD, headers={"content-type": "image/png"})
        assert resp.status_code == 202 and "preference-applied" not in resp.headers
        url = resp.headers["location"]
        status = _wait_for(client, url, lambda s: s["progress"]["done"] >= 2)
        assert status["state"] == "running" and status["progress"]["total"] == 10
        assert client.get(url + "/result").status_code == 409
        cancelled = client.delete(url)
        assert cancelled.status_code == 200 and cancelled.json()["state"] == "cancelled"
        result = client.get(url + "/result")
        assert result.status_code == 409 and result.json()["type"].endswith("job-cancelled")
        forgotten = client.delete(url)  # a finished job is forgotten
        assert forgotten.status_code == 200 and forgotten.json()["state"] == "cancelled"
        assert client.get(url).status_code == 404
    finally:
        client.app.dependency_overrides.clear()  # type: ignore[attr-defined]


def test_an_error_before_the_pool_is_the_requests_own(client: TestClient) -> None:
    resp = client.post(
        "/v1/prune",
        content=BIRD,
        params={"beta": "-1"},
        headers={"content-type": "image/png", "prefer": "respond-async"},
    )
    sync = client.post(
        "/v1/prune", content=BIRD, params={"beta": "-1"}, headers={"content-type": "image/png"}
    )
    assert resp.status_code == sync.status_code == 422 and "location" not in resp.headers
    assert client.app.state.long_jobs.active() == 0  # type: ignore[attr-defined]
