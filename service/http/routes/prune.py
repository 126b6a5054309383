"""``POST /v1/prune`` and ``POST /v1/prune/batch``."""

from __future__ import annotations

import asyncio
import json
import logging
from collections.abc import AsyncIterator, Callable
from typing import Annotated, Any

from fastapi import APIRouter, Depends, Response
from fastapi.responses import StreamingResponse

from service.apidocs import openapi
from service.apidocs.examples import PRUNE_RESPONSES
from service.errors import InternalError, lookup, problem
from service.http import long_job
from service.http.bodies import (
    BATCH_MAX_ITEMS,
    batch_size,
    check_polygon_body,
    check_upload,
    check_values,
    parse_batch,
    parse_polygon,
    polygon_item,
    validate_json,
)
from service.http.builder import JobBuilder, job_builder
from service.http.negotiation import NDJSON, accept_ndjson, negotiate
from service.http.scan import BatchItem
from service.http.shape_request import ShapeRequest, ShapeRequests
from service.settings import Settings
from service.worker.jobs import Job, run_job
from service.worker.pool import PoolError
from skelprune.budget import check_polygon
from skelprune.errors import InvalidPolygonError, SkelpruneError
from skelprune.io.input import check_image_size

__all__ = ["job_function", "router"]

router = APIRouter()
log = logging.getLogger("service.routes")


async def job_function() -> Callable[[Job], Any]:
    """The worker-side function (a dependency, so that tests can swap in a faulty one).

    ``async`` although it does nothing to wait for: FastAPI runs a plain ``def``
    dependency in its thread pool, a thread round trip on every request.
    """
    return run_job


#: ``POST /v1/prune`` takes a PNG or TIFF (as the body or a form's file), GeoJSON, or a
#: volume (a ``.npy`` or a multi-page TIFF as the body).
PRUNE = ShapeRequests(
    negotiate,
    ("image", "form", "json"),
    "image/png, image/tiff, application/x-npy, multipart/form-data (field 'file') or "
    "application/json (GeoJSON)",
)
#: ``POST /v1/prune/batch`` takes a form of files or a JSON list; it answers NDJSON.
BATCH = ShapeRequests(
    lambda accept: accept_ndjson(accept or ""),
    ("form", "json"),
    "multipart/form-data (fields 'file') or application/json (a list of GeoJSON objects)",
)


@router.post(
    "/v1/prune",
    summary="Prune the skeleton of a PNG mask or a GeoJSON polygon",
    description=openapi.PRUNE_DESCRIPTION,
    response_class=Response,
    responses=PRUNE_RESPONSES,
    openapi_extra=openapi.PRUNE_EXTRA,
    tags=["prune"],
)
async def prune(
    call: Annotated[ShapeRequest, Depends(PRUNE)],
    fn: Annotated[Callable[[Job], Any], Depends(job_function)],
) -> Response:
    if long_job.wants_async(call):  # Prefer: respond-async: 202 and a long job
        return await long_job.submit(call, fn, prune)
    settings = call.settings
    png, geojson, envelope = None, None, None
    if call.kind == "image":
        png = call.body
    elif call.kind == "form":
        form = await call.form(max_files=1)
        (png,) = form.uploads(("file",), "the PNG")
        envelope = form.options(files="file")
    else:
        envelope, geojson = await validate_json(
            parse_polygon,
            call.body,
            check_polygon_body(settings.max_vertices, settings.estimate_seconds),
        )
    if png is not None:  # refused before it is queued, off the event loop
        declared = call.content_type if call.kind == "image" else None
        await check_upload(png, settings.max_pixels, declared)
    assert call.media is not None  # negotiate always names one
    build = job_builder(
        call.query, envelope, settings, polygon=geojson is not None, media=call.media
    )
    result = await call.run(fn, build.job(png=png, geojson=geojson))
    # The same URL answers in three formats: caches must key on Accept.
    return Response(
        result.body, media_type=result.media_type, headers={"Vary": "Accept", **result.headers}
    )


def _item_problem(exc: Exception) -> dict[str, Any]:
    row = lookup(exc)
    if row is None or (row.status >= 500 and not isinstance(exc, PoolError)):
        if row is None:
            log.error("batch item failed: %s", type(exc).__name__)
        exc = InternalError("the job failed with an internal error")
    return json.loads(problem(exc).body)


def _batch_item(
    index: int, item: bytes | BatchItem, build: JobBuilder, settings: Settings
) -> Job | dict[str, Any]:
    """The job of one shape (PNG bytes, or a JSON item measured and not yet decoded),
    or its problem line."""
    try:
        if isinstance(item, bytes):
            check_image_size(item, settings.max_pixels)  # a batch holds images, not volumes
            return build.job(png=item)
        counts = item.counts
        check_values(counts, settings.max_vertices)
        check_polygon(
            counts.parts, counts.positions, settings.max_vertices, settings.estimate_seconds
        )
        return build.job(geojson=polygon_item(item.decode()))
    except SkelpruneError as exc:
        return {"index": index, "problem": _item_problem(exc)}
    except RecursionError:  # an item nested deeper than the parser's or validation's stack
        return {
            "index": index,
            "problem": _item_problem(InvalidPolygonError("shape: nested too deep")),
        }


def _batch_jobs(
    items: list[bytes] | list[BatchItem], build: JobBuilder, settings: Settings
) -> list[Job | dict[str, Any]]:
    return [_batch_item(i, item, build, settings) for i, item in enumerate(items)]


@router.post(
    "/v1/prune/batch",
    summary="Prune several shapes; NDJSON answer in input order",
    description=openapi.BATCH_DESCRIPTION,
    response_class=Response,
    responses=openapi.BATCH_RESPONSES,
    openapi_extra=openapi.BATCH_EXTRA,
    tags=["prune"],
)
async def prune_batch(
    call: Annotated[ShapeRequest, Depends(BATCH)],
    fn: Annotated[Callable[[Job], Any], Depends(job_function)],
) -> Response:
    settings = call.settings
    items: list[bytes] | list[BatchItem]
    if call.kind == "form":
        form = await call.form(max_files=BATCH_MAX_ITEMS + 1)
        items = list(form.files("file"))
        batch_size(items)
        # the options are checked first, once: a bad option is the batch's problem
        build = job_builder(
            call.query, form.options(files="file"), settings, polygon=False, media="json"
        )
        jobs = await asyncio.to_thread(_batch_jobs, items, build, settings)
    else:
        # split, measured and validated off the event loop, item by item
        items = await asyncio.to_thread(parse_batch, call.body)
        build = job_builder(call.query, None, settings, polygon=True, media="json")
        jobs = await asyncio.to_thread(_batch_jobs, items, build, settings)

    async def lines() -> AsyncIterator[bytes]:
        for index, job in enumerate(jobs):
            if isinstance(job, dict):
                line = job
            else:
                try:  # one job at a time: a batch never holds more than one worker
                    result = await call.run(fn, job)
                    yield b'{"index":%d,"result":' % index + result.body + b"}\n"
                    continue
                except Exception as exc:  # this shape's failure, not the batch's
                    line = {"index": index, "problem": _item_problem(exc)}
            yield json.dumps(line, separators=(",", ":")).encode() + b"\n"

    return StreamingResponse(lines(), media_type=NDJSON)
