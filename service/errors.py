"""RFC 9457 problem details for every error the service returns.

One table, :data:`PROBLEMS`, maps each exception type to its HTTP status and problem
type; the handlers below cover domain errors, pool errors, FastAPI's own 4xx
(404, 405, 400, 422) and, as a last resort, any other exception (500, with no
internals in the answer; the traceback goes to the server log only).
"""

from __future__ import annotations

import http
import logging
import uuid
from dataclasses import dataclass
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse, Response
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.requests import ClientDisconnect

from service.logs import request_id_var
from service.worker.long_jobs import (
    JobNotFoundError,
    JobPendingError,
    ResultTooLargeError,
    TooManyJobsError,
)
from service.worker.pool import (
    JobCancelledError,
    JobFailedError,
    JobOverMemoryError,
    JobTimeoutError,
    PoolClosedError,
    PoolStartingError,
    QueueFullError,
    WorkerCrashedError,
)
from skelprune.errors import (
    EmptyMaskError,
    ImageTooLargeError,
    InvalidImageError,
    InvalidOptionError,
    InvalidPolygonError,
    JobTooLargeError,
    SkelpruneError,
    plain_text,
)
from skelprune.matching import UnmatchableShapeError

__all__ = [
    "PROBLEMS",
    "PROBLEM_MEDIA_TYPE",
    "BadRequestError",
    "BodyTooLargeError",
    "HeaderTooLargeError",
    "InternalError",
    "MainMemoryError",
    "NotAcceptableError",
    "RequestTimeoutError",
    "UnauthorizedError",
    "UnsupportedMediaTypeError",
    "install_error_handlers",
    "problem",
    "problem_response",
]

log = logging.getLogger("service.errors")

PROBLEM_MEDIA_TYPE = "application/problem+json"
TYPE_PREFIX = "urn:skelprune:problem:"
#: Status logged and counted for a request whose client went away mid-body.
CLIENT_CLOSED_REQUEST = 499


class BodyTooLargeError(Exception):
    """The request body is larger than ``SKELPRUNE_MAX_BODY_BYTES``."""


class UnsupportedMediaTypeError(Exception):
    """The request's Content-Type is not one the endpoint reads."""


class NotAcceptableError(Exception):
    """None of the media types in Accept can be produced."""


class UnauthorizedError(Exception):
    """The service has an API key and the request did not carry it."""


class BadRequestError(Exception):
    """The request is not valid HTTP (answered below the application)."""


class HeaderTooLargeError(Exception):
    """The request line and headers are over ``SKELPRUNE_MAX_HEADER_BYTES`` or have more
    than ``SKELPRUNE_MAX_HEADERS`` fields."""


class RequestTimeoutError(Exception):
    """The client took longer than ``SKELPRUNE_HEADER_TIMEOUT`` to send its headers or
    ``SKELPRUNE_BODY_TIMEOUT`` to send its body."""


class MainMemoryError(Exception):
    """The main process holds more than ``SKELPRUNE_MAIN_MEMORY_MB``: no new body is read
    until it holds less (a 503 that passes)."""


class InternalError(Exception):
    """A bug: an exception nothing else maps (the message gives a log reference)."""


@dataclass(frozen=True)
class ProblemKind:
    status: int
    slug: str
    title: str


