"""From a request's options to the worker's jobs: the one request builder.

Every endpoint that prunes (``POST /v1/prune``, each shape of ``POST /v1/prune/batch``,
both shapes of ``POST /v1/match``) goes through :func:`job_builder`: it gathers the
options from the query and the body, refuses an option where it does not apply, has the
library's option classes check the values, and :meth:`JobBuilder.job` makes the
:class:`~service.worker.jobs.Job` of each shape. A :class:`~service.worker.jobs.Job` is made nowhere
else.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import Any

from fastapi.exceptions import RequestValidationError
from pydantic import BaseModel

from service.http.schemas import POLYGON_ONLY, PruneQuery
from service.settings import Settings
from service.worker.jobs import MEDIA_TYPES, Job, Media
from service.worker.match_job import MatchJob
from skelprune.errors import InvalidOptionError
from skelprune.options import (
    GROUPS,
    OutputOptions,
    PruneOptions,
    RasterOptions,
    ReadOptions,
    VolumeOptions,
)

__all__ = ["JobBuilder", "job_builder"]

PNG_ONLY = tuple(f.name for f in fields(ReadOptions))
#: Options of the JSON document only: refused with Accept: image/png or geo+json.
JSON_ONLY = ("curve", "overlay", "sequence")
#: Options of the overlay image: for Accept: image/png, or the JSON with overlay=true.
OVERLAY_ONLY = ("overlay_scale", "overlay_legend")
#: Options of the GeoJSON answer only.
GEOJSON_ONLY = ("simplify", "cut_ends", "lines")
#: Options of the skeleton's branches as GeoJSON: the map lines (lines=map) have none.
BRANCHES_ONLY = ("simplify", "cut_ends")
#: Options of the tables' answers only (Accept: text/csv; pixel_size too, for an image).
TABLE_ONLY = ("table",)
TABLE_OUTPUTS = ("csv", "graphml")
#: The option groups a request's options are sorted into, each checked by its class.
OPTION_GROUPS = (*GROUPS, VolumeOptions)


def _gather(
    query: PruneQuery, body: BaseModel | None, polygon: bool, media: Media
) -> dict[str, Any]:
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
    if media != "json":
        misplaced = [k for k in JSON_ONLY if k in opts]
        if misplaced:
            raise InvalidOptionError(
                f"option(s) {', '.join(misplaced)} only apply to the JSON document "
                f"(Accept: application/json), not to the {MEDIA_TYPES[media]} answer"
            )
    if media != "geojson":
        misplaced = [k for k in GEOJSON_ONLY if k in opts]
        if misplaced:
            raise InvalidOptionError(
                f"option(s) {', '.join(misplaced)} only apply to the GeoJSON answer "
                "(Accept: application/geo+json)"
            )
    if opts.get("lines", "branches") != "branches":
        misplaced = [k for k in BRANCHES_ONLY if k in opts]
        if misplaced:
            raise InvalidOptionError(
                f"option(s) {', '.join(misplaced)} only apply to the skeleton's branches "
                f"(lines=branches), not to lines={opts['lines']}"
            )
        if not polygon:
            raise InvalidOptionError(
                f"lines={opts['lines']} only applies to polygon (GeoJSON) input: the map "
                "lines are drawn inside the polygon"
            )
    if media == "geojson" or (media == "json" and not opts.get("overlay")):
        misplaced = [k for k in OVERLAY_ONLY if k in opts]
        if misplaced:
            raise InvalidOptionError(
                f"option(s) {', '.join(misplaced)} only apply to the overlay image "
                "(Accept: image/png, or overlay=true)"
            )
    if any(k in opts for k in TABLE_ONLY) and media != "csv":
        raise InvalidOptionError(
            f"option(s) {', '.join(k for k in TABLE_ONLY if k in opts)} only apply to the "
            "tables' answer (Accept: text/csv)"
        )
    if not polygon and "pixel_size" in opts and media not in TABLE_OUTPUTS:
        raise InvalidOptionError(
            "option(s) pixel_size only apply to polygon input, or to an image's tables "
            "(Accept: text/csv or application/graphml+xml), whose unit it sets"
        )
    if polygon and "spacing" in opts:
        raise InvalidOptionError(
            "option(s) spacing only apply to volume input (a .npy or a TIFF stack body)"
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


def _where(query: PruneQuery, body: BaseModel | None) -> dict[str, str]:
    """Where each given option came from, as a validation error locates it."""
    where = {k: "query" for k, v in query.model_dump().items() if v is not None}
    if body is not None:
        where.update(
            (k, "body") for k, v in body.model_dump(exclude={"geojson"}).items() if v is not None
        )
    return where


def _values(opts: dict[str, Any], where: dict[str, str]) -> tuple[Any, ...]:
    """One value of each options class: the classes check the values, the only check
    (the request's models check wire types). Every refused option is located where it
    was given, as a validation error of the request."""
    values, errors = [], []
    for group in OPTION_GROUPS:
        try:
            values.append(group(**_group(opts, group)))
        except InvalidOptionError as exc:
            if not exc.errors:  # options refused together: no one place to name
                raise
            errors += [
                {"loc": (where.get(name, "query"), name), "msg": message, "type": "value_error"}
                for name, message in exc.errors
            ]
    if errors:
        raise RequestValidationError(errors)
    return tuple(values)


@dataclass(frozen=True)
class JobBuilder:
    """A request's checked options and the service's limits: makes the job of each of
    its shapes."""

    media: Media
    settings: Settings
    options: PruneOptions
    output: OutputOptions
    read: ReadOptions
    raster: RasterOptions
    volume: VolumeOptions = field(default_factory=VolumeOptions)

    def job(self, png: bytes | None = None, geojson: dict[str, Any] | None = None) -> Job:
        """The worker's job for one shape: exactly one of ``png`` (the bytes of an image
        body: PNG, TIFF, or a volume's ``.npy`` or TIFF stack) and ``geojson``."""
        settings = self.settings
        kind, data = ("image", png) if png is not None else ("geojson", geojson or {})
        return Job(
            media=self.media,
            kind=kind,
            data=data,
            options=self.options,
            read=self.read,
            raster=self.raster,
            output=self.output,
            volume=self.volume,
            max_pixels=settings.max_pixels,
            max_vertices=settings.max_vertices,
            memory_budget=settings.job_memory_mb * 2**20,
            time_budget=settings.estimate_seconds,
        )

    def match_job(self, a: Job, b: Job) -> MatchJob:
        """The worker's job matching two shapes (each a :meth:`job`)."""
        return MatchJob(a=a, b=b)


def job_builder(
    query: PruneQuery,
    body: BaseModel | None,
    settings: Settings,
    *,
    polygon: bool,
    media: Media,
    match: bool = False,
) -> JobBuilder:
    """The builder of a request's jobs.

    Parameters
    ----------
    query : PruneQuery
        The query's options.
    body : pydantic model, optional
        The options given in the body (the JSON envelope, the multipart fields).
    settings : Settings
        The service's limits, which every job carries.
    polygon : bool
        The input is GeoJSON (else PNG): the raster options apply, ``foreground`` not.
    media : {"json", "png", "geojson", "csv", "graphml", "swc"}
        The negotiated answer: the output options apply where they shape it.
    match : bool
        A match: no output option applies.

    Raises
    ------
    InvalidOptionError
        An option given twice, where it does not apply, or refused together with another.
    RequestValidationError
        An option with a bad value, located where it was given (query or body).
    """
    opts = _gather(query, body, polygon, media)
    if match:
        unused = list(_group(opts, OutputOptions)) + list(_group(opts, VolumeOptions))
        if unused:
            raise InvalidOptionError(f"option(s) {', '.join(unused)} do not apply to /v1/match")
    if (
        polygon
        and "pixel_size" not in opts
        and "longest_side" not in opts
        and settings.polygon_longest_side is not None
    ):
        opts["longest_side"] = settings.polygon_longest_side  # the server's default
    values = dict(zip(OPTION_GROUPS, _values(opts, _where(query, body)), strict=True))
    return JobBuilder(
        media,
        settings,
        values[PruneOptions],
        values[OutputOptions],
        values[ReadOptions],
        values[RasterOptions],
        values[VolumeOptions],
    )
