"""HTTP endpoints: ``POST /v1/prune``, ``POST /v1/prune/batch``, ``POST /v1/match``,
``/healthz``, ``/readyz``, ``/metrics``, ``/v1/version``."""

from __future__ import annotations

import asyncio
import json
import logging
from collections.abc import AsyncIterator, Callable
from dataclasses import fields
from typing import Annotated, Any

from fastapi import APIRouter, Depends, Request, Response
from fastapi.exceptions import RequestValidationError
from fastapi.responses import StreamingResponse
from prometheus_client import CONTENT_TYPE_LATEST, generate_latest
from pydantic import ValidationError
from starlette.datastructures import QueryParams, UploadFile

from service import examples
from service.errors import (
    BodyTooLargeError,
    InternalError,
    NotAcceptableError,
    UnsupportedMediaTypeError,
    lookup,
    problem,
)
from service.jobs import MEDIA_TYPES, Job, Output, run_job
from service.match_job import (
    MATCH_DESCRIPTION,
    MATCH_REQUEST_BODY,
    MATCH_RESPONSES,
    MatchJob,
    MatchPolygons,
    run_match_job,
)
from service.pool import (
    PoolClosedError,
    PoolError,
    PoolStartingError,
    QueueFullError,
    WorkerPool,
)
from service.schemas import (
    POLYGON_ONLY,
    Health,
    PolygonJob,
    PruneQuery,
    Readiness,
    Version,
    polygon_request_adapter,
    query_parameters,
)
from service.settings import Settings
from skelprune import ALGORITHM_VERSION, __version__
from skelprune.errors import InvalidOptionError, InvalidPolygonError, SkelpruneError
from skelprune.io.png import check_png_size
from skelprune.options import OutputOptions, PruneOptions, RasterOptions, ReadOptions

__all__ = ["job_function", "match_function", "negotiate", "parse_query", "router"]

router = APIRouter()
log = logging.getLogger("service.routes")

#: Media types ``POST /v1/prune`` can answer with, in the server's order of preference.
PRODUCES: dict[str, Output] = {
    "application/json": "json",
    "image/png": "png",
    "application/geo+json": "geojson",
}
JSON_TYPES = ("application/json", "application/geo+json")
PNG_ONLY = tuple(f.name for f in fields(ReadOptions))
BIG_JSON = 256 * 1024  # bytes of JSON above which validation moves to a thread
QUERY_OPTIONS = frozenset(PruneQuery.model_fields)  # no aliases: field name = parameter
#: Options of the JSON document only: refused with Accept: image/png or geo+json.
JSON_ONLY = ("curve", "overlay", "sequence")
#: Options of the overlay image: for Accept: image/png, or the JSON with overlay=true.
OVERLAY_ONLY = ("overlay_scale", "overlay_legend")
#: Tags of the JSON body's union: pydantic puts them in error locations, the user's body
#: has no such level.
BODY_TAGS = frozenset({"Polygon", "MultiPolygon", "Feature", "FeatureCollection", "job"})


def negotiate(accept: str | None) -> Output:
    """Pick the output for an ``Accept`` header (q-values honoured; none means JSON).

    Raises
    ------
    NotAcceptableError
        When no producible type has q > 0.
    """
    if not accept or not accept.strip():
        return "json"
    ranges: list[tuple[str, float]] = []
    for part in accept.split(","):
        fields = [f.strip() for f in part.split(";")]
        media = fields[0].lower()
        if not media:
            continue
        q = 1.0
        for param in fields[1:]:
            key, _, value = param.partition("=")
            if key.strip().lower() == "q":
                try:
                    q = float(value)
                except ValueError:
                    q = 0.0
        ranges.append((media, q))

    def quality(candidate: str) -> float:
        main = candidate.split("/")[0]
        best, best_rank = 0.0, -1
        for media, q in ranges:
            rank = (
                2
                if media == candidate
                else 1
                if media == f"{main}/*"
                else 0
                if media == "*/*"
                else -1
            )
            if rank > best_rank:
                best, best_rank = q, rank
        return best if best_rank >= 0 else 0.0

    if not ranges:  # only commas and blanks: no preference stated, as without the header
        return "json"
    scored = [(quality(m), -i, out) for i, (m, out) in enumerate(PRODUCES.items())]
    q, _, out = max(scored)
    if q <= 0:
        raise NotAcceptableError(
            f"cannot produce any of {accept!r}; available: {', '.join(PRODUCES)}"
        )
    return out