#: The one table: exception type -> (status, problem type, title). Looked up along
#: the MRO, so subclasses inherit their parent's row. The library's errors name their
#: own problem type (``kind``), which is also what ``prune_many`` records.
PROBLEMS: dict[type[BaseException], ProblemKind] = {
    InvalidImageError: ProblemKind(400, InvalidImageError.kind, "Invalid image"),
    ImageTooLargeError: ProblemKind(413, ImageTooLargeError.kind, "Image too large"),
    JobTooLargeError: ProblemKind(413, JobTooLargeError.kind, "Job too large"),
    JobOverMemoryError: ProblemKind(413, JobTooLargeError.kind, "Job too large"),
    EmptyMaskError: ProblemKind(422, EmptyMaskError.kind, "Empty mask"),
    InvalidPolygonError: ProblemKind(422, InvalidPolygonError.kind, "Invalid polygon"),
    InvalidOptionError: ProblemKind(422, InvalidOptionError.kind, "Invalid option"),
    UnmatchableShapeError: ProblemKind(422, UnmatchableShapeError.kind, "Shape cannot be matched"),
    SkelpruneError: ProblemKind(422, SkelpruneError.kind, "Invalid input"),
    BodyTooLargeError: ProblemKind(413, "body-too-large", "Request body too large"),
    BadRequestError: ProblemKind(400, "bad-request", "Bad request"),
    HeaderTooLargeError: ProblemKind(431, "header-too-large", "Request header fields too large"),
    RequestTimeoutError: ProblemKind(408, "request-timeout", "Request timeout"),
    UnsupportedMediaTypeError: ProblemKind(415, "unsupported-media-type", "Unsupported media type"),
    NotAcceptableError: ProblemKind(406, "not-acceptable", "Not acceptable"),
    UnauthorizedError: ProblemKind(401, "unauthorized", "Unauthorized"),
    QueueFullError: ProblemKind(503, "queue-full", "Service busy"),
    TooManyJobsError: ProblemKind(503, "too-many-jobs", "Too many long jobs"),
    JobNotFoundError: ProblemKind(404, "job-not-found", "Unknown job"),
    JobPendingError: ProblemKind(409, "job-pending", "Job not finished"),
    JobCancelledError: ProblemKind(409, "job-cancelled", "Job cancelled"),
    ResultTooLargeError: ProblemKind(413, "result-too-large", "Result too large to keep"),
    MainMemoryError: ProblemKind(503, "main-memory", "Service busy"),
    PoolStartingError: ProblemKind(503, "starting", "Service starting"),
    PoolClosedError: ProblemKind(503, "unavailable", "Service unavailable"),
    JobTimeoutError: ProblemKind(504, "job-timeout", "Job timed out"),
    WorkerCrashedError: ProblemKind(500, "worker-crashed", "Worker crashed"),
    JobFailedError: ProblemKind(500, "internal-error", "Internal error"),
    InternalError: ProblemKind(500, "internal-error", "Internal error"),
    RequestValidationError: ProblemKind(422, "validation-error", "Request validation failed"),
}


def lookup(exc: BaseException) -> ProblemKind | None:
    """The table row for ``exc``'s type or its nearest ancestor."""
    for cls in type(exc).__mro__:
        if cls in PROBLEMS:
            return PROBLEMS[cls]
    return None


def problem_response(
    status: int,
    detail: str,
    *,
    slug: str | None = None,
    title: str | None = None,
    instance: str | None = None,
    headers: dict[str, str] | None = None,
    extra: dict[str, Any] | None = None,
) -> JSONResponse:
    """Build an ``application/problem+json`` response."""
    phrase = http.HTTPStatus(status).phrase
    body: dict[str, Any] = {
        "type": TYPE_PREFIX + slug if slug else "about:blank",
        "title": title or phrase,
        "status": status,
        "detail": plain_text(detail),
    }
    if instance:
        body["instance"] = instance
    rid = request_id_var.get()
    if rid is not None:
        body["request_id"] = rid
    if extra:
        body.update(extra)
    return JSONResponse(body, status_code=status, headers=headers, media_type=PROBLEM_MEDIA_TYPE)


def problem(
    exc: BaseException,
    *,
    instance: str | None = None,
    headers: dict[str, str] | None = None,
    extra: dict[str, Any] | None = None,
) -> JSONResponse:
    """The problem+json answer for ``exc``, from its row of :data:`PROBLEMS`.

    Every error answer of the service is built here, so that the status, the problem
    type and the title of an error are written once, in the table.
    """
    row = lookup(exc)
    if row is None:
        raise TypeError(f"{type(exc).__name__} has no row in PROBLEMS")
    return problem_response(
        row.status,
        str(exc) or row.title,
        slug=row.slug,
        title=row.title,
        instance=instance,
        headers=headers,
        extra=extra,
    )


