"""The one entry point most callers need: :func:`prune`."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from .errors import EmptyMaskError
from .grid import components8
from .io.input import Input, read_input
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
from .output.document import PruneResult
from .pipeline import prune_component, prune_components

if TYPE_CHECKING:
    from .output.volume import VolumeResult
from .volume import is_volume, prune_volume

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
    progress: Callable[[int, int], None] | None = None,
    **keywords: Any,
) -> PruneResult | VolumeResult:
    """Pruned skeleton of every 8-connected component of a shape: a mask, an image or a
    polygon; or of every 26-connected component of a volume (a 3-D array, a ``.npy``
    file or a TIFF stack, docs/volumes.md).

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
        ``coarse``, ``dce_threshold``, ``min_margin``, ``choice``, ``trim``; the defaults:
        the paper's pruning from a coarse DCE skeleton, the answer's end branches of
        margin below 0.01 dropped, their tips cut back).
    read : ReadOptions, optional
        Image input: which pixels are the shape (``foreground``).
    raster : RasterOptions, optional
        Polygon input: how it becomes pixels (``pixel_size``, ``longest_side``,
        ``pixels_per_width``, ``pixel_budget``, ``repair``).
    output : OutputOptions, optional
        What the result's outputs hold by default (``curve``, ``sequence``, ``overlay``,
        ``overlay_scale``, ``overlay_legend``, ``simplify``, ``cut_ends``).
    volume : VolumeOptions, optional
        Volume input (a 3-D array or a ``.npy`` path): the voxel ``spacing``
        ``(dz, dy, dx)``. A volume is pruned as docs/volumes.md says, and answers with a
        :class:`~skelprune.output.volume.VolumeResult`.
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
        its outputs need no further argument. A volume answers with a
        :class:`~skelprune.output.volume.VolumeResult` (docs/volumes.md).

    Raises
    ------
    EmptyMaskError
        When the shape has no pixel.
    InvalidOptionError
        For an option its class refuses.
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
    volume = volume_value(volume, keywords)
    options, read, raster, output = resolve_options(options, read, raster, output, keywords)
    if volume is not None or is_volume(source):
        if read is not None or raster is not None:
            raise TypeError("read and raster options apply to images and polygons, not volumes")
        return prune_volume(source, options, volume or VolumeOptions(), output, progress)
    if isinstance(source, Input):
        if read is not None or raster is not None:
            raise TypeError("read and raster options apply to reading; this input is read")
        shape = source
    else:
        shape = read_input(source, read=read, raster=raster)
    return prune_input(shape, options, output, progress)


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
