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

from service.http.schemas import PruneQuery
from service.settings import Settings
from service.worker.jobs import Job, Media
from service.worker.match_job import MatchJob
from skelprune.errors import InvalidOptionError
from skelprune.limits import Limits
from skelprune.options import (
    GROUPS,
    OutputOptions,
    PruneOptions,
    RasterOptions,
    ReadOptions,
    VolumeOptions,
)
from skelprune.options_where import refuse_misplaced

__all__ = ["JobBuilder", "job_builder"]

#: Options of the skeleton's branches as GeoJSON: the map lines (lines=map) have none.
BRANCHES_ONLY = ("simplify", "cut_ends")
#: The option groups a request's options are sorted into, each checked by its class.
OPTION_GROUPS = GROUPS


def _gather(
    query: PruneQuery, body: BaseModel | None, polygon: bool, media: Media
) -> dict[str, Any]:
    """The request's options: the query's and the body's (JSON envelope or multipart
    fields), each given once, each where its definition says it applies
    (:func:`skelprune.options_where.refuse_misplaced`, the library's own check)."""
    opts = {k: v for k, v in query.model_dump().items() if v is not None}
    if body is not None:
        for key, value in body.model_dump(exclude={"geojson"}).items():
            if value is None:
                continue
            if key in opts:
                raise InvalidOptionError(f"option {key!r} is given both in the query and the body")
            opts[key] = value
    overlay = bool(opts.get("overlay"))
    if polygon:
        refuse_misplaced(opts, "polygon", media, overlay)
        if opts.get("lines", "branches") != "branches":
            misplaced = [k for k in BRANCHES_ONLY if k in opts]
            if misplaced:
                raise InvalidOptionError(
                    f"option(s) {', '.join(misplaced)} only apply to the skeleton's branches "
                    f"(lines=branches), not to lines={opts['lines']}"
                )
        return opts
    # an image body may hold a volume (a .npy or a TIFF stack), told when it is read:
    # an option of either passes here, and the library refuses it there if misplaced
    try:
        refuse_misplaced(opts, "image", media, overlay)
    except InvalidOptionError:
        try:
            refuse_misplaced(opts, "volume", media, overlay)
        except InvalidOptionError:
            refuse_misplaced(opts, "image", media, overlay)
    if opts.get("lines", "branches") != "branches":
        raise InvalidOptionError(
            f"lines={opts['lines']} only applies to the GeoJSON answer of polygon input "
            "(GeoJSON): the map lines are drawn inside the polygon"
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
            limits=Limits(
                memory_mb=settings.job_memory_mb,
                seconds=settings.estimate_seconds,
                max_pixels=settings.max_pixels,
                max_vertices=settings.max_vertices,
            ),
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
