"""From a request's options to the worker's jobs: the one request builder.

Every endpoint that prunes (``POST /v1/prune``, each shape of ``POST /v1/prune/batch``,
both shapes of ``POST /v1/match``) goes through :func:`job_builder`: it gathers the
options from the query and the body, refuses an option where it does not apply, has the
library's option classes check the values, and :meth:`JobBuilder.job` makes the
:class:`~service.jobs.Job` of each shape. A :class:`~service.jobs.Job` is made nowhere
else.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any

from pydantic import BaseModel

from service.jobs import MEDIA_TYPES, Job, Output
from service.match_job import MatchJob
from service.schemas import POLYGON_ONLY, PruneQuery
from service.settings import Settings
from skelprune.errors import InvalidOptionError
from skelprune.options import OutputOptions, PruneOptions, RasterOptions, ReadOptions

__all__ = ["JobBuilder", "job_builder"]

PNG_ONLY = tuple(f.name for f in fields(ReadOptions))
#: Options of the JSON document only: refused with Accept: image/png or geo+json.
JSON_ONLY = ("curve", "overlay", "sequence")
#: Options of the overlay image: for Accept: image/png, or the JSON with overlay=true.
OVERLAY_ONLY = ("overlay_scale", "overlay_legend")
#: Options of the GeoJSON answer only.
GEOJSON_ONLY = ("simplify", "cut_ends")


def _gather(
    query: PruneQuery, body: BaseModel | None, polygon: bool, output: Output
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
    if output != "json":
        misplaced = [k for k in JSON_ONLY if k in opts]
        if misplaced:
            raise InvalidOptionError(
                f"option(s) {', '.join(misplaced)} only apply to the JSON document "
                f"(Accept: application/json), not to the {MEDIA_TYPES[output]} answer"
            )
    if output != "geojson":
        misplaced = [k for k in GEOJSON_ONLY if k in opts]
        if misplaced:
            raise InvalidOptionError(
                f"option(s) {', '.join(misplaced)} only apply to the GeoJSON answer "
                "(Accept: application/geo+json)"
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


@dataclass(frozen=True)
class JobBuilder:
    """A request's checked options and the service's limits: makes the job of each of
    its shapes."""

    output: Output
    settings: Settings
    prune: PruneOptions
    out: OutputOptions
    read: ReadOptions
    #: Keyword arguments of the polygon raster (empty for PNG input).
    raster: dict[str, Any]

    def job(self, png: bytes | None = None, geojson: dict[str, Any] | None = None) -> Job:
        """The worker's job for one shape: exactly one of ``png`` and ``geojson``."""
        settings = self.settings
        return Job(
            output=self.output,
            png=png,
            geojson=geojson,
            prune_options=self.prune.kwargs(),
            raster=self.raster,
            curve=self.out.curve,
            overlay=self.out.overlay,
            sequence=self.out.sequence,
            overlay_scale=self.out.overlay_scale,
            overlay_legend=self.out.overlay_legend,
            simplify=self.out.simplify,
            cut_ends=self.out.cut_ends,
            max_pixels=settings.max_pixels,
            foreground=self.read.foreground,
            memory_budget=settings.job_memory_mb * 2**20,
            time_budget=settings.job_timeout,
        )

    def match_job(self, a: Job, b: Job) -> MatchJob:
        """The worker's job matching two shapes (each a :meth:`job`)."""
        return MatchJob(a=a, b=b, prune_options=self.prune.kwargs())


def job_builder(
    query: PruneQuery,
    body: BaseModel | None,
    settings: Settings,
    *,
    polygon: bool,
    output: Output,
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
    output : {"json", "png", "geojson"}
        The negotiated answer: the output options apply where they shape it.
    match : bool
        A match: no output option applies.

    Raises
    ------
    InvalidOptionError
        An option given twice, where it does not apply, or with a bad value.
    """
    opts = _gather(query, body, polygon, output)
    if match:
        unused = list(_group(opts, OutputOptions))
        if unused:
            raise InvalidOptionError(f"option(s) {', '.join(unused)} do not apply to /v1/match")
    # The library's option classes check the values (the only place they are checked).
    prune = PruneOptions(**_group(opts, PruneOptions))
    out = OutputOptions(**_group(opts, OutputOptions))
    read = ReadOptions(**_group(opts, ReadOptions))
    raster: dict[str, Any] = {}
    if polygon:
        given = _group(opts, RasterOptions)
        if "pixel_size" not in given and settings.polygon_longest_side is not None:
            given.setdefault("longest_side", settings.polygon_longest_side)
        raster = {**RasterOptions(**given).kwargs(), "max_vertices": settings.max_vertices}
    return JobBuilder(output, settings, prune, out, read, raster)
