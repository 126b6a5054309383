"""Long jobs over HTTP: ``POST /v1/jobs`` (or ``POST /v1/prune`` with
``Prefer: respond-async``, :mod:`service.http.long_job`) answers 202 with the job's URL;
``GET /v1/jobs/{id}`` its state and progress, ``GET /v1/jobs/{id}/result`` the answer
``POST /v1/prune`` would have given (status, headers and bytes), ``DELETE
/v1/jobs/{id}`` cancels or forgets it.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Annotated, Any

from fastapi import APIRouter, Depends, Request, Response

from service.apidocs import jobs_docs
from service.http.long_job import jobs_of, status_answer, submit
from service.http.routes import prune as prune_routes
from service.http.shape_request import ShapeRequest
from service.worker.jobs import Job
from service.worker.long_jobs import FINISHED, JobPendingError
from service.worker.pool import JobCancelledError

__all__ = ["router"]

router = APIRouter()

#: The ``{job_id}`` of the routes below, read from the path as it is (any text: an id
#: that is no job's is a 404), so that no request validation (422) applies.
JOB_ID = {
    "parameters": [
        {
            "name": "job_id",
            "in": "path",
            "required": True,
            "description": "The job's id, from its 202 answer.",
            "schema": {"type": "string"},
        }
    ]
}


def _job_id(request: Request) -> str:
    return str(request.path_params["job_id"])


@router.post(
    "/v1/jobs",
    status_code=202,
    summary="Prune a shape as a long job (POST /v1/prune, answered 202)",
    description=jobs_docs.SUBMIT_DESCRIPTION,
    response_class=Response,
    responses=jobs_docs.SUBMIT_RESPONSES,
    openapi_extra=jobs_docs.SUBMIT_EXTRA,
    tags=["jobs"],
)
async def submit_job(
    call: Annotated[ShapeRequest, Depends(prune_routes.PRUNE)],
    fn: Annotated[Callable[[Job], Any], Depends(prune_routes.job_function)],
) -> Response:
    return await submit(call, fn, prune_routes.prune)


@router.get(
    "/v1/jobs/{job_id}",
    summary="A long job's state and progress",
    description=jobs_docs.STATUS_DESCRIPTION,
    response_model=jobs_docs.JobStatus,
    responses=jobs_docs.STATUS_RESPONSES,
    openapi_extra=JOB_ID,
    tags=["jobs"],
)
async def job_status(request: Request) -> Response:
    job_id = _job_id(request)
    return status_answer(jobs_of(request).get(job_id))


@router.get(
    "/v1/jobs/{job_id}/result",
    summary="A long job's answer: what POST /v1/prune would have answered",
    description=jobs_docs.RESULT_DESCRIPTION,
    response_class=Response,
    responses=jobs_docs.RESULT_RESPONSES,
    openapi_extra=JOB_ID,
    tags=["jobs"],
)
async def job_result(request: Request) -> Response:
    job_id = _job_id(request)
    job = jobs_of(request).get(job_id)
    if job.state == "cancelled":
        raise JobCancelledError(f"long job {job_id} was cancelled: it has no result")
    if job.answer is None:
        raise JobPendingError(
            f"long job {job_id} is {job.state} ({job.done} of {job.total or '?'} done): "
            f"poll /v1/jobs/{job_id} until its state is done or failed"
        )
    response = Response(job.answer.body, status_code=job.answer.status)
    response.raw_headers = list(job.answer.headers)
    return response


@router.delete(
    "/v1/jobs/{job_id}",
    summary="Cancel a long job, or forget a finished one",
    description=jobs_docs.DELETE_DESCRIPTION,
    response_class=Response,
    responses=jobs_docs.DELETE_RESPONSES,
    openapi_extra=JOB_ID,
    tags=["jobs"],
)
async def delete_job(request: Request) -> Response:
    job_id = _job_id(request)
    jobs = jobs_of(request)
    job = jobs.get(job_id)
    if job.state in FINISHED:  # forgotten, with its result: its last status
        jobs.discard(job)
        return status_answer(job)
    await jobs.cancel(job)
    return status_answer(job)
