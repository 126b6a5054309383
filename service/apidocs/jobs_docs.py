"""The OpenAPI documentation of the long-job endpoints (``/v1/jobs``): descriptions,
the status document's model and the responses, with examples."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, Field

from service.apidocs.examples import PRUNE_RESPONSES, UNAUTHORIZED, problem_example
from service.apidocs.openapi import PRUNE_EXTRA

__all__ = [
    "DELETE_DESCRIPTION",
    "DELETE_RESPONSES",
    "RESULT_DESCRIPTION",
    "RESULT_RESPONSES",
    "STATUS_DESCRIPTION",
    "STATUS_RESPONSES",
    "SUBMIT_DESCRIPTION",
    "SUBMIT_EXTRA",
    "SUBMIT_RESPONSES",
    "JobStatus",
]

Responses = dict[int | str, dict[str, Any]]


class JobProgress(BaseModel):
    """How far a long job is."""

    done: int = Field(description="Components (windows, for scope=local) pruned so far.")
    total: int = Field(description="Components (windows) in all; 0 until known.")


class JobStatus(BaseModel):
    """A long job's status document."""

    id: str = Field(description="The job's id (unguessable: whoever holds it may read it).")
    state: Literal["queued", "running", "done", "failed", "cancelled"]
    progress: JobProgress
    created: str = Field(description="When it was submitted (ISO 8601, UTC).")
    started: str | None = Field(description="When it took a long-job slot.")
    finished: str | None = Field(description="When it ended.")
    expires: str | None = Field(
        description="When its status and result will be dropped (SKELPRUNE_LONG_JOB_TTL)."
    )
    url: str = Field(description="This document's path.")
    result: str | None = Field(description="The result's path, once done or failed.")
    problem: dict[str, Any] | None = Field(
        None, description="A failed job's problem document (also its result)."
    )


STATUS_EXAMPLE = {
    "id": "Vh3qjW0v3vG0p0m2cQ1mHw",
    "state": "running",
    "progress": {"done": 137, "total": 300},
    "created": "2026-12-06T21:40:00.120+00:00",
    "started": "2026-12-06T21:40:00.180+00:00",
    "finished": None,
    "expires": None,
    "url": "/v1/jobs/Vh3qjW0v3vG0p0m2cQ1mHw",
    "result": None,
}

LIFETIME = """
Jobs live in the server's memory only: a restart (or a shutdown) cancels the queued and
running jobs and loses every result. A finished job is kept `SKELPRUNE_LONG_JOB_TTL`
seconds (default one hour), and the results together at most
`SKELPRUNE_LONG_JOB_RESULTS_BYTES` (the oldest dropped first); then its URLs answer 404.
"""

SUBMIT_DESCRIPTION = (
    """
Run what `POST /v1/prune` runs (the same body, query options and `Accept`) as a long
job, under `SKELPRUNE_LONG_JOB_TIMEOUT` (default 30 min) instead of the synchronous
`SKELPRUNE_JOB_TIMEOUT`. `POST /v1/prune` with `Prefer: respond-async` does the same.

Everything checked before any work (options, `Accept`, the body, the memory and time
estimates) answers at once, as `POST /v1/prune` would; else **202 Accepted** with the
job's status (`JobStatus`) and `Location: /v1/jobs/{id}`. Poll `GET /v1/jobs/{id}`
(its `progress`: components pruned of all), then read `GET /v1/jobs/{id}/result`.

At most `SKELPRUNE_LONG_JOBS` jobs are queued or running (503 `too-many-jobs` beyond,
with `Retry-After`), and they hold at most `SKELPRUNE_LONG_JOB_WORKERS` workers (default:
all but one), so that synchronous requests always find a worker; each has the memory
budget of a synchronous job.
"""
    + LIFETIME
)

_ACCEPTED = {
    "description": "The job is queued: its status; `Location` is its URL.",
    "headers": {
        "Location": {"description": "`/v1/jobs/{id}`.", "schema": {"type": "string"}},
        "Preference-Applied": {
            "description": "`respond-async`, when the request asked for it (`Prefer`).",
            "schema": {"type": "string"},
        },
    },
    "content": {
        "application/json": {
            "schema": {"$ref": "#/components/schemas/JobStatus"},
            "example": {**STATUS_EXAMPLE, "state": "queued", "progress": {"done": 0, "total": 0}},
        }
    },
}

SUBMIT_RESPONSES: Responses = {
    202: _ACCEPTED,
    **{k: v for k, v in PRUNE_RESPONSES.items() if k not in (200, 500, 504)},
    503: problem_example(
        503,
        "too-many-jobs",
        "Too many long jobs",
        "8 long jobs are queued or running, the limit is 8 (SKELPRUNE_LONG_JOBS); try "
        "again when one has finished",
    ),
}
SUBMIT_EXTRA = PRUNE_EXTRA

_NOT_FOUND = problem_example(
    404,
    "job-not-found",
    "Unknown job",
    "no long job 'abc': it never existed, or it expired or was deleted (finished jobs "
    "are kept 3600 s, and a restart loses them all)",
)

STATUS_DESCRIPTION = (
    """
The job's state (`queued`, `running`, `done`, `failed`, `cancelled`) and progress
(`done` of `total` components, or windows with `scope=local`; a volume's `total` is
known once its components are found). While it is queued or running the answer has
`Retry-After: 1`. A failed job's `problem` is the problem document `POST /v1/prune`
would have answered.
"""
    + LIFETIME
)

STATUS_RESPONSES: Responses = {
    200: {"content": {"application/json": {"example": STATUS_EXAMPLE}}},
    401: UNAUTHORIZED,
    404: _NOT_FOUND,
}

RESULT_DESCRIPTION = """
The answer `POST /v1/prune` would have given the submitted request: the same status,
headers and bytes, in the format its `Accept` chose (a done job: 200 and the document,
image or table; a failed one: its problem document, e.g. 413 `job-too-large` or 504
`job-timeout` at `SKELPRUNE_LONG_JOB_TIMEOUT`). A job still queued or running answers
409 `job-pending`, a cancelled one 409 `job-cancelled`.
"""

_PENDING = problem_example(
    409,
    "job-pending",
    "Job not finished",
    "long job Vh3qjW0v3vG0p0m2cQ1mHw is running (137 of 300 done): poll "
    "/v1/jobs/Vh3qjW0v3vG0p0m2cQ1mHw until its state is done or failed",
)

RESULT_RESPONSES: Responses = {
    **{k: v for k, v in PRUNE_RESPONSES.items() if k not in (406, 415, 503)},
    404: _NOT_FOUND,
    409: {
        **_PENDING,
        "description": "The job is still queued or running (`job-pending`), or was "
        "cancelled (`job-cancelled`).",
    },
}

DELETE_DESCRIPTION = """
Cancel a queued or running job: a running job's worker process is stopped (its memory
returned) and replaced; the answer is its status, `state: cancelled`, kept until
`SKELPRUNE_LONG_JOB_TTL`. A finished job (done, failed or cancelled) is forgotten, with
its result (its URLs answer 404 from then on); the answer is its last status.
"""

DELETE_RESPONSES: Responses = {
    200: {
        "description": "The job was cancelled, or forgotten if it had finished: its status.",
        "content": {
            "application/json": {
                "schema": {"$ref": "#/components/schemas/JobStatus"},
                "example": {**STATUS_EXAMPLE, "state": "cancelled"},
            }
        },
    },
    401: UNAUTHORIZED,
    404: _NOT_FOUND,
}