#: Most validation errors an answer lists (``error_count`` says how many there were).
MAX_ERRORS = 20


def _loc(loc: tuple[Any, ...] | list[Any]) -> str:
    return ".".join(str(p) for p in loc)[:200]


def install_error_handlers(app: FastAPI, *, retry_after: int) -> None:
    """Register the problem+json handlers on ``app``."""

    async def domain_error(request: Request, exc: Exception) -> JSONResponse:
        row = lookup(exc)
        assert row is not None
        headers = {"Retry-After": str(retry_after)} if row.status == 503 else None
        if row.status == 408:  # the rest of the body may still come: not on this connection
            headers = {"Connection": "close"}
        if row.status >= 500:
            log.warning(
                "%s %s -> %d: %s",
                request.method,
                request.url.path,
                row.status,
                exc,
                extra={"request_id": request_id_var.get()},
            )
        return problem(exc, instance=request.url.path, headers=headers)

    async def http_error(request: Request, exc: Exception) -> JSONResponse:
        assert isinstance(exc, StarletteHTTPException)
        status = exc.status_code
        detail = exc.detail if isinstance(exc.detail, str) else http.HTTPStatus(status).phrase
        if status == 404 and detail == "Not Found":
            detail = f"no resource at {request.url.path}"
        elif status == 405:
            allow = (exc.headers or {}).get("Allow") or (exc.headers or {}).get("allow")
            detail = f"method {request.method} is not allowed on {request.url.path}" + (
                f"; allowed: {allow}" if allow else ""
            )
        return problem_response(
            status, detail, instance=request.url.path, headers=dict(exc.headers or {}) or None
        )

    async def validation_error(request: Request, exc: Exception) -> JSONResponse:
        assert isinstance(exc, RequestValidationError)
        found = exc.errors()
        errors = [
            # pydantic prefixes a validator's message with "Value error, ": not the user's
            {
                "loc": [str(p) for p in e.get("loc", ())],
                "msg": plain_text(str(e.get("msg", "")).removeprefix("Value error, ")),
                "type": str(e.get("type", "")),
            }
            for e in found[:MAX_ERRORS]
        ]
        shown = "; ".join(f"{_loc(e['loc'])}: {e['msg']}" for e in errors[:5])
        more = f" (and {len(found) - 5} more)" if len(found) > 5 else ""
        row = PROBLEMS[RequestValidationError]
        return problem_response(
            row.status,
            shown + more or row.title,
            slug=row.slug,
            title=row.title,
            instance=request.url.path,
            extra={"errors": errors, "error_count": len(found)},
        )

    async def unexpected(request: Request, exc: Exception) -> JSONResponse:
        # Normally RequestContextMiddleware catches these first; this is the fallback.
        ref = uuid.uuid4().hex[:12]
        log.error(
            "unhandled error %s on %s %s: %s",
            ref,
            request.method,
            request.url.path,
            type(exc).__name__,
            exc_info=log.isEnabledFor(logging.DEBUG),
            extra={"request_id": request_id_var.get(), "reference": ref},
        )
        return problem(
            InternalError(f"internal error (reference {ref}); the server log has the details"),
            instance=request.url.path,
        )

    async def client_gone(request: Request, exc: Exception) -> Response:
        # The client closed the connection before its request was read: nobody to answer,
        # and not the server's fault. 499 (nginx's "client closed request") keeps it out
        # of the 5xx counts of the access log and /metrics.
        log.info(
            "%s %s: the client closed the connection before sending its body",
            request.method,
            request.url.path,
            extra={"request_id": request_id_var.get()},
        )
        return Response(status_code=CLIENT_CLOSED_REQUEST)

    app.add_exception_handler(ClientDisconnect, client_gone)
    for cls in PROBLEMS:
        if cls is not RequestValidationError:
            app.add_exception_handler(cls, domain_error)
    app.add_exception_handler(StarletteHTTPException, http_error)
    app.add_exception_handler(RequestValidationError, validation_error)
    app.add_exception_handler(Exception, unexpected)