async def job_function() -> Callable[[Job], Any]:
    """The worker-side function (a dependency, so that tests can swap in a faulty one).

    ``async`` although it does nothing to wait for: FastAPI runs a plain ``def``
    dependency in its thread pool, a thread round trip on every request.
    """
    return run_job


def _validation(errors: list[dict[str, Any]], prefix: tuple[str, ...]) -> RequestValidationError:
    return RequestValidationError([{**e, "loc": (*prefix, *e.get("loc", ()))} for e in errors])


def parse_query(params: QueryParams) -> PruneQuery:
    """The query options, validated as one model.

    Does what FastAPI does for a parameter ``Annotated[PruneQuery, Query()]`` (the last
    value of a repeated option wins; any other parameter goes to the model too, a list if
    repeated, where ``extra="forbid"`` refuses it; errors are located at
    ``("query", name)``), without its per-field dependency machinery, which took about
    a third of the application's own CPU time per request.

    Raises
    ------
    RequestValidationError
        When an option is invalid or unknown.
    """
    data: dict[str, Any] = {name: params[name] for name in QUERY_OPTIONS if name in params}
    extras: dict[str, list[str]] = {}
    for key, value in params.multi_items():
        if key not in QUERY_OPTIONS:
            extras.setdefault(key, []).append(value)
    data.update((key, v[0] if len(v) == 1 else v) for key, v in extras.items())
    try:
        return PruneQuery.model_validate(data)
    except ValidationError as exc:
        raise _validation(exc.errors(include_url=False), ("query",)) from None


def _options(query: PruneQuery, body: Any, polygon: bool, output: Output) -> dict[str, Any]:
    """The request's options: the query's and the body's (JSON envelope or multipart
    fields), each given once, each where it applies."""
    opts = {k: v for k, v in query.model_dump().items() if v is not None}
    if body is not None:
        for key, value in body.model_dump(exclude={"geojson"}).items():
            if value is None:
                continue
            if key in opts:
                raise InvalidOptionError(f"option {key!r} is given both in the query and the body")
            opts[key] = value
    if output != "json":
        misplaced = [k for k in JSON_ONLY if k in opts]
        if misplaced:
            raise InvalidOptionError(
                f"option(s) {', '.join(misplaced)} only apply to the JSON document "
                f"(Accept: application/json), not to the {MEDIA_TYPES[output]} answer"
            )
    if output == "geojson" or (output == "json" and not opts.get("overlay")):
        misplaced = [k for k in OVERLAY_ONLY if k in opts]
        if misplaced:
            raise InvalidOptionError(
                f"option(s) {', '.join(misplaced)} only apply to the overlay image "
                "(Accept: image/png, or overlay=true)"
            )
    if not polygon:
        misplaced = [k for k in POLYGON_ONLY if k in opts]
        if misplaced:
            raise InvalidOptionError(
                f"option(s) {', '.join(misplaced)} only apply to polygon (JSON) input"
            )
    else:
        misplaced = [k for k in PNG_ONLY if k in opts]
        if misplaced:
            raise InvalidOptionError(
                f"option(s) {', '.join(misplaced)} only apply to PNG input; a polygon's "
                "shape is its interior"
            )
    return opts


def _group(opts: dict[str, Any], group: type) -> dict[str, Any]:
    """The options of one group that the request gave."""
    return {f.name: opts[f.name] for f in fields(group) if f.name in opts}


def _body_errors(errors: list[Any]) -> list[dict[str, Any]]:
    """Validation errors located in the user's body, without pydantic's union tags."""
    shown = []
    for e in errors:
        loc = tuple(p for p in e.get("loc", ()) if p not in BODY_TAGS)
        if e.get("type") == "union_tag_invalid":
            given = (e.get("ctx") or {}).get("tag")
            e = {
                **e,
                "msg": f"GeoJSON type {given!r} is not accepted: send a Polygon, "
                "MultiPolygon, Feature or FeatureCollection, or "
                '{"geojson": <one of those>, <options>}',
            }
        elif e.get("type") == "model_type":  # pydantic names the model class here
            e = {**e, "msg": "Input should be a JSON object"}
        shown.append({**e, "loc": loc})
    return shown


