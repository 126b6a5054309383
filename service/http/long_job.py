"""Running ``POST /v1/prune`` as a long job (``POST /v1/jobs``, or ``Prefer:
respond-async``): :func:`submit`.

A long job runs the route's handler itself, in a background task, with the long job's
time limit in its settings and a :class:`~service.worker.long_jobs.LongJobRunner` in
place of the pool: everything up to the pool (options, negotiation, body checks,
estimates) answers at once, as the synchronous route does; once the job reaches the
pool the request is answered 202, and what the handler returns or raises (through the
application's error handlers) becomes the job's answer, status, headers and bytes.
"""

from __future__ import annotations

import asyncio
import json
from collections.abc import Awaitable, Callable
from dataclasses import replace
from typing import Any

from fastapi import Request, Response
from fastapi.responses import JSONResponse

from service.http.shape_request import ShapeRequest
from service.worker.jobs import Job
from service.worker.long_jobs import (
    FINISHED,
    LongJob,
    LongJobRunner,
    LongJobs,
    ResultTooLargeError,
    State,
    StoredAnswer,
)
from service.worker.pool import JobCancelledError

__all__ = ["jobs_of", "prefers_async", "status_answer", "submit", "wants_async"]

Handler = Callable[[ShapeRequest, Callable[[Job], Any]], Awaitable[Response]]


def prefers_async(request: Request) -> bool:
    """Whether the request's ``Prefer`` header holds ``respond-async`` (RFC 7240)."""
    for value in request.headers.getlist("prefer"):
        for pref in value.split(","):
            name = pref.split(";")[0].split("=")[0].strip().lower()
            if name == "respond-async":
                return True
    return False


def wants_async(call: ShapeRequest) -> bool:
    """A request to run as a long job, not one already running as one."""
    return prefers_async(call.request) and not isinstance(call.pool, LongJobRunner)


def jobs_of(request: Request) -> LongJobs:
    jobs: LongJobs = request.app.state.long_jobs
    return jobs


async def _error_answer(request: Request, exc: Exception) -> Response:
    """The answer the application's error handlers give ``exc`` on this request."""
    handlers = request.app.exception_handlers
    for cls in type(exc).__mro__:
        handler = handlers.get(cls)
        if handler is not None:
            response: Response = await handler(request, exc)
            return response
    raise exc  # pragma: no cover - the application handles Exception


def _stored(response: Response) -> StoredAnswer:
    return StoredAnswer(response.status_code, bytes(response.body), list(response.raw_headers))


async def _run(jobs: LongJobs, job: LongJob, handler: Handler, call: ShapeRequest, fn: Any) -> Any:
    """The job's task: the route's handler; once admitted, its answer is the job's."""
    request = call.request
    try:
        response = await handler(call, fn)
    except (asyncio.CancelledError, JobCancelledError):
        if not job.admitted.is_set():
            raise
        jobs.finish(job, "cancelled", None)
        return None
    except Exception as exc:
        if not job.admitted.is_set():
            raise
        response = await _error_answer(request, exc)
    if not job.admitted.is_set():  # answered without the pool: the request's own answer
        return response
    state: State = "done" if response.status_code < 400 else "failed"
    answer = _stored(response)
    try:
        jobs.finish(job, state, answer)
    except ResultTooLargeError as exc:
        answer = _stored(await _error_answer(request, exc))
        jobs.finish(job, "failed", answer)
        state = "failed"
    if state == "failed":
        job.problem = _problem_doc(answer)
    return None


def _problem_doc(answer: StoredAnswer) -> dict[str, Any] | None:
    try:
        doc = json.loads(answer.body)
    except ValueError:
        return None
    return doc if isinstance(doc, dict) else None


def status_answer(
    job: LongJob, status: int = 200, headers: dict[str, str] | None = None
) -> Response:
    extra = dict(headers or {})
    if job.state not in FINISHED:
        extra.setdefault("Retry-After", "1")  # when to poll again
    return JSONResponse(job.status(), status_code=status, headers=extra)


async def submit(call: ShapeRequest, fn: Callable[[Job], Any], handler: Handler) -> Response:
    """Run ``handler(call, fn)`` as a long job: its error if it fails before the pool,
    else 202 with the job's status, ``Location`` its URL.

    Raises
    ------
    TooManyJobsError
        When ``SKELPRUNE_LONG_JOBS`` jobs are queued or running (503).
    """
    jobs = jobs_of(call.request)
    job = jobs.new()
    settings = call.settings.model_copy(update={"job_timeout": jobs.timeout})
    long_call = replace(call, settings=settings, pool=LongJobRunner(jobs, job))
    task = asyncio.create_task(_run(jobs, job, handler, long_call, fn))
    job.task = task
    admitted = asyncio.create_task(job.admitted.wait())
    try:
        await asyncio.wait({task, admitted}, return_when=asyncio.FIRST_COMPLETED)
    except asyncio.CancelledError:  # the client left before its job was admitted
        if not job.admitted.is_set():
            task.cancel()
            jobs.discard(job)
        raise
    finally:
        admitted.cancel()
    if not job.admitted.is_set():
        jobs.discard(job)
        response: Response = task.result()  # raises the request's error, as it would
        return response
    headers = {"Location": f"/v1/jobs/{job.id}"}
    if prefers_async(call.request):
        headers["Preference-Applied"] = "respond-async"
        headers["Vary"] = "Accept, Prefer"
    return status_answer(job, 202, headers)
