"""The start every endpoint that prunes shares, as one FastAPI dependency (in the manner
of titiler's option dependencies): the query's options parsed first (a bad option is
refused before anything else), the ``Accept`` header negotiated, a compressed body
refused, the body read (size- and time-limited by
:class:`~service.http.middleware.BodyLimitMiddleware`) and its ``Content-Type`` sorted
into the kinds the endpoint takes, with the application's settings and worker pool.

An endpoint declares what it takes once, as a :class:`ShapeRequests`, and receives a
:class:`ShapeRequest`; it runs its jobs through :meth:`ShapeRequest.run`, which records
each job's time in the metrics.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

from fastapi import Request

from service.errors import MainMemoryError, UnsupportedMediaTypeError
from service.http.bodies import JSON_TYPES, Form, content_type, read_form, refuse_encoding
from service.http.query import parse_query
from service.http.schemas import PruneQuery
from service.settings import Settings
from service.worker.jobs import Media
from service.worker.pool import JobRunner
from skelprune.budget import mib, resident_bytes

if TYPE_CHECKING:
    from service.metrics import Metrics

__all__ = ["BodyKind", "ShapeRequest", "ShapeRequests", "check_main_memory"]


def check_main_memory(limit_mb: int) -> None:
    """Refuse a new body while the main process holds more than ``limit_mb`` MiB: the
    main process's memory watched as the workers' is (it cannot be replaced, so what
    it stops is more work).

    Raises
    ------
    MainMemoryError
        Naming what it holds and its budget.
    """
    held = resident_bytes()
    if held > limit_mb * 2**20:
        raise MainMemoryError(
            f"the server's main process holds {mib(held)}, over its budget of "
            f"{mib(limit_mb * 2**20)}; try again shortly"
        )


#: What a body holds, by its ``Content-Type``: an image as the body itself (PNG or
#: TIFF; a volume as a ``.npy`` or a TIFF stack), a multipart form, or JSON (GeoJSON).
BodyKind = Literal["image", "form", "json"]
KINDS: dict[str, BodyKind] = {
    "image/png": "image",
    "image/tiff": "image",
    "image/gif": "image",
    "application/x-npy": "image",  # a volume as a .npy file
    "multipart/form-data": "form",
    **dict.fromkeys(JSON_TYPES, "json"),
}


@dataclass(frozen=True)
class ShapeRequest:
    """A request to an endpoint that prunes, its shared part read and checked."""

    request: Request
    query: PruneQuery
    settings: Settings
    pool: JobRunner  # the worker pool; a long job's runner for a long job
    metrics: Metrics
    media: Media | None  # the answer the Accept header asks for (None: the endpoint has one)
    kind: BodyKind
    body: bytes
    content_type: str = ""  # the body's declared media type, without parameters

    async def form(self, max_files: int) -> Form:
        """The body as a multipart form (:func:`~service.http.bodies.read_form`)."""
        return await read_form(self.request, max_files=max_files)

    async def run(self, fn: Callable[[Any], Any], job: Any) -> Any:
        """``fn(job)`` on a worker; its time in the library goes to the metrics."""
        result = await self.pool.run(fn, job)
        self.metrics.prune_seconds.observe(result.prune_seconds)
        return result


@dataclass(frozen=True)
class ShapeRequests:
    """The dependency of an endpoint that prunes: ``Depends(ShapeRequests(...))``.

    ``accept`` reads the ``Accept`` header (raising ``NotAcceptableError``) into the
    answer's media, ``kinds`` are the bodies taken, and ``send`` completes the refusal of
    any other: "Content-Type … is not supported; send {send}".
    """

    accept: Callable[[str | None], Media | None]
    kinds: tuple[BodyKind, ...]
    send: str

    async def __call__(self, request: Request) -> ShapeRequest:
        query = parse_query(request.query_params)  # first: bad options are refused before all
        state = request.app.state
        media = self.accept(request.headers.get("accept"))
        ctype = content_type(request)
        refuse_encoding(request)
        check_main_memory(state.settings.main_memory_mb)
        body = await request.body()  # size-limited by BodyLimitMiddleware
        kind = KINDS.get(ctype)
        if kind is None or kind not in self.kinds:
            raise UnsupportedMediaTypeError(
                f"Content-Type {ctype or 'none'!r} is not supported; send {self.send}"
            )
        return ShapeRequest(
            request, query, state.settings, state.pool, state.metrics, media, kind, body, ctype
        )
