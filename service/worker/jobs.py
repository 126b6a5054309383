"""Code that runs inside the worker processes: decode, prune, render.

Everything CPU-bound happens here, so the server's event loop only moves bytes:
the worker returns the response body already serialised.
"""

from __future__ import annotations

import json
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from skelprune.budget import (
    VOLUME_BASIS,
    check_budget,
    estimate,
    out_of_memory,
    volume_estimate,
)
from skelprune.errors import ImageTooLargeError, InvalidOptionError
from skelprune.io.input import Input, Kind, read_input
from skelprune.options import (
    OutputOptions,
    PruneOptions,
    RasterOptions,
    ReadOptions,
    VolumeOptions,
)
from skelprune.output.finite import finite_text, finite_tree
from skelprune.output.render import auto_scale

__all__ = [
    "PNG_HEADER_COMPONENTS",
    "Job",
    "JobResult",
    "answer_pixels",
    "dumps",
    "kernel_counts",
    "read_job",
    "run_job",
    "warmup",
]

#: The answers a job makes (its media type: :data:`MEDIA_TYPES`).
Media = Literal["json", "png", "geojson", "csv", "graphml"]

MEDIA_TYPES: dict[str, str] = {
    "json": "application/json",
    "png": "image/png",
    "geojson": "application/geo+json",
    "csv": "text/csv",
    "graphml": "application/graphml+xml",
}


@dataclass(frozen=True)
class Job:
    """One shape to prune, as sent to a worker (picklable): the input as it came, its
    kind, and the request's options as the library's checked, frozen values.

    ``data`` is the body's bytes for ``kind="image"`` (PNG or TIFF; a ``.npy`` or a
    multi-page TIFF is a volume), a GeoJSON mapping for ``kind="geojson"``; the worker
    reads it with :func:`skelprune.io.read_input` (as data, never a file's name) and
    prunes it with :func:`skelprune.api.prune_input`, the library's pipeline, or a volume
    with :func:`skelprune.volume.prune_volume`.
    """

    media: Media
    kind: Kind
    data: bytes | dict[str, Any]
    options: PruneOptions = field(default_factory=PruneOptions)
    read: ReadOptions = field(default_factory=ReadOptions)
    raster: RasterOptions = field(default_factory=RasterOptions)
    output: OutputOptions = field(default_factory=OutputOptions)
    volume: VolumeOptions = field(default_factory=VolumeOptions)
    max_pixels: int | None = None
    max_vertices: int | None = None
    memory_budget: int | None = None  # bytes a worker may hold for the job
    time_budget: float | None = None  # seconds its time estimate may reach (None: no screen)


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
    """The job's input, read with the service's limits."""
    return read_input(
        job.data,
        kind=job.kind,
        read=job.read,
        raster=job.raster,
        max_pixels=job.max_pixels,
        max_vertices=job.max_vertices,
    )


def answer_pixels(job: Job, shape: tuple[int, int]) -> int:
    """Pixels of the job's answer image (0 without one); refuses more than the pixel limit.

    Raises
    ------
    ImageTooLargeError
        When ``overlay_scale`` makes the overlay larger than ``max_pixels``.
    """
    if job.media != "png" and not job.output.overlay:
        return 0
    scale = auto_scale(shape) if job.output.overlay_scale is None else job.output.overlay_scale
    height, width = shape[0] * scale, shape[1] * scale
    if job.max_pixels is not None and width * height > job.max_pixels:
        raise ImageTooLargeError(
            f"the overlay image would have {width * height} pixels ({width}×{height}: "
            f"overlay_scale {scale} on {shape[1]}×{shape[0]}), the limit is "
            f"{job.max_pixels}; use a smaller overlay_scale"
        )
    return width * height


def run_job(job: Job, progress: Callable[[int, int], None] | None = None) -> JobResult:
    """Decode the input, check its memory estimate, prune it and serialise the answer.

    A ``MemoryError`` anywhere is the input's size: the same 413 as an estimate over
    the budget (:class:`~skelprune.errors.JobTooLargeError`), not an internal error.
    ``progress(done, total)`` is called as components (windows) are pruned.
    """
    try:
        return _run_job(job, progress)
    except MemoryError:
        raise out_of_memory(job.memory_budget) from None


