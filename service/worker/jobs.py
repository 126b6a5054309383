"""Code that runs inside the worker processes: decode, prune, render.

Everything CPU-bound happens here, so the server's event loop only moves bytes:
the worker returns the response body already serialised.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any, Literal

import numpy as np

from skelprune.budget import Estimate, check_budget, estimate
from skelprune.io.input import Input, Kind, read_input
from skelprune.limits import Limits
from skelprune.options import (
    OutputOptions,
    PruneOptions,
    RasterOptions,
    ReadOptions,
    VolumeOptions,
)
from skelprune.output.finite import finite_json, finite_text

__all__ = [
    "PNG_HEADER_COMPONENTS",
    "Job",
    "JobResult",
    "dumps",
    "kernel_counts",
    "read_job",
    "run_job",
    "warmup",
]

#: The answers a job makes (its media type: :data:`MEDIA_TYPES`).
Media = Literal["json", "png", "geojson", "csv", "graphml", "swc"]

MEDIA_TYPES: dict[str, str] = {
    "json": "application/json",
    "png": "image/png",
    "geojson": "application/geo+json",
    "csv": "text/csv",
    "graphml": "application/graphml+xml",
    "swc": "text/x-swc",
}


@dataclass(frozen=True)
class Job:
    """One shape to prune, as sent to a worker (picklable): the input as it came, its
    kind, and the request's options as the library's checked, frozen values.

    ``data`` is the body's bytes for ``kind="image"`` (PNG or TIFF; a ``.npy`` or a
    multi-page TIFF is a volume), a GeoJSON mapping for ``kind="geojson"``; the worker
    prunes it with :func:`skelprune.prune` (as data, never a file's name) under
    ``limits`` and writes the answer with :func:`skelprune.encode`: the library's one
    entry and one encoder.
    """

    media: Media
    kind: Kind
    data: bytes | dict[str, Any]
    options: PruneOptions = field(default_factory=PruneOptions)
    read: ReadOptions = field(default_factory=ReadOptions)
    raster: RasterOptions = field(default_factory=RasterOptions)
    output: OutputOptions = field(default_factory=OutputOptions)
    volume: VolumeOptions = field(default_factory=VolumeOptions)
    limits: Limits = field(default_factory=Limits)  # the service's, per job


#: Response headers of the PNG answer: one value a component, comma-separated, in the
#: document's order (``repr`` of the float: it reads back exactly), for at most
#: :data:`PNG_HEADER_COMPONENTS` components.
PNG_HEADERS = {
    "X-Skelprune-RER": "rer",
    "X-Skelprune-SS": "ss",
    "X-Skelprune-Objective": "objective",
}


#: Most components whose values the PNG answer's headers list (three values of at most
#: 24 characters each: about 2.4 KB of headers). Proxies pass a few kilobytes of
#: response headers (nginx's default buffer: one 4-KiB page); past this the values are
#: left out and ``X-Skelprune-Values`` says where they are.
PNG_HEADER_COMPONENTS = 32


@dataclass(frozen=True)
class JobResult:
    """Serialised response body, its headers and the time spent in the library."""

    body: bytes
    media_type: str
    prune_seconds: float
    headers: dict[str, str] = field(default_factory=dict)


def kernel_counts() -> tuple[int, int]:
    """Compiled library kernels of this process: ``(loaded from numba's cache, compiled)``."""
    from numba.core.registry import CPUDispatcher

    loaded = compiled = 0
    for name, module in list(sys.modules.items()):
        if name == "skelprune" or name.startswith("skelprune."):
            for obj in list(vars(module).values()):
                if isinstance(obj, CPUDispatcher):
                    loaded += sum(obj.stats.cache_hits.values())
                    compiled += sum(obj.stats.cache_misses.values())
    return loaded, compiled


def warmup() -> str:
    """Worker initialiser: import the library and run it once so the JIT is compiled.

    The shape has a hole (the loop code paths) and a noisy boundary whose spurs the
    coarse stage removes (its code paths); ``coarse=None``, ``method="dce"`` and
    ``choice="noise-floor"`` run too, a match and a volume, so that no job of any option
    meets a function still to be loaded.

    Returns
    -------
    str
        What it took, for the log: kernels loaded from numba's cache and compiled.
    """
    t0 = time.perf_counter()
    import skelprune

    mask = np.zeros((32, 44), dtype=bool)
    mask[4:28, 4:40] = True
    mask[12:20, 16:28] = False  # a hole
    rng = np.random.default_rng(0)  # one-pixel bumps and notches along the rim: spurs
    mask[3, 4:40] = rng.random(36) < 0.5
    mask[28, 4:40] = rng.random(36) < 0.5
    mask[4:28:3, 4] = False
    for options in ({"choice": "noise-floor"}, {}, {"coarse": None}, {"method": "dce"}):
        res = skelprune.prune(mask, **options)
        res.to_dict()
    res.to_geojson()
    res.overlay_png()
    skelprune.match(res, res).to_dict()  # the matching kernels of POST /v1/match
    volume = np.zeros((12, 24, 36), dtype=bool)  # a T of two bars: a volume's code paths
    volume[3:9, 4:10, 3:33] = True
    volume[3:9, 4:21, 15:21] = True
    vres = skelprune.prune(volume, spacing=(2.0, 1.0, 1.0))
    vres.to_dict()
    vres.to_csv()
    vres.overlay_png()
    sparse = np.zeros((8, 20, 40), dtype=bool)  # a thin bar in a wide box: the sparse path
    sparse[3:6, 9:12, 5:35] = True
    skelprune.prune(sparse).to_dict()
    loaded, compiled = kernel_counts()
    took = f"{time.perf_counter() - t0:.1f} s"
    if compiled:
        return (
            f"compiled {compiled} numba kernels ({loaded} loaded from the cache) "
            f"in {took}; they are cached now"
        )
    return f"{loaded} numba kernels loaded from the cache in {took}"


#: The response header of a warning about the input that every answer carries (the
#: JSON document also holds it, as ``hint``): a label image read without ``labels``.
WARNING_HEADER = "X-Skelprune-Warning"


def read_job(job: Job) -> Input:
    """The job's input, read with the service's limits (``/v1/match`` reads its two)."""
    return read_input(
        job.data,
        kind=job.kind,
        read=job.read,
        raster=job.raster,
        max_pixels=job.limits.max_pixels,
        max_vertices=job.limits.max_vertices,
    )


def run_job(job: Job, progress: Callable[[int, int], None] | None = None) -> JobResult:
    """Prune the job's input under its limits and serialise the answer: the library's
    :func:`skelprune.prune` and :func:`skelprune.encode`, what every front calls.
    ``progress(done, total)`` is called as components (windows) are pruned."""
    t0 = time.perf_counter()
    try:
        if job.media == "geojson" and job.output.lines != "branches":
            return _run_lines_job(job)
        return _answer(job, t0, progress)
    except MemoryError:  # rendering the answer, past the estimate: the input's size
        from skelprune.budget import out_of_memory

        raise out_of_memory(job.limits.memory) from None


def _answer(job: Job, t0: float, progress: Callable[[int, int], None] | None = None) -> JobResult:
    from skelprune.api import prune
    from skelprune.output.encode import MEDIA_TYPES as ANSWER_TYPES
    from skelprune.output.encode import encode
    from skelprune.output.volume import VolumeResult

    res = prune(
        job.data,
        job.options,
        read=job.read,
        raster=job.raster,
        output=job.output,
        volume=job.volume,
        limits=job.limits,
        answers=(job.media,),
        kind=job.kind,
        progress=progress,
    )
    elapsed = time.perf_counter() - t0
    body = encode(res, job.media)
    headers: dict[str, str] = {}
    if job.media == "png":
        headers = png_headers(
            [c.to_dict() for c in res.components]
            if isinstance(res, VolumeResult)
            else [{k: getattr(c, k) for k in PNG_HEADERS.values()} for c in res.components]
        )
        if res.warnings:  # a polygon the raster does not hold as it is
            headers["X-Skelprune-Warnings"] = str(len(res.warnings))
    hint = getattr(getattr(res, "input", None), "hint", None)
    if hint is not None:  # a label image read without labels: said in every answer
        headers[WARNING_HEADER] = hint.encode("ascii", "replace").decode("ascii")
    media_type = MEDIA_TYPES.get(job.media, ANSWER_TYPES[job.media])
    return JobResult(body=body, media_type=media_type, prune_seconds=elapsed, headers=headers)


def _run_lines_job(job: Job) -> JobResult:
    """The map lines of a polygon job (``lines=map`` or ``main-path``): the library's
    :func:`skelprune.geo.geojson_lines`, every Feature pruned on its own, as
    ``skelprune centerlines`` prunes a file of them. The estimate: the whole input's
    read as one raster for one Feature; a collection's, the sum of its Features' (each
    read with the job's limits)."""
    from shapely.geometry import mapping

    from skelprune.geo import geojson_frame, geojson_lines
    from skelprune.io.input import read_input

    assert isinstance(job.data, dict)  # a polygon job's GeoJSON
    limits = job.limits
    whole = read_job(job)
    cost = estimate(whole.mask, 0, job.options.scope, whole.labels)
    frame = geojson_frame(job.data)
    if len(frame) > 1:
        raster = _feature_raster(job, frame)
        costs = [
            estimate(
                read_input(
                    mapping(g),
                    kind="geojson",
                    raster=raster,
                    max_pixels=limits.max_pixels,
                    max_vertices=limits.max_vertices,
                ).mask
            )
            for g in frame.geometry
            if g is not None and not g.is_empty
        ]
        if costs:  # (a collection of null geometries was refused when read)
            cost = Estimate(max(c.bytes for c in costs), sum(c.seconds for c in costs))
    check_budget(cost, limits.memory, limits.seconds)
    t0 = time.perf_counter()
    raster = replace(job.raster, crs=None)  # the CRS goes on its own, as centerlines takes it
    body = geojson_lines(
        job.data,
        main_path=job.output.lines == "main-path",
        crs=job.raster.crs,
        options=job.options,
        raster=raster,
    )
    return JobResult(
        body=body,
        media_type=MEDIA_TYPES[job.media],
        prune_seconds=time.perf_counter() - t0,
    )


def _feature_raster(job: Job, frame: Any) -> RasterOptions:
    """The raster options a Feature of ``frame`` is read with for its estimate: the
    job's, with the collection's CRS where the job gives none."""
    from skelprune.io.crs import crs_name

    crs = job.raster.crs or crs_name(frame.crs)
    return job.raster if crs is None else replace(job.raster, crs=crs)


def png_headers(values: list[Any]) -> dict[str, str]:
    """The PNG answer's headers from each component's numbers (a mapping with the keys of
    :data:`PNG_HEADERS`): the values up to :data:`PNG_HEADER_COMPONENTS` components,
    past them a pointer to the JSON document, so that headers stay small."""
    headers = {"X-Skelprune-Components": str(len(values))}
    if len(values) <= PNG_HEADER_COMPONENTS:
        for name, key in PNG_HEADERS.items():
            headers[name] = ",".join(finite_text(v[key]) for v in values)
    else:
        headers["X-Skelprune-Values"] = (
            f"omitted: more than {PNG_HEADER_COMPONENTS} components; ask for application/json"
        )
    return headers


def dumps(doc: Any) -> bytes:
    """The answer as compact JSON (what every job serialises with): a number that is not
    finite is null, the one rule of :mod:`skelprune.output.finite`."""
    return finite_json(doc)
