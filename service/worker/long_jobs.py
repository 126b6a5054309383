"""Long jobs: a request's job run in the background, past the synchronous time limit.

A long job is the job ``POST /v1/prune`` would run, admitted by its own limits and kept
in this process's memory only (a restart loses every job and every result):

- at most ``SKELPRUNE_LONG_JOBS`` jobs queued or running at once
  (:class:`TooManyJobsError`, 503);
- at most :attr:`~service.settings.Settings.long_job_slots` of them hold a worker at
  once (all workers but one by default: synchronous requests always find one); the
  others wait, queued, outside the pool's wait queue;
- each runs under ``SKELPRUNE_LONG_JOB_TIMEOUT`` in the same pool, with the same memory
  budget and estimates as a synchronous job;
- a finished job's answer is kept ``SKELPRUNE_LONG_JOB_TTL`` seconds, the answers
  together at most ``SKELPRUNE_LONG_JOB_RESULTS_BYTES`` (the oldest dropped first);
- its id is :func:`secrets.token_urlsafe` (128 bits): whoever holds the id (and the API
  key, if the service has one) may read or cancel it.

Progress comes from the library's ``progress(done, total)`` (components, windows),
sent by the worker (:func:`service.worker.process.report_progress`) to the pool.
"""

from __future__ import annotations

import asyncio
import contextlib
import inspect
import secrets
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import UTC, datetime
from typing import Any, Literal

from service.worker.pool import WorkerPool
from service.worker.process import report_progress

__all__ = [
    "JobNotFoundError",
    "JobPendingError",
    "LongJob",
    "LongJobRunner",
    "LongJobs",
    "ResultTooLargeError",
    "State",
    "StoredAnswer",
    "TooManyJobsError",
    "run_reporting",
]

State = Literal["queued", "running", "done", "failed", "cancelled"]
FINISHED: frozenset[State] = frozenset({"done", "failed", "cancelled"})

#: Least seconds between two progress messages of one job (the last one always goes).
PROGRESS_SECONDS = 0.2


class TooManyJobsError(Exception):
    """``SKELPRUNE_LONG_JOBS`` long jobs are already queued or running (a 503 that passes)."""


class JobNotFoundError(Exception):
    """No long job has this id: it never existed, expired or was deleted."""


class JobPendingError(Exception):
    """The long job has no answer yet (queued or running), or was cancelled."""


class ResultTooLargeError(Exception):
    """A long job's answer is larger than ``SKELPRUNE_LONG_JOB_RESULTS_BYTES``."""


def run_reporting(fn: Callable[..., Any], job: Any) -> Any:
    """Worker side of a long job: ``fn(job)`` with its progress sent to the parent, at
    most every :data:`PROGRESS_SECONDS` (and always the last call)."""
    if "progress" not in inspect.signature(fn).parameters:
        return fn(job)
    last = [0.0]

    def progress(done: int, total: int) -> None:
        now = time.monotonic()
        if done >= total or now - last[0] >= PROGRESS_SECONDS:
            last[0] = now
            report_progress(done, total)

    return fn(job, progress=progress)


@dataclass(frozen=True)
class StoredAnswer:
    """The HTTP answer a long job ended with: status, body and headers as they were."""

    status: int
    body: bytes
    headers: list[tuple[bytes, bytes]]


def _iso(wall: float | None) -> str | None:
    if wall is None:
        return None
    return datetime.fromtimestamp(wall, UTC).isoformat(timespec="milliseconds")


@dataclass(eq=False)
class LongJob:
    """One long job: its state, progress, answer and the means to stop it."""

    id: str
    state: State = "queued"
    done: int = 0
    total: int = 0
    created: float = field(default_factory=time.time)
    started: float | None = None
    finished: float | None = None
    expires: float | None = None  # wall clock
    answer: StoredAnswer | None = None
    problem: dict[str, Any] | None = None
    cancel: threading.Event = field(default_factory=threading.Event)
    task: asyncio.Task[Any] | None = None
    #: Set once the job reaches the worker pool: the request is answered 202 then.
    admitted: asyncio.Event = field(default_factory=asyncio.Event)

    def progress(self, done: int, total: int) -> None:
        """The library's ``progress(done, total)``, from the pool's job thread."""
        self.done, self.total = done, total

    def status(self) -> dict[str, Any]:
        """The job's status document (``GET /v1/jobs/{id}``)."""
        doc: dict[str, Any] = {
            "id": self.id,
            "state": self.state,
            "progress": {"done": self.done, "total": self.total},
            "created": _iso(self.created),
            "started": _iso(self.started),
            "finished": _iso(self.finished),
            "expires": _iso(self.expires),
            "url": f"/v1/jobs/{self.id}",
            "result": f"/v1/jobs/{self.id}/result" if self.answer is not None else None,
        }
        if self.problem is not None:
            doc["problem"] = self.problem
        return doc