def _run_job(job: Job, progress: Callable[[int, int], None] | None = None) -> JobResult:
    from skelprune.api import prune_input
    from skelprune.volume import is_volume

    if job.kind == "image" and isinstance(job.data, bytes) and is_volume(job.data):
        return _run_volume_job(job, progress)
    if job.volume != VolumeOptions():
        raise InvalidOptionError(
            "option(s) spacing only apply to volume input (a .npy or a TIFF stack body)"
        )
    shape = read_job(job)
    cost = estimate(
        shape.mask, answer_pixels(job, shape.mask.shape), job.options.scope, shape.labels
    )
    check_budget(cost, job.memory_budget, job.time_budget)
    t0 = time.perf_counter()
    res = prune_input(shape, job.options, job.output, progress)
    elapsed = time.perf_counter() - t0
    headers: dict[str, str] = {}
    if job.media == "png":
        body = res.overlay_png()
        headers = png_headers(
            [{k: getattr(c, k) for k in PNG_HEADERS.values()} for c in res.components]
        )
        if res.warnings:  # a polygon the raster does not hold as it is
            headers["X-Skelprune-Warnings"] = str(len(res.warnings))
    elif job.media == "geojson":
        body = dumps(res.to_geojson())
    elif job.media == "csv":  # the tables (docs/tables.md)
        body = res.to_csv(job.output.table).encode()
    elif job.media == "graphml":
        body = res.to_graphml().encode()
    else:
        body = dumps(res.to_dict())
    if shape.hint is not None:  # a label image read without labels: said in every answer
        headers[WARNING_HEADER] = shape.hint.encode("ascii", "replace").decode("ascii")
    return JobResult(
        body=body, media_type=MEDIA_TYPES[job.media], prune_seconds=elapsed, headers=headers
    )


def _run_volume_job(job: Job, progress: Callable[[int, int], None] | None = None) -> JobResult:
    """A volume's job: its voxels count against the pixel limit and the budgets."""
    from skelprune.volume import prune_volume, read_volume, refuse_image_options

    refuse_image_options(job.read, job.output)
    if job.media in ("geojson", "graphml"):
        raise InvalidOptionError(
            f"a volume has no {MEDIA_TYPES[job.media]} answer; ask for application/json, "
            "image/png (its three projections) or text/csv"
        )
    volume = read_volume(job.data, max_voxels=job.max_pixels)
    answer, scale = 0, 1
    if job.media == "png":
        scale, answer = projections_size(job, volume.shape)
    cost = volume_estimate(volume, answer)
    check_budget(cost, job.memory_budget, job.time_budget, VOLUME_BASIS)
    t0 = time.perf_counter()
    res = prune_volume(volume, job.options, job.volume, job.output, progress=progress)
    elapsed = time.perf_counter() - t0
    headers: dict[str, str] = {}
    if job.media == "png":
        body = res.overlay_png(scale)
        headers = png_headers([c.to_dict() for c in res.components])
    elif job.media == "csv":
        body = res.to_csv().encode()
    else:
        body = dumps(res.to_dict())
    return JobResult(
        body=body, media_type=MEDIA_TYPES[job.media], prune_seconds=elapsed, headers=headers
    )


def projections_size(job: Job, shape: tuple[int, ...]) -> tuple[int, int]:
    """The scale and pixels of a volume's projections image: ``overlay_scale``, or the
    default scale made smaller until the image fits the pixel limit.

    Raises
    ------
    ImageTooLargeError
        When the image is over ``max_pixels`` at the scale asked for (or at 1).
    """
    from skelprune.output.volume import auto_volume_scale

    z, y, x = shape
    base = (y + z + 4) * (x + z + 4)
    given = job.output.overlay_scale
    scale = given or auto_volume_scale(shape)
    if given is None and job.max_pixels is not None:
        while scale > 1 and base * scale * scale > job.max_pixels:
            scale -= 1
    answer = base * scale * scale
    if job.max_pixels is not None and answer > job.max_pixels:
        raise ImageTooLargeError(
            f"the projections image would have {answer} pixels (overlay_scale {scale} "
            f"on a {x}×{y}×{z} volume), the limit is {job.max_pixels}; use a smaller "
            "overlay_scale"
        )
    return scale, answer


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
    """The answer as compact JSON (what every job serialises with)."""
    # A number that is not finite is null (the one rule of skelprune.output.finite);
    # allow_nan=False then only guards that rule.
    return json.dumps(finite_tree(doc), separators=(",", ":"), allow_nan=False).encode()
