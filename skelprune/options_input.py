"""The input's options: which pixels of an image are the shape (:class:`ReadOptions`), how a
polygon becomes pixels (:class:`RasterOptions`) and how a volume's voxels measure
(:class:`VolumeOptions`), with their defaults and limits. Importable from
:mod:`skelprune.options`, with the other options.
"""

from __future__ import annotations

from dataclasses import dataclass

from .errors import InvalidOptionError
from .options_checks import (
    _check_fields,
    _choice,
    _crs_name,
    _flag,
    _integer,
    _number,
    _option,
    _scale,
    _spacing,
)

__all__ = [
    "ARRAY_FOREGROUND",
    "DEFAULT_LONGEST_SIDE",
    "DEFAULT_PIXELS_PER_WIDTH",
    "DEFAULT_PIXEL_BUDGET",
    "FOREGROUND_RULES",
    "LONGEST_SIDE_RANGE",
    "MAX_CLEAN_AREA",
    "RasterOptions",
    "ReadOptions",
    "VolumeOptions",
]

#: The foreground rules (:mod:`skelprune.io.foreground`).
FOREGROUND_RULES = ("auto", "nonzero", "zero")
#: The foreground rule of an array given without one: an array is a mask, its non-zero
#: pixels the shape (an image file's default is ``auto``, :class:`ReadOptions`).
ARRAY_FOREGROUND = "nonzero"
#: The largest area (pixels) ``fill_holes`` and ``min_area`` take: a 2¹⁶ × 2¹⁶ image.
MAX_CLEAN_AREA = 1 << 32
#: Pixels across the longer side of a polygon's bounding box at the least (a polygon's
#: narrow parts may ask for more) ...
DEFAULT_LONGEST_SIDE = 512
#: ... and the range it may be set to: fewer pixels cannot hold a skeleton worth the
#: name; for more, give a pixel_size.
LONGEST_SIDE_RANGE = (8, 16384)
#: Pixels across a polygon's narrowest part when the pixel size comes from the polygon
#: (where the answer stops changing on generated rivers: docs/gis.md) ...
DEFAULT_PIXELS_PER_WIDTH = 3.0
#: ... within this many raster pixels (a 2048 × 2048 image).
DEFAULT_PIXEL_BUDGET = 2048 * 2048


#: Where the input's options apply (:mod:`skelprune.options_where`): an image's pixels ...
_IMAGE: dict[str, tuple[str, ...] | None] = {"image": None}
#: ... a polygon's raster (``pixel_size`` also sets the unit of an image's tables).
_POLYGON: dict[str, tuple[str, ...] | None] = {"polygon": None}


@dataclass(frozen=True)
class ReadOptions:
    """Which pixels of an image are the shape (image input only)."""

    foreground: str = _option(
        "auto",
        "Which pixels are the shape: auto (the grey side not holding most of the "
        "image border, split at mid-grey; the opaque part of a transparent image), nonzero "
        "or zero.",
        _choice(FOREGROUND_RULES),
        FOREGROUND_RULES,
        where=_IMAGE,
    )
    # label images and cleaning (docs/graph.md#label-images, #cleaning)
    labels: bool = _option(
        False,
        "Label image: every distinct non-zero value of an integer image is its own shape, "
        "pruned on its own even where two labels touch; each component carries its label.",
        _flag,
        where=_IMAGE,
    )
    fill_holes: int = _option(
        0,
        "Fill the shape's holes of fewer pixels than this, a whole number from 0 to "
        f"{MAX_CLEAN_AREA} (default 0: every hole kept).",
        _integer(0, MAX_CLEAN_AREA),
        where=_IMAGE,
    )
    min_area: int = _option(
        0,
        "Drop the components of fewer pixels than this, a whole number from 0 to "
        f"{MAX_CLEAN_AREA} (default 0: every component kept).",
        _integer(0, MAX_CLEAN_AREA),
        where=_IMAGE,
    )

    def __post_init__(self) -> None:
        _check_fields(self)


