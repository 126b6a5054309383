"""``POST /v1/match``: the skeletons of two shapes, pruned alike, matched."""

from __future__ import annotations

from collections.abc import Callable
from typing import Annotated, Any

from fastapi import APIRouter, Depends, Request, Response

from service.apidocs import openapi
from service.errors import UnsupportedMediaTypeError
from service.http.bodies import (
    JSON_TYPES,
    check_polygon_body,
    content_type,
    parse_pair,
    read_form,
    refuse_encoding,
    validate_json,
)
from service.http.builder import job_builder
from service.http.query import QUERY_OPTIONS, parse_query
from service.settings import Settings
from service.worker.match_job import MatchJob, run_match_job
from service.worker.pool import WorkerPool
from skelprune.errors import InvalidOptionError
from skelprune.io.input import check_image_size

__all__ = ["match_function", "router"]

router = APIRouter()


async def match_function() -> Callable[[MatchJob], Any]:
    """The worker-side function of ``/v1/match`` (a dependency, as
    :func:`service.http.routes.prune.job_function`)."""
    return run_match_job


@router.post(
    "/v1/match",
    summary="Match the skeletons of two shapes (path similarity)",
    description=openapi.MATCH_DESCRIPTION,
    response_class=Response,
    responses=openapi.MATCH_RESPONSES,
    openapi_extra=openapi.MATCH_EXTRA,
    tags=["match"],
)
async def match(
    request: Request,
    fn: Annotated[Callable[[MatchJob], Any], Depends(match_function)],
) -> Response:
    query = parse_query(request.query_params)
    settings: Settings = request.app.state.settings
    pool: WorkerPool = request.app.state.pool
    ctype = content_type(request)
    refuse_encoding(request)
    body = await request.body()  # size-limited by BodyLimitMiddleware
    pngs: list[bytes] | None = None
    shapes: tuple[dict[str, Any], dict[str, Any]] | None = None
    if ctype == "multipart/form-data":
        form = await read_form(request, max_files=2)
        misplaced = sorted(k for k in form.names() if k in QUERY_OPTIONS)
        if misplaced:
            raise InvalidOptionError(
                f"option(s) {', '.join(misplaced)} sent as multipart fields; options go in "
                "the query string"
            )
        pngs = form.uploads(("a", "b"), "a PNG")
        for png in pngs:
            check_image_size(png, settings.max_pixels)
    elif ctype in JSON_TYPES:
        shapes = await validate_json(
            parse_pair,
            body,
            check_polygon_body(
                settings.max_vertices,
                None if settings.estimate_seconds is None else 2 * settings.estimate_seconds,
                shapes=2,
            ),
        )
    else:
        raise UnsupportedMediaTypeError(
            f"Content-Type {ctype or 'none'!r} is not supported; send multipart/form-data "
            "(fields 'a' and 'b') or application/json ({\"a\": GeoJSON, \"b\": GeoJSON})"
        )
    build = job_builder(
        query, None, settings, polygon=shapes is not None, output="json", match=True
    )
    a, b = (
        [build.job(png=p) for p in pngs]
        if pngs is not None
        else [build.job(geojson=g) for g in shapes or ()]
    )
    result = await pool.run(fn, build.match_job(a, b))
    request.app.state.metrics.prune_seconds.observe(result.prune_seconds)
    return Response(result.body, media_type=result.media_type)
