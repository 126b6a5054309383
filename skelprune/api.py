"""The one entry point most callers need: :func:`prune`."""

from __future__ import annotations

from collections.abc import Callable, Collection
from dataclasses import fields, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from .budget import VOLUME_BASIS, check_budget, estimate, out_of_memory, volume_estimate
from .errors import EmptyMaskError, InvalidOptionError
from .grid import components8
from .io.input import Input, Kind, read_input
from .limits import Limits, overlay_pixels, projections_scale
from .options import (
    METHODS,
    OutputOptions,
    PruneOptions,
    RasterOptions,
    ReadOptions,
    VolumeOptions,
    resolve_options,
    volume_value,
)
from .options_where import refuse_misplaced
from .output.document import PruneResult
from .pipeline import prune_component, prune_components

if TYPE_CHECKING:
    from .output.volume import VolumeResult
from .io.zarr import is_zarr
from .volume import MAX_VOLUME_VOXELS, is_volume, prune_volume, read_volume, read_zarr

__all__ = ["METHODS", "components", "prune", "prune_component", "prune_input"]


def components(mask: np.ndarray) -> list[tuple[np.ndarray, tuple[int, int]]]:
    """8-connected components as padded crops with their origin in the image.

    Each crop has one background pixel all around (so shapes touching the image
    border work) and holds only its own component.
    """
    return components8(mask)


def prune(
    source: Any,
    options: PruneOptions | None = None,
    *,
    read: ReadOptions | None = None,
    raster: RasterOptions | None = None,
    output: OutputOptions | None = None,
    volume: VolumeOptions | None = None,
    limits: Limits | None = None,
    answers: Collection[str] | None = None,
    kind: Kind | None = None,
    progress: Callable[[int, int], None] | None = None,
    **keywords: Any,
) -> PruneResult | VolumeResult:
    """Pruned skeleton of every 8-connected component of a shape: a mask, an image or a
    polygon; or of every 26-connected component of a volume (a 3-D array, a ``.npy``
    file or a TIFF stack, docs/volumes.md).

    The one entry of the pipeline: the command line, the service and data-set runs call
    it with their limits and the answers they will give, then
    :func:`skelprune.encode` writes each answer.

    Parameters
    ----------
    source : array, Input, GeoJSON mapping or text, shapely geometry, bytes or path
        (A 3-D array whose last axis is longer than 4, a ``.npy`` path or a multi-page
        TIFF's path is a volume; so is any 3-D array when ``spacing`` is given.)
        What :func:`skelprune.io.read_input` reads: a mask (its non-zero pixels are the
        shape unless ``foreground`` says otherwise), PNG bytes or a file's path, or a
        polygon (``Polygon``, ``MultiPolygon``, ``Feature`` or ``FeatureCollection``, or
        a shapely (Multi)Polygon), rasterised as ``raster`` says. A polygon's result maps
        itself back: ``to_dict()`` and ``to_geojson()`` answer in its coordinates and
        carry the raster's ``warnings``.
    options : PruneOptions, optional
        How to prune (:class:`skelprune.options.PruneOptions`: ``beta``, ``method``,
        ``coarse``, ``dce_threshold``, ``min_margin``, ``choice``, ``trim``, ``scope``,
        ``window``).
    read : ReadOptions, optional
        Image input: which pixels are the shape (``foreground``, ``labels``, ...).
    raster : RasterOptions, optional
        Polygon input: how it becomes pixels (``pixel_size``, ``longest_side``,
        ``pixels_per_width``, ``pixel_budget``, ``repair``, ``crs``).
    output : OutputOptions, optional
        What the result's answers hold by default (``curve``, ``sequence``, ``overlay``,
        ``overlay_scale``, ``overlay_legend``, ``simplify``, ``cut_ends``, ``table``).
    volume : VolumeOptions, optional
        Volume input: the voxel ``spacing`` ``(dz, dy, dx)``. A volume answers with a
        :class:`~skelprune.output.volume.VolumeResult` (docs/volumes.md).
    limits : Limits, optional
        What the input may cost (:class:`skelprune.limits.Limits`: pixels, positions,
        estimated memory and time); default: no limit.
    answers : collection of str, optional
        The answers that will be encoded (``"json"``, ``"geojson"``, ``"csv"``,
        ``"graphml"``, ``"png"``, ``"swc"``): an option that applies to none of them is
        refused, and an answer image counts against the limits. Default: any answer.
    kind : {"image", "geojson"}, optional
        What ``source`` is, when the caller knows (:func:`skelprune.io.read_input`):
        then bytes or text are data, never a file's path or another kind's.
    progress : callable, optional
        ``progress(done, total)``, called as each component (with ``scope="local"``: each
        window) is pruned: for a progress bar on a large image.
    **keywords
        Any field of those five classes by name, instead of the class's value (never
        both for one class): ``prune(mask, beta=3.0)`` is
        ``prune(mask, PruneOptions(beta=3.0))``.

    Returns
    -------
    PruneResult or VolumeResult
        The components' answers, the input (mask, frame, foreground) and every option:
        its outputs need no further argument.

    Raises
    ------
    EmptyMaskError
        When the shape has no pixel.
    InvalidOptionError
        For an option its class refuses, or one given where it does not apply (an
        image's ``foreground`` for a polygon, a GeoJSON ``simplify`` for a volume:
        each option's definition says where it applies).
    ImageTooLargeError, JobTooLargeError
        For an input over ``limits``.
    TypeError
        For an unknown option, or a class's value and its fields both given.

    Examples
    --------
    >>> m = np.zeros((80, 180), bool); m[10:70, 10:170] = True
    >>> res = prune(m)
    >>> comp = res.components[0]
    >>> len(comp.to_dict()["skeleton"]["endpoints"]), comp.rer < 0.05
    (4, True)
    >>> prune(m, beta=3.0).to_dict()["beta"], prune(m, PruneOptions(method="dce")).method
    (3.0, 'dce')

    A polygon, in its own coordinates:

    >>> strip = {"type": "Polygon",
    ...          "coordinates": [[[0, 0], [1000, 0], [1000, 20], [0, 20], [0, 0]]]}
    >>> res = prune(strip)
    >>> doc = res.to_dict()
    >>> doc["raster"]["fitted"], doc["warnings"]
    (True, [])
    >>> line = res.to_geojson()["features"][0]["geometry"]
    >>> line["type"], all(0 <= x <= 1000 and 0 <= y <= 20 for x, y in line["coordinates"])
    ('LineString', True)
    """
    named = set(keywords)
    volume = volume_value(volume, keywords)
    options, read, raster, output = resolve_options(options, read, raster, output, keywords)
    given = named | _changed(read, raster, output, volume)
    limits = limits or Limits()
    try:
        # an array given a spacing is a volume: a 2-D one is told it is not
        spacing = volume is not None
        if is_volume(source, spacing) or (spacing and isinstance(source, np.ndarray)):
            refuse_misplaced(given, "volume", answers, output.overlay)
            return _prune_volume(
                source, options, volume or VolumeOptions(), output, limits, answers, progress
            )
        if isinstance(source, Input):
            if read is not None or raster is not None:
                raise InvalidOptionError(
                    "read and raster options apply to reading; this input is read already"
                )
            shape = source
        else:
            shape = read_input(
                source,
                read=read,
                raster=raster,
                kind=kind,
                max_pixels=limits.max_pixels,
                max_vertices=limits.max_vertices,
            )
        refuse_misplaced(
            given, "polygon" if shape.kind == "geojson" else "image", answers, output.overlay
        )
        image = answers is not None and ("png" in answers or ("json" in answers and output.overlay))
        answer_pixels = overlay_pixels(shape.mask.shape, output, limits.max_pixels) if image else 0
        cost = estimate(shape.mask, answer_pixels, options.scope, shape.labels)
        check_budget(cost, limits.memory, limits.seconds)
        return prune_input(shape, options, output, progress)
    except MemoryError:  # the input's size: the same error as an estimate over the budget
        raise out_of_memory(limits.memory) from None