@dataclass(frozen=True)
class RasterOptions:
    """How a GeoJSON polygon becomes a raster (polygon input only).

    Examples
    --------
    >>> RasterOptions(pixel_size=0.5)  # doctest: +NORMALIZE_WHITESPACE
    RasterOptions(pixel_size=0.5, longest_side=None, pixels_per_width=3.0,
                  pixel_budget=4194304, repair=True, crs=None)
    >>> RasterOptions(pixel_size=0.5, longest_side=100)
    Traceback (most recent call last):
    ...
    skelprune.errors.InvalidOptionError: give pixel_size or longest_side, not both
    """

    pixel_size: float | None = _option(
        None,
        "Raster pixel size in the polygon's units, > 0 (default: fitted to the polygon, "
        "see pixels_per_width). For an image: the side of a pixel in your units, which "
        "the tables (summary, CSV) measure in (default: pixels).",
        _scale,
        where={"polygon": None, "image": ("csv", "graphml")},
    )
    longest_side: int | None = _option(
        None,
        "Pixels across the longer side of the bounding box, a whole number from "
        f"{LONGEST_SIDE_RANGE[0]} to {LONGEST_SIDE_RANGE[1]} (instead of pixel_size; "
        "default: fitted to the polygon).",
        _integer(*LONGEST_SIDE_RANGE),
        where=_POLYGON,
    )
    pixels_per_width: float = _option(
        DEFAULT_PIXELS_PER_WIDTH,
        "When neither pixel_size nor longest_side is given: pixels across the polygon's "
        f"narrowest part, >= 1 (default {DEFAULT_PIXELS_PER_WIDTH:g}); the raster is never "
        f"coarser than {DEFAULT_LONGEST_SIDE} px along the longer side and holds at most "
        "pixel_budget pixels.",
        _number(1, strict=False),
        where=_POLYGON,
    )
    pixel_budget: int = _option(
        DEFAULT_PIXEL_BUDGET,
        "Most pixels of a raster fitted to the polygon, a whole number from 4096 to "
        f"{1 << 28} (default {DEFAULT_PIXEL_BUDGET}).",
        _integer(4096, 1 << 28),
        where=_POLYGON,
    )
    repair: bool = _option(
        True,
        "Repair self-intersections with shapely's make_valid (true) or refuse them.",
        _flag,
        where=_POLYGON,
    )
    crs: str | None = _option(
        None,
        "The coordinates' CRS, an authority code pyproj knows or its URN (EPSG:4326, "
        "OGC:CRS84 for RFC 7946 GeoJSON, EPSG:32633, urn:ogc:def:crs:EPSG::32633), or "
        "planar: coordinates used as they are. Default: the GeoJSON's crs member; "
        "without one, longitude/latitude (OGC:CRS84, with a warning) if every coordinate "
        "lies within its bounds and the polygon is 1e-6 to 1 degree across, else planar. "
        "Longitude/latitude is pruned in a local equidistant projection: "
        "pixel_size, lengths and radii in metres, lines back in longitude/latitude. Needs "
        "the geo extra (pyproj).",
        _crs_name,
        where=_POLYGON,
    )

    def __post_init__(self) -> None:
        _check_fields(self)
        if self.pixel_size is not None and self.longest_side is not None:
            raise InvalidOptionError("give pixel_size or longest_side, not both")


@dataclass(frozen=True)
class VolumeOptions:
    """How a 3-D volume's voxels measure (volume input only: a 3-D array, a ``.npy`` or a
    TIFF stack).

    Examples
    --------
    >>> VolumeOptions(spacing=(3, 1, 1)).spacing, VolumeOptions(spacing="2,1,1").spacing
    ((3.0, 1.0, 1.0), (2.0, 1.0, 1.0))
    >>> VolumeOptions(spacing=(1, 0, 1))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    skelprune.errors.InvalidOptionError: spacing must be three finite numbers > 0 ...
    """

    spacing: tuple[float, float, float] = _option(
        (1.0, 1.0, 1.0),
        "Volume input: the physical size of a voxel along z, y and x (the array's first, "
        "second and last axis), three numbers > 0 (default 1, 1, 1). Distances, radii, "
        "lengths and widths are in its units; volumes are counted in voxels.",
        _spacing,
        where={"volume": None},
    )

    def __post_init__(self) -> None:
        object.__setattr__(self, "spacing", _spacing("spacing", self.spacing))
