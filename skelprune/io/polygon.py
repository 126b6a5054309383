"""GeoJSON polygons to a raster mask and the frame that maps pixels back.

Parsing and validation: :mod:`skelprune.io.parse` (a ``Polygon`` or ``MultiPolygon``,
a ``Feature`` holding one, or a ``FeatureCollection`` of them; invalid geometry repaired or
refused).

Rasterisation: the pixel size is fitted to the polygon (:mod:`skelprune.io.fit`: a few
pixels across its narrowest part, at least 512 pixels along the bounding box's longer
side, within a pixel budget), or the bounding box is scaled so that its longer side spans
``longest_side`` pixels, or the given ``pixel_size`` is used, with a margin
of ``margin`` background pixels (default 2) on every side. A pixel belongs to the shape
iff its centre lies inside the polygon or on its boundary (OpenCV fills the interior,
shapely decides the pixels next to an edge exactly).
World y grows upwards, so row 0 is the top of the bounding box and the returned
:class:`~skelprune.io.frame.PixelFrame` has ``flip_y=True``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import cv2
import numpy as np
from shapely.geometry import MultiPolygon

from skelprune.errors import EmptyMaskError, ImageTooLargeError, InvalidPolygonError, shown
from skelprune.io.crs import (
    GUESS_DEGREES,
    PLANAR,
    LocalProjection,
    guess_crs,
    has_pyproj,
    local_projection,
)
from skelprune.io.fit import (
    RasterWarning,
    budget_pixel_size,
    check_topology,
    covered_xy,
    fitted_pixel_size,
)
from skelprune.io.frame import PixelFrame
from skelprune.io.parse import parse_geojson, parse_polygon
from skelprune.options import DEFAULT_LONGEST_SIDE, RasterOptions, options_value

__all__ = [
    "DEFAULT_LONGEST_SIDE",
    "DEFAULT_MARGIN",
    "PolygonRaster",
    "parse_geojson",
    "polygon_mask",
    "polygon_raster",
    "rasterize",
    "read_polygon",
]

DEFAULT_MARGIN = 2
#: Times a fitted pixel size is refined to the size the topology check names.
REFITS = 2
_SHIFT = 8  # fractional bits for cv2.fillPoly: sub-pixel vertex positions
_MAX_SIDE = 1 << 20  # keeps fixed-point vertex coordinates inside int32


@dataclass
class PolygonRaster:
    """A polygon, its raster, the frame that maps the raster back, and what it lost.

    ``fitted`` tells whether the pixel size came from the polygon (no ``pixel_size`` or
    ``longest_side`` given); ``warnings`` lists the parts the raster does not hold as they
    are (:func:`skelprune.io.fit.check_topology`); ``options`` are the options that made it.
    ``crs``: the coordinates' CRS, where one is known; ``projection``: for geographic
    coordinates, the local projection the polygon (``geometry``, in metres) and the frame
    are in (:mod:`skelprune.io.crs`).
    """

    geometry: MultiPolygon
    mask: np.ndarray
    frame: PixelFrame
    fitted: bool
    warnings: list[RasterWarning] = field(default_factory=list)
    options: RasterOptions = field(default_factory=RasterOptions)
    crs: str | None = None
    projection: LocalProjection | None = None

    def to_dict(self) -> dict[str, Any]:
        """What the document says of the raster (``raster``): its size and every raster
        option (``pixel_size`` the one used, given or fitted)."""
        return {
            "pixel_size": self.frame.pixel_size,
            "width": int(self.mask.shape[1]),
            "height": int(self.mask.shape[0]),
            "fitted": self.fitted,
            "parts": len(self.geometry.geoms),
            "longest_side": self.options.longest_side,
            "pixels_per_width": self.options.pixels_per_width,
            "pixel_budget": self.options.pixel_budget,
            "repair": self.options.repair,
            "crs": self.crs,
            **({} if self.projection is None else {"projection": self.projection.proj}),
        }


def rasterize(
    geom: MultiPolygon,
    options: RasterOptions | None = None,
    *,
    margin: int = DEFAULT_MARGIN,
    max_pixels: int | None = None,
    **keywords: Any,
) -> tuple[np.ndarray, PixelFrame]:
    """Fill a polygon into a boolean raster.

    Parameters
    ----------
    geom : shapely.geometry.MultiPolygon
        Valid polygonal geometry, e.g. from :func:`parse_geojson`.
    options : RasterOptions, optional
        The pixel size (``pixel_size``, or ``longest_side`` pixels across the bounding
        box's longer side, or fitted to the polygon: :mod:`skelprune.io.fit`,
        ``pixels_per_width`` pixels across its narrowest part, within ``pixel_budget``
        pixels and ``max_pixels``). Its fields may be given as keywords instead.
    margin : int
        Background pixels added on every side.
    max_pixels : int, optional
        Refuse a raster larger than this (before allocating it).

    Returns
    -------
    mask : numpy.ndarray
        ``(H, W)`` boolean raster.
    frame : PixelFrame
        Maps pixel centres ``(col, row)`` back to polygon coordinates.

    Raises
    ------
    EmptyMaskError
        When no pixel centre falls inside the polygon (it is thinner than a pixel).
    """
    raster = polygon_raster(
        geom,
        options_value(RasterOptions, options, keywords),
        margin=margin,
        max_pixels=max_pixels,
        check=False,
    )
    return raster.mask, raster.frame


def polygon_raster(
    geom: MultiPolygon,
    options: RasterOptions | None = None,
    *,
    margin: int = DEFAULT_MARGIN,
    max_pixels: int | None = None,
    check: bool = True,
    **keywords: Any,
) -> PolygonRaster:
    """:func:`rasterize`, keeping the geometry, the options and (``check``) the topology
    check's warnings.

    Examples
    --------
    >>> from shapely.geometry import box
    >>> raster = polygon_raster(MultiPolygon([box(0, 0, 10, 10)]), pixel_size=1.0)
    >>> raster.mask.shape, raster.fitted, raster.options.pixel_size
    ((14, 14), False, 1.0)
    """
    options = options_value(RasterOptions, options, keywords)
    pixel_size, longest_side = options.pixel_size, options.longest_side
    minx, miny, maxx, maxy = geom.bounds
    extent = max(maxx - minx, maxy - miny)
    if not math.isfinite(extent):
        raise InvalidPolygonError("coordinates span too large a range to rasterise")

    def fill(g: MultiPolygon, size: float) -> tuple[np.ndarray, PixelFrame]:
        return _fill(g, size, margin, max_pixels)

    fitted = pixel_size is None and longest_side is None
    budget = options.pixel_budget if max_pixels is None else min(options.pixel_budget, max_pixels)
    if fitted:
        if extent <= 0 or not math.isfinite(extent / DEFAULT_LONGEST_SIDE):
            raise InvalidPolygonError(f"polygon extent {extent:.3g} is too small to rasterise")
        size = fitted_pixel_size(
            geom, options.pixels_per_width, budget, DEFAULT_LONGEST_SIDE, margin
        )
        mask, frame = fill(geom, size)
    else:
        if pixel_size is None:
            side = DEFAULT_LONGEST_SIDE if longest_side is None else longest_side
            if side > _MAX_SIDE:
                raise ImageTooLargeError(
                    f"longest_side {shown(side)} is over the limit of {_MAX_SIDE} pixels"
                )
            pixel_size = extent / side
        mask, frame = fill(geom, pixel_size)
    warnings = check_topology(geom, mask, frame, margin, fill) if check else []
    if fitted:
        # A fitted size that loses a part: take the size that holds it, budget allowing
        # (the size came from a measure; the check is the proof).
        finest = budget_pixel_size(geom, budget, margin)
        for _ in range(REFITS):
            sizes = [w.pixel_size for w in warnings if w.pixel_size is not None]
            if not sizes or min(sizes) < finest:
                break
            mask, frame = fill(geom, min(sizes))
            warnings = check_topology(geom, mask, frame, margin, fill)
    return PolygonRaster(geom, mask, frame, fitted, warnings, options)


def _fill(
    geom: MultiPolygon, pixel_size: float, margin: int, max_pixels: int | None
) -> tuple[np.ndarray, PixelFrame]:
    minx, miny, maxx, maxy = geom.bounds
    extent = max(maxx - minx, maxy - miny)
    cols_f = (maxx - minx) / pixel_size
    rows_f = (maxy - miny) / pixel_size
    if not (cols_f <= _MAX_SIDE and rows_f <= _MAX_SIDE):  # also catches inf / nan
        raise ImageTooLargeError(
            f"raster of {cols_f:.3g}×{rows_f:.3g} pixels is too large; use a larger pixel_size"
        )
    scale = (1 << _SHIFT) / pixel_size if pixel_size > 0 else math.inf
    if not math.isfinite(scale):
        raise InvalidPolygonError(
            f"polygon extent {extent:.3g} or pixel size {pixel_size:.3g} is too small to rasterise"
        )
    width = math.ceil(cols_f - 1e-9) + 2 * margin
    height = math.ceil(rows_f - 1e-9) + 2 * margin
    if max_pixels is not None and width * height > max_pixels:
        raise ImageTooLargeError(
            f"raster of {width}×{height} = {width * height} pixels exceeds the limit of "
            f"{max_pixels}; use a larger pixel_size or a smaller longest_side"
        )
    # Pixel (col,row) covers [col-0.5, col+0.5]; the bbox starts at the margin's edge.
    frame = PixelFrame(
        x0=minx + (0.5 - margin) * pixel_size,
        y0=maxy + (margin - 0.5) * pixel_size,
        pixel_size=pixel_size,
        flip_y=True,
    )
    canvas = np.zeros((height, width), dtype=np.uint8)
    band = np.zeros_like(canvas)
    for poly in geom.geoms:
        pts = []
        for ring in (poly.exterior, *poly.interiors):
            xy = np.asarray(ring.coords)[:, :2]
            col = (xy[:, 0] - frame.x0) * scale
            row = (frame.y0 - xy[:, 1]) * scale
            pts.append(np.round(np.stack([col, row], axis=1)).astype(np.int32))
        # One call per polygon: even-odd over its rings leaves the holes empty, and
        # islands inside another polygon's hole survive because nothing is erased.
        cv2.fillPoly(canvas, pts, 1, lineType=cv2.LINE_8, shift=_SHIFT)
        cv2.polylines(band, pts, True, 1, thickness=1, lineType=cv2.LINE_8, shift=_SHIFT)
    # fillPoly counts every pixel its edges touch as inside (up to half a pixel of bias
    # per side). Re-decide the pixels near an edge exactly: centre inside or on the
    # boundary. Only the thin band is tested, so this costs little.
    band = cv2.dilate(band, np.ones((3, 3), np.uint8))
    rows, cols = np.nonzero(band)
    xs = frame.x0 + cols * pixel_size
    ys = frame.y0 - rows * pixel_size
    canvas[rows, cols] = covered_xy(geom, xs, ys)
    if not canvas.any():
        raise EmptyMaskError(
            f"the polygon covers no pixel centre at a pixel size of {pixel_size:.3g}: it is "
            "thinner than a pixel; use a smaller pixel_size or a larger longest_side"
        )
    return canvas.astype(bool), frame


def polygon_mask(
    obj: Mapping[str, Any],
    options: RasterOptions | None = None,
    *,
    margin: int = DEFAULT_MARGIN,
    max_vertices: int | None = None,
    max_pixels: int | None = None,
    **keywords: Any,
) -> tuple[np.ndarray, PixelFrame]:
    """Validate and rasterise a GeoJSON polygon: :func:`parse_geojson` then :func:`rasterize`
    (``options`` or its fields as keywords: :class:`~skelprune.options.RasterOptions`).

    Examples
    --------
    >>> square = {"type": "Polygon",
    ...           "coordinates": [[[0, 0], [10, 0], [10, 10], [0, 10], [0, 0]]]}
    >>> mask, frame = polygon_mask(square, pixel_size=1.0)
    >>> mask.shape, int(mask.sum()), frame.point(2, 2)
    ((14, 14), 100, (0.5, 9.5))
    """
    options = options_value(RasterOptions, options, keywords)
    geom = parse_geojson(obj, max_vertices=max_vertices, repair=options.repair)
    return rasterize(geom, options, margin=margin, max_pixels=max_pixels)


def _guessed(geom: MultiPolygon, warnings: list[RasterWarning]) -> str | None:
    """The CRS of a polygon given without one (:func:`guess_crs`), its warning added."""
    crs = guess_crs(geom)
    if crs is None:
        return None
    what = (
        f"no CRS given, and every coordinate lies within longitude/latitude bounds with the "
        f"polygon at most {GUESS_DEGREES:g}° across"
    )
    if not has_pyproj():  # pragma: no cover - the geo extra installs it
        warnings.append(
            RasterWarning(
                "crs",
                f"{what}, as RFC 7946 longitude/latitude is; read as planar all the same "
                "(pyproj is missing: install skelprune[geo]); give crs to say which",
            )
        )
        return None
    warnings.append(
        RasterWarning(
            "crs",
            f"{what}: read as RFC 7946 longitude/latitude ({crs}), pruned on the ground in "
            'metres; give crs="planar" if the coordinates are planar',
        )
    )
    return crs


def read_polygon(
    obj: Mapping[str, Any],
    options: RasterOptions | None = None,
    *,
    max_vertices: int | None = None,
    max_pixels: int | None = None,
) -> PolygonRaster:
    """Validate a GeoJSON polygon and rasterise it with its topology check:
    :func:`parse_geojson` then :func:`polygon_raster`.

    The one way a polygon becomes a raster for pruning (:func:`skelprune.io.read_input`).
    A polygon in a geographic CRS (``options.crs``, else the GeoJSON's ``crs`` member,
    else :func:`~skelprune.io.crs.guess_crs`, with a ``crs`` warning) is rasterised in its
    local equidistant projection (:mod:`skelprune.io.crs`).
    """
    options = RasterOptions() if options is None else options
    parsed = parse_polygon(obj, max_vertices=max_vertices, repair=options.repair)
    crs = options.crs or parsed.crs
    geom, projection = parsed.geometry, None
    if crs is None:
        crs = _guessed(geom, parsed.warnings)
    elif crs == PLANAR:
        crs = None
    if crs is not None:
        projection = local_projection(geom, crs)
        if projection is not None:
            geom = projection.forward(geom)
    raster = polygon_raster(geom, options, max_pixels=max_pixels)
    raster.warnings[:0] = parsed.warnings
    raster.crs, raster.projection = crs, projection
    return raster