class LongJobs:
    """The long jobs of one server, in memory.

    Parameters
    ----------
    pool : WorkerPool
        The pool the synchronous jobs run in.
    max_jobs : int
        Jobs queued or running at once.
    slots : int
        Workers long jobs may hold at once.
    timeout : float
        Seconds one long job may run.
    ttl : float
        Seconds a finished job is kept.
    max_bytes : int
        Bytes of answers kept, all jobs together.
    """

    def __init__(
        self,
        pool: WorkerPool,
        *,
        max_jobs: int,
        slots: int,
        timeout: float,
        ttl: float,
        max_bytes: int,
    ) -> None:
        self.pool = pool
        self.max_jobs = max_jobs
        self.slots = slots
        self.timeout = timeout
        self.ttl = ttl
        self.max_bytes = max_bytes
        self._jobs: dict[str, LongJob] = {}
        self._semaphore: asyncio.Semaphore | None = None
        self.held_bytes = 0

    # -- the table -----------------------------------------------------------------
    def active(self) -> int:
        """Jobs queued or running."""
        return sum(job.state not in FINISHED for job in self._jobs.values())

    def sweep(self) -> None:
        """Drop the finished jobs past their time to live."""
        now = time.time()
        for job in [j for j in self._jobs.values() if j.expires is not None and j.expires <= now]:
            self.discard(job)

    def new(self) -> LongJob:
        """A new queued job, under its unguessable id.

        Raises
        ------
        TooManyJobsError
            When ``max_jobs`` jobs are queued or running.
        """
        self.sweep()
        active = self.active()
        if active >= self.max_jobs:
            raise TooManyJobsError(
                f"{active} long jobs are queued or running, the limit is {self.max_jobs} "
                "(SKELPRUNE_LONG_JOBS); try again when one has finished"
            )
        job = LongJob(secrets.token_urlsafe(16))
        self._jobs[job.id] = job
        return job

    def get(self, job_id: str) -> LongJob:
        """The job of this id.

        Raises
        ------
        JobNotFoundError
            When there is none (never made, expired, deleted).
        """
        self.sweep()
        job = self._jobs.get(job_id)
        if job is None:
            raise JobNotFoundError(
                f"no long job {job_id!r}: it never existed, or it expired or was deleted "
                f"(finished jobs are kept {self.ttl:g} s, and a restart loses them all)"
            )
        return job

    def discard(self, job: LongJob) -> None:
        """Forget the job and its answer."""
        if self._jobs.pop(job.id, None) is not None and job.answer is not None:
            self.held_bytes -= len(job.answer.body)

    # -- running -------------------------------------------------------------------
    async def run(self, job: LongJob, fn: Callable[..., Any], *args: Any) -> Any:
        """``fn(*args)`` as this long job: admitted, then run in the pool when a slot
        is free, with its progress recorded and its ``cancel`` event watched."""
        if self._semaphore is None:
            self._semaphore = asyncio.Semaphore(self.slots)
        job.admitted.set()
        async with self._semaphore:
            job.state, job.started = "running", time.time()
            (job_arg,) = args
            return await self.pool.run(
                run_reporting,
                fn,
                job_arg,
                timeout=self.timeout,
                progress=job.progress,
                cancel=job.cancel,
                queue=False,
            )

    def finish(self, job: LongJob, state: State, answer: StoredAnswer | None) -> None:
        """Record how the job ended; its answer is kept within ``max_bytes``, the oldest
        kept answers dropped to make room (an answer larger than ``max_bytes`` cannot be
        kept: :class:`ResultTooLargeError`, which the caller records instead)."""
        if answer is not None and len(answer.body) > self.max_bytes:
            raise ResultTooLargeError(
                f"the job's answer has {len(answer.body)} bytes, more than the "
                f"{self.max_bytes} bytes of long jobs' results the server keeps "
                "(SKELPRUNE_LONG_JOB_RESULTS_BYTES); ask for a smaller answer"
            )
        if answer is not None:
            for old in sorted(
                (j for j in self._jobs.values() if j.answer is not None),
                key=lambda j: j.finished or 0.0,
            ):
                if self.held_bytes + len(answer.body) <= self.max_bytes:
                    break
                self.discard(old)
            self.held_bytes += len(answer.body)
        job.state, job.answer = state, answer
        job.finished = time.time()
        job.expires = job.finished + self.ttl
        if job.id not in self._jobs:  # deleted while it ran: keep nothing
            if answer is not None:
                self.held_bytes -= len(answer.body)
            return
        with contextlib.suppress(RuntimeError):  # no loop: swept on the next request
            asyncio.get_running_loop().call_later(self.ttl, self.sweep)

    async def cancel(self, job: LongJob, wait: float = 10.0) -> None:
        """Stop the job: a running one's worker is killed (its memory returned) and
        replaced; one still waiting for a slot or a worker never starts. Waits up to
        ``wait`` s for it to end."""
        job.cancel.set()
        task = job.task
        if task is None or task.done():
            return
        if job.state == "queued":
            task.cancel()
        # a job in a worker ends within a watchdog sample of the event; one that has a
        # slot but still waits for a free worker is stopped waiting
        done, _ = await asyncio.wait({task}, timeout=min(2.0, wait))
        if not done:
            task.cancel()
            await asyncio.wait({task}, timeout=wait)

    async def close(self) -> None:
        """Cancel every job (at shutdown: a restart keeps none)."""
        for job in list(self._jobs.values()):
            job.cancel.set()
            if job.task is not None and not job.task.done():
                job.task.cancel()
        tasks = [j.task for j in self._jobs.values() if j.task is not None]
        await asyncio.gather(*tasks, return_exceptions=True)
        self._jobs.clear()
        self.held_bytes = 0


@dataclass(frozen=True)
class LongJobRunner:
    """Runs a request's job as a long job: what a :class:`ShapeRequest` runs its jobs
    with in place of the pool (a :class:`~service.worker.pool.JobRunner`)."""

    jobs: LongJobs
    job: LongJob

    async def run(self, fn: Callable[..., Any], *args: Any) -> Any:
        return await self.jobs.run(self.job, fn, *args)