def _parse_polygon(body: bytes) -> tuple[PolygonJob | None, dict[str, Any]]:
    """Validate a JSON body: (envelope with options or None, GeoJSON as plain data)."""
    try:
        parsed = polygon_request_adapter.validate_json(body)
    except ValidationError as exc:
        raise _validation(_body_errors(exc.errors(include_url=False)), ("body",)) from None
    envelope = parsed if isinstance(parsed, PolygonJob) else None
    shape = parsed.geojson if envelope is not None else parsed
    return envelope, shape.model_dump(mode="json", exclude_none=True)


async def _png_from_multipart(request: Request) -> tuple[bytes, PruneQuery]:
    """The PNG of the field ``file`` and the options sent as the other fields."""
    async with request.form(max_files=1, max_fields=16) as form:
        upload = form.get("file")
        if not isinstance(upload, UploadFile):
            raise RequestValidationError(
                [
                    {
                        "loc": ("body", "file"),
                        "type": "missing",
                        "msg": "multipart field 'file' with the PNG is required",
                    }
                ]
            )
        # The other fields are options, read as the query's are (unknown ones refused).
        fields = QueryParams(
            [(k, v) for k, v in form.multi_items() if k != "file" and isinstance(v, str)]
        )
        try:
            options = parse_query(fields)
        except RequestValidationError as exc:
            raise RequestValidationError(
                [{**e, "loc": ("body", *e["loc"][1:])} for e in exc.errors()]
            ) from None
        return await upload.read(), options


PRUNE_DESCRIPTION = """
Compute the pruned skeleton of a shape.

**Input** (by `Content-Type`):
- `image/png`: the PNG itself as the body;
- `multipart/form-data`: the PNG in the field `file`;
- `application/json` (or `application/geo+json`): a GeoJSON `Polygon`, `MultiPolygon`,
  `Feature` or `FeatureCollection` (holes allowed), or an object
  `{"geojson": <GeoJSON>, <options>}`. The polygon is rasterised (default: longer side
  512 px) and every coordinate, radius and length in the answer is in the polygon's
  own frame and units.

**Output** (by `Accept`): `application/json` (default) the result document
(`PruneDocument` below: per component its RER, SS, λ and the skeleton graph, nodes with
radii and branches as paths), `image/png` the overlay image (the numbers in the
`X-Skelprune-*` headers), `application/geo+json` the skeleton as GeoJSON (the numbers in
its properties).

Options go in the query string, or in the body (multipart fields beside `file`; the
JSON envelope), never both; an option where it does not apply is refused (422).
"""


@router.post(
    "/v1/prune",
    summary="Prune the skeleton of a PNG mask or a GeoJSON polygon",
    description=PRUNE_DESCRIPTION,
    response_class=Response,
    responses=examples.PRUNE_RESPONSES,
    # the query options are parsed in the handler (parse_query): documented from the model
    openapi_extra={
        "requestBody": examples.PRUNE_REQUEST_BODY,
        "parameters": query_parameters(PruneQuery),
    },
    tags=["prune"],
)
async def prune(
    request: Request,
    fn: Annotated[Callable[[Job], Any], Depends(job_function)],
) -> Response:
    query = parse_query(request.query_params)  # first: bad options are refused before all
    settings: Settings = request.app.state.settings
    pool: WorkerPool = request.app.state.pool
    output = negotiate(request.headers.get("accept"))
    ctype = request.headers.get("content-type", "").split(";")[0].strip().lower()
    encoding = request.headers.get("content-encoding", "").strip().lower()
    if encoding not in ("", "identity"):  # never decode what was meant to be inflated
        raise UnsupportedMediaTypeError(
            f"Content-Encoding {encoding!r} is not supported; send the body uncompressed"
        )
    body = await request.body()  # size-limited by BodyLimitMiddleware
    if ctype in ("image/png", "multipart/form-data"):
        envelope = None
        if ctype == "image/png":
            png = body
        else:
            png, envelope = await _png_from_multipart(request)
        check_png_size(png, settings.max_pixels)  # refused before it is queued
        geojson = None
    elif ctype in JSON_TYPES:
        # A big polygon takes a while to validate: off the event loop, so that other
        # requests (health checks included) keep being served meanwhile.
        if len(body) > BIG_JSON:
            envelope, geojson = await asyncio.to_thread(_parse_polygon, body)
        else:
            envelope, geojson = _parse_polygon(body)
        png = None
    else:
        shown = ctype or "none"
        raise UnsupportedMediaTypeError(
            f"Content-Type {shown!r} is not supported; send image/png, multipart/form-data "
            "(field 'file') or application/json (GeoJSON)"
        )
    opts = _options(query, envelope, polygon=geojson is not None, output=output)
    job = _job(opts, settings, output, png, geojson)
    result = await pool.run(fn, job)
    request.app.state.metrics.prune_seconds.observe(result.prune_seconds)
    # The same URL answers in three formats: caches must key on Accept.
    return Response(
        result.body, media_type=result.media_type, headers={"Vary": "Accept", **result.headers}
    )


