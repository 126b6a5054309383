"""``POST /v1/match``: the skeletons of two shapes, pruned alike, matched."""

from __future__ import annotations

from collections.abc import Callable
from typing import Annotated, Any

from fastapi import APIRouter, Depends, Response

from service.apidocs import openapi
from service.http.bodies import (
    check_polygon_body,
    check_upload,
    parse_pair,
    validate_json,
)
from service.http.builder import job_builder
from service.http.negotiation import accept_json
from service.http.query import QUERY_OPTIONS
from service.http.shape_request import ShapeRequest, ShapeRequests
from service.worker.match_job import MatchJob, run_match_job
from skelprune.errors import InvalidOptionError

__all__ = ["match_function", "router"]

router = APIRouter()


async def match_function() -> Callable[[MatchJob], Any]:
    """The worker-side function of ``/v1/match`` (a dependency, as
    :func:`service.http.routes.prune.job_function`)."""
    return run_match_job


#: ``POST /v1/match`` takes a form of two files or a JSON pair; it answers JSON.
MATCH = ShapeRequests(
    accept_json,
    ("form", "json"),
    "multipart/form-data (fields 'a' and 'b') or application/json "
    '({"a": GeoJSON, "b": GeoJSON})',
)


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
    call: Annotated[ShapeRequest, Depends(MATCH)],
    fn: Annotated[Callable[[MatchJob], Any], Depends(match_function)],
) -> Response:
    settings = call.settings
    pngs: list[bytes] | None = None
    shapes: tuple[dict[str, Any], dict[str, Any]] | None = None
    if call.kind == "form":
        form = await call.form(max_files=2)
        misplaced = sorted(k for k in form.names() if k in QUERY_OPTIONS)
        if misplaced:
            raise InvalidOptionError(
                f"option(s) {', '.join(misplaced)} sent as multipart fields; options go in "
                "the query string"
            )
        pngs = form.uploads(("a", "b"), "a PNG")
        for png in pngs:
            await check_upload(png, settings.max_pixels)
    else:
        shapes = await validate_json(
            parse_pair,
            call.body,
            check_polygon_body(
                settings.max_vertices,
                None if settings.estimate_seconds is None else 2 * settings.estimate_seconds,
                shapes=2,
            ),
        )
    build = job_builder(
        call.query, None, settings, polygon=shapes is not None, media="json", match=True
    )
    a, b = (
        [build.job(png=p) for p in pngs]
        if pngs is not None
        else [build.job(geojson=g) for g in shapes or ()]
    )
    result = await call.run(fn, build.match_job(a, b))
    return Response(result.body, media_type=result.media_type)