def _changed(*values: Any) -> set[str]:
    """The names of the options set to other than their defaults in option values."""
    return {
        f.name
        for value in values
        if value is not None
        for f in fields(value)
        if getattr(value, f.name) != getattr(type(value)(), f.name)
    }


def _prune_volume(
    source: Any,
    options: PruneOptions,
    volume: VolumeOptions,
    output: OutputOptions,
    limits: Limits,
    answers: Collection[str] | None,
    progress: Callable[[int, int], None] | None = None,
) -> VolumeResult:
    """A volume, read within the pixel limit, its estimate within the budget (a Zarr
    store's voxel size from its OME-Zarr scale, unless a spacing is given). A Zarr store
    pruned inside a Dask task (as ``prune_many`` runs it on a cluster) is pruned chunk by
    chunk on that cluster instead, never whole in one worker."""
    cluster = _task_cluster() if is_zarr(source) else None
    voxels = None
    if cluster is not None:  # only the store's metadata here
        from .io.zarr import open_zarr_volume

        shape = tuple(int(n) for n in open_zarr_volume(source).shape)
    elif is_zarr(source):
        voxels, stored = read_zarr(source, limits.max_pixels or MAX_VOLUME_VOXELS)
        if stored is not None and volume == VolumeOptions():
            volume = VolumeOptions(spacing=stored)
        voxels = read_volume(voxels)  # the dims' and the dtype's checks
        shape = voxels.shape
    else:
        voxels = read_volume(source, max_voxels=limits.max_pixels)
        shape = voxels.shape
    answer_pixels = 0
    if answers is not None and "png" in answers:
        scale, answer_pixels = projections_scale(shape, output, limits.max_pixels)
        output = replace(output, overlay_scale=scale)
    if cluster is not None:
        from .parallel.volume_chunks import MAX_BOX_VOXELS, prune_zarr_chunked

        with cluster as client:  # the task's slot is given back while its tasks run
            return prune_zarr_chunked(
                source,
                client,
                options,
                volume,
                output,
                max_box_voxels=min(MAX_BOX_VOXELS, limits.max_pixels or MAX_BOX_VOXELS),
            )
    assert voxels is not None
    check_budget(
        volume_estimate(voxels, answer_pixels), limits.memory, limits.seconds, VOLUME_BASIS
    )
    return prune_volume(voxels, options, volume, output, progress=progress)


def _task_cluster() -> Any:
    """A client of the Dask cluster running this call as a task (a context manager), or
    None outside a Dask worker."""
    try:
        from distributed import get_worker, worker_client
    except ImportError:
        return None
    try:
        get_worker()
    except ValueError:  # not in a worker
        return None
    return worker_client()


def prune_input(
    shape: Input,
    options: PruneOptions,
    output: OutputOptions | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> PruneResult:
    """The pipeline after reading: prune every component of an :class:`Input`.

    What :func:`prune` runs once its input is read and its options built; callers that
    read with limits of their own (the service) call it directly.
    """
    if not shape.mask.any():
        raise EmptyMaskError("the mask has no foreground pixel")
    applied = options.resolved()
    if applied.scope == "local":
        from .local import prune_local

        return prune_local(shape, applied, output, progress=progress)
    return prune_components(shape, applied, output, progress)