def _job(
    opts: dict[str, Any],
    settings: Settings,
    output: Output,
    png: bytes | None,
    geojson: dict[str, Any] | None,
) -> Job:
    """The worker's job for one shape and the request's options."""
    # The library's option classes check the values (the only place they are checked).
    prune_options = PruneOptions(**_group(opts, PruneOptions))
    output_options = OutputOptions(**_group(opts, OutputOptions))
    read_options = ReadOptions(**_group(opts, ReadOptions))
    raster: dict[str, Any] = {}
    if geojson is not None:
        given = _group(opts, RasterOptions)
        if "pixel_size" not in given:
            given.setdefault("longest_side", settings.polygon_longest_side)
        raster = {**RasterOptions(**given).kwargs(), "max_vertices": settings.max_vertices}
    return Job(
        output=output,
        png=png,
        geojson=geojson,
        prune_options=prune_options.kwargs(),
        raster=raster,
        curve=output_options.curve,
        overlay=output_options.overlay,
        sequence=output_options.sequence,
        overlay_scale=output_options.overlay_scale,
        overlay_legend=output_options.overlay_legend,
        max_pixels=settings.max_pixels,
        foreground=read_options.foreground,
        memory_budget=settings.job_memory_mb * 2**20,
        time_budget=settings.job_timeout,
    )


#: Most shapes in one batch request (more: 413 before any is pruned).
BATCH_MAX_ITEMS = 32
NDJSON = "application/x-ndjson"

BATCH_DESCRIPTION = f"""
Prune several shapes in one request; the answer is NDJSON (`{NDJSON}`), one line per
shape in input order: `{{"index": i, "result": <document>}}` or
`{{"index": i, "problem": <problem details>}}`. One shape's failure never fails the others.

**Input**: `multipart/form-data` with the PNGs in repeated fields `file` (options as other
fields or in the query), or `application/json`: a list of GeoJSON objects (`Polygon`,
`MultiPolygon`, `Feature`, `FeatureCollection`; options in the query). At most
{BATCH_MAX_ITEMS} shapes; the body limit is the one of `POST /v1/prune`. The options
apply to every shape. Shapes are pruned one after another, each a job of the same worker
pool and queue as `POST /v1/prune`: a batch holds at most one worker at a time, so single
requests are never starved by it; a shape that meets a full queue gets its 503 problem.
"""


def _item_problem(exc: Exception) -> dict[str, Any]:
    row = lookup(exc)
    if row is None or (row.status >= 500 and not isinstance(exc, PoolError)):
        if row is None:
            log.error("batch item failed: %s", type(exc).__name__)
        exc = InternalError("the job failed with an internal error")
    return json.loads(problem(exc).body)


def _batch_item(
    index: int, item: Any, opts: dict[str, Any], settings: Settings, png: bool
) -> Job | dict[str, Any]:
    """The job of one shape, or its problem line."""
    try:
        if png:
            check_png_size(item, settings.max_pixels)
            return _job(opts, settings, "json", item, None)
        try:
            shape = polygon_request_adapter.validate_python(item)
        except ValidationError as exc:
            first = _body_errors(exc.errors(include_url=False))[0]
            where = ".".join(str(p) for p in first["loc"])
            raise InvalidPolygonError(f"{where or 'shape'}: {first['msg']}") from None
        if isinstance(shape, PolygonJob):
            raise InvalidOptionError("a batch item is a GeoJSON object; options go in the query")
        return _job(opts, settings, "json", None, shape.model_dump(mode="json", exclude_none=True))
    except SkelpruneError as exc:
        return {"index": index, "problem": _item_problem(exc)}
    except RecursionError:  # an item nested deeper than validation's stack
        return {
            "index": index,
            "problem": _item_problem(InvalidPolygonError("shape: nested too deep")),
        }


@router.post(
    "/v1/prune/batch",
    summary="Prune several shapes; NDJSON answer in input order",
    description=BATCH_DESCRIPTION,
    response_class=Response,
    responses={
        **{k: v for k, v in examples.PRUNE_RESPONSES.items() if k != 200},
        200: {
            "description": "One JSON line per shape, in input order.",
            "content": {
                NDJSON: {
                    "schema": {"type": "string"},
                    "example": (
                        '{"index":0,"result":{"width":60,"height":30,"components":[…]}}\n'
                        '{"index":1,"problem":{"type":"urn:skelprune:problem:invalid-image",'
                        '"title":"Invalid image","status":400,"detail":"not a PNG file '
                        '(bad signature)"}}\n'
                    ),
                }
            },
        },
        413: examples.problem_response(
            413,
            "body-too-large",
            "Request body too large",
            f"a batch holds at most {BATCH_MAX_ITEMS} shapes, got 40",
            "/v1/prune/batch",
        ),
    },
    openapi_extra={
        "parameters": query_parameters(PruneQuery),
        "requestBody": {
            "required": True,
            "content": {
                "multipart/form-data": {
                    "schema": {
                        "type": "object",
                        "properties": {
                            "file": {
                                "type": "array",
                                "items": {"type": "string", "format": "binary"},
                                "maxItems": BATCH_MAX_ITEMS,
                            }
                        },
                        "required": ["file"],
                    }
                },
                "application/json": {
                    "schema": {
                        "type": "array",
                        "maxItems": BATCH_MAX_ITEMS,
                        "items": {"type": "object"},
                    }
                },
            },
        },
    },
    tags=["prune"],
)
async def prune_batch(
    request: Request,
    fn: Annotated[Callable[[Job], Any], Depends(job_function)],
) -> Response:
    query = parse_query(request.query_params)
    settings: Settings = request.app.state.settings
    pool: WorkerPool = request.app.state.pool
    accept = request.headers.get("accept", "")
    if accept.strip() and not any(m in accept for m in (NDJSON, "application/json", "*/*")):
        raise NotAcceptableError(f"cannot produce any of {accept!r}; available: {NDJSON}")
    ctype = request.headers.get("content-type", "").split(";")[0].strip().lower()
    body = await request.body()  # size-limited by BodyLimitMiddleware
    items: list[Any]
    form_options = None
    if ctype == "multipart/form-data":
        async with request.form(max_files=BATCH_MAX_ITEMS + 1, max_fields=16) as form:
            uploads = [v for v in form.getlist("file") if isinstance(v, UploadFile)]
            items = [await u.read() for u in uploads]
            fields = QueryParams(
                [(k, v) for k, v in form.multi_items() if k != "file" and isinstance(v, str)]
            )
        try:
            form_options = parse_query(fields)
        except RequestValidationError as exc:
            raise RequestValidationError(
                [{**e, "loc": ("body", *e["loc"][1:])} for e in exc.errors()]
            ) from None
    elif ctype in JSON_TYPES:
        try:
            # UTF-8 only, as POST /v1/prune reads JSON (json.loads would guess UTF-16/32)
            items = json.loads(body.decode("utf-8"))
        except UnicodeDecodeError as exc:
            raise RequestValidationError(
                [
                    {
                        "loc": ("body",),
                        "type": "json_invalid",
                        "msg": f"invalid JSON: not UTF-8 (byte {exc.start})",
                    }
                ]
            ) from None
        except ValueError as exc:
            raise RequestValidationError(
                [{"loc": ("body",), "type": "json_invalid", "msg": f"invalid JSON: {exc}"}]
            ) from None
        except RecursionError:  # nesting deeper than the parser's stack
            raise RequestValidationError(
                [{"loc": ("body",), "type": "json_invalid", "msg": "invalid JSON: nested too deep"}]
            ) from None
        if not isinstance(items, list):
            raise RequestValidationError(
                [
                    {
                        "loc": ("body",),
                        "type": "list_type",
                        "msg": "a batch is a JSON list of GeoJSON objects",
                    }
                ]
            )
    else:
        raise UnsupportedMediaTypeError(
            f"Content-Type {ctype or 'none'!r} is not supported; send multipart/form-data "
            "(fields 'file') or application/json (a list of GeoJSON objects)"
        )
    if not items:
        raise InvalidOptionError("the batch is empty: send at least one shape")
    if len(items) > BATCH_MAX_ITEMS:
        raise BodyTooLargeError(f"a batch holds at most {BATCH_MAX_ITEMS} shapes, got {len(items)}")
    png = ctype == "multipart/form-data"
    opts = _options(query, form_options, polygon=not png, output="json")
    _job(opts, settings, "json", b"" if png else None, None if png else {})  # options first
    jobs = [_batch_item(i, item, opts, settings, png) for i, item in enumerate(items)]

    async def lines() -> AsyncIterator[bytes]:
        for index, job in enumerate(jobs):
            if isinstance(job, dict):
                line = job
            else:
                try:  # one job at a time: a batch never holds more than one worker
                    result = await pool.run(fn, job)
                    request.app.state.metrics.prune_seconds.observe(result.prune_seconds)
                    yield b'{"index":%d,"result":' % index + result.body + b"}\n"
                    continue
                except Exception as exc:  # this shape's failure, not the batch's
                    line = {"index": index, "problem": _item_problem(exc)}
            yield json.dumps(line, separators=(",", ":")).encode() + b"\n"

    return StreamingResponse(lines(), media_type=NDJSON)


async def match_function() -> Callable[[MatchJob], Any]:
    """The worker-side function of ``/v1/match`` (a dependency, as :func:`job_function`)."""
    return run_match_job


async def _pngs_from_multipart(request: Request) -> tuple[bytes, bytes]:
    async with request.form(max_files=2, max_fields=16) as form:
        misplaced = sorted(k for k in form if k in QUERY_OPTIONS)
        if misplaced:
            raise InvalidOptionError(
                f"option(s) {', '.join(misplaced)} sent as multipart fields; options go in "
                "the query string"
            )
        missing = [k for k in ("a", "b") if not isinstance(form.get(k), UploadFile)]
        if missing:
            raise RequestValidationError(
                [
                    {
                        "loc": ("body", k),
                        "type": "missing",
                        "msg": f"multipart field {k!r} with a PNG is required",
                    }
                    for k in missing
                ]
            )
        a, b = form.get("a"), form.get("b")
        assert isinstance(a, UploadFile) and isinstance(b, UploadFile)
        return await a.read(), await b.read()


def _parse_pair(body: bytes) -> tuple[dict[str, Any], dict[str, Any]]:
    try:
        parsed = MatchPolygons.model_validate_json(body)
    except ValidationError as exc:
        raise _validation(exc.errors(include_url=False), ("body",)) from None
    return (
        parsed.a.model_dump(mode="json", exclude_none=True),
        parsed.b.model_dump(mode="json", exclude_none=True),
    )


@router.post(
    "/v1/match",
    summary="Match the skeletons of two shapes (path similarity)",
    description=MATCH_DESCRIPTION,
    response_class=Response,
    responses={
        **{k: v for k, v in examples.PRUNE_RESPONSES.items() if k not in (200, 406)},
        **MATCH_RESPONSES,
    },
    openapi_extra={
        "requestBody": MATCH_REQUEST_BODY,
        "parameters": [
            p
            for p in query_parameters(PruneQuery)
            if p["name"] not in {f.name for f in fields(OutputOptions)}
        ],
    },
    tags=["match"],
)
async def match(
    request: Request,
    fn: Annotated[Callable[[MatchJob], Any], Depends(match_function)],
) -> Response:
    query = parse_query(request.query_params)
    settings: Settings = request.app.state.settings
    pool: WorkerPool = request.app.state.pool
    ctype = request.headers.get("content-type", "").split(";")[0].strip().lower()
    encoding = request.headers.get("content-encoding", "").strip().lower()
    if encoding not in ("", "identity"):
        raise UnsupportedMediaTypeError(
            f"Content-Encoding {encoding!r} is not supported; send the body uncompressed"
        )
    body = await request.body()  # size-limited by BodyLimitMiddleware
    pngs: tuple[bytes, bytes] | None = None
    shapes: tuple[dict[str, Any], dict[str, Any]] | None = None
    if ctype == "multipart/form-data":
        pngs = await _pngs_from_multipart(request)
        for png in pngs:
            check_png_size(png, settings.max_pixels)
    elif ctype in JSON_TYPES:
        shapes = (
            await asyncio.to_thread(_parse_pair, body)
            if len(body) > BIG_JSON
            else _parse_pair(body)
        )
    else:
        raise UnsupportedMediaTypeError(
            f"Content-Type {ctype or 'none'!r} is not supported; send multipart/form-data "
            "(fields 'a' and 'b') or application/json ({\"a\": GeoJSON, \"b\": GeoJSON})"
        )
    opts = _options(query, None, polygon=shapes is not None, output="json")
    unused = [k for k in _group(opts, OutputOptions)]
    if unused:
        raise InvalidOptionError(f"option(s) {', '.join(unused)} do not apply to /v1/match")
    prune_options = PruneOptions(**_group(opts, PruneOptions))
    read_options = ReadOptions(**_group(opts, ReadOptions))
    raster: dict[str, Any] = {}
    if shapes is not None:
        given = _group(opts, RasterOptions)
        if "pixel_size" not in given:
            given.setdefault("longest_side", settings.polygon_longest_side)
        raster = {**RasterOptions(**given).kwargs(), "max_vertices": settings.max_vertices}
    inputs = (
        [
            Job(
                output="json",
                png=p,
                max_pixels=settings.max_pixels,
                foreground=read_options.foreground,
                memory_budget=settings.job_memory_mb * 2**20,
                time_budget=settings.job_timeout,
            )
            for p in pngs
        ]
        if pngs is not None
        else [
            Job(
                output="json",
                geojson=g,
                raster=raster,
                max_pixels=settings.max_pixels,
                memory_budget=settings.job_memory_mb * 2**20,
                time_budget=settings.job_timeout,
            )
            for g in shapes or ()
        ]
    )
    job = MatchJob(a=inputs[0], b=inputs[1], prune_options=prune_options.kwargs())
    result = await pool.run(fn, job)
    request.app.state.metrics.prune_seconds.observe(result.prune_seconds)
    return Response(result.body, media_type=result.media_type)


@router.get(
    "/healthz",
    response_model=Health,
    summary="Liveness: the process answers",
    tags=["ops"],
    responses={
        200: {
            "content": {
                "application/json": {
                    "example": {
                        "status": "ok",
                        "version": __version__,
                        "algorithm": ALGORITHM_VERSION,
                    }
                }
            }
        }
    },
)
async def healthz() -> Health:
    return Health(status="ok", version=__version__, algorithm=ALGORITHM_VERSION)


@router.get(
    "/v1/version",
    response_model=Version,
    summary="Versions of the service and its results",
    responses={
        200: {
            "content": {
                "application/json": {
                    "example": {
                        "service": __version__,
                        "library": __version__,
                        "algorithm": ALGORITHM_VERSION,
                    }
                }
            }
        }
    },
    tags=["ops"],
)
async def version() -> Version:
    return Version(service=__version__, library=__version__, algorithm=ALGORITHM_VERSION)


@router.get(
    "/readyz",
    response_model=Readiness,
    summary="Readiness: worker pool up and the queue not full",
    responses={
        200: {
            "content": {
                "application/json": {
                    "example": {
                        "status": "ready",
                        "workers": 4,
                        "busy": 1,
                        "queued": 0,
                        "queue_size": 16,
                    }
                }
            }
        },
        503: examples.problem_response(
            503, "queue-full", "Service busy", "the queue is full (16 jobs waiting)", "/readyz"
        ),
    },
    tags=["ops"],
)
async def readyz(request: Request) -> Readiness:
    pool: WorkerPool = request.app.state.pool
    if pool.starting and not pool.closed:
        raise PoolStartingError(
            f"the worker pool is warming up ({pool.warm} of {pool.size} workers ready)"
        )
    failure = request.app.state.pool_failure
    if failure is not None:
        raise PoolClosedError(f"the worker pool failed to start: {failure}")
    if not pool.started or pool.closed:
        raise PoolClosedError("the worker pool is not running")
    if not pool.ready:
        raise QueueFullError(f"the queue is full ({pool.waiting} jobs waiting)")
    return Readiness(
        status="ready",
        workers=pool.alive(),
        busy=pool.busy,
        queued=pool.waiting,
        queue_size=pool.queue_size,
    )


@router.get(
    "/metrics",
    summary="Prometheus metrics",
    response_class=Response,
    responses={
        200: {
            "description": "Prometheus text exposition format.",
            "content": {
                "text/plain": {"schema": {"type": "string"}, "example": examples.METRICS_EXAMPLE}
            },
        },
        401: examples.UNAUTHORIZED,
    },
    tags=["ops"],
)
async def metrics(request: Request) -> Response:
    return Response(
        generate_latest(request.app.state.metrics.registry), media_type=CONTENT_TYPE_LATEST
    )
