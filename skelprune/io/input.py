"""Any input read into one value: :class:`Input` (the mask, the frame back to the input's
coordinates, what was taken as the shape), by one reader, :func:`read_input`.

The first stage of every caller's pipeline (the library's :func:`skelprune.prune`, the
command line, the service's jobs): what differs between a PNG, an array and a GeoJSON
polygon ends here.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from ..errors import ImageTooLargeError, InvalidImageError, InvalidPolygonError
from ..options import ARRAY_FOREGROUND, RasterOptions, ReadOptions
from .foreground import POLYGON_FOREGROUND, Foreground
from .frame import IDENTITY, PixelFrame
from .geotiff import GEOTIFF_SUFFIXES, Georeference
from .tiff import is_georeferenced

if TYPE_CHECKING:
    from .polygon import PolygonRaster

__all__ = [
    "GEOJSON_SUFFIXES",
    "IMAGE_FORMATS",
    "MASK_FOREGROUND",
    "Input",
    "Kind",
    "check_image_size",
    "read_input",
]

#: What an input is: an image (PNG or array) or a GeoJSON polygon.
Kind = Literal["image", "geojson"]
#: File name endings read as GeoJSON polygons (any case); any other file is read as a PNG.
GEOJSON_SUFFIXES = (".geojson", ".json")
#: The image formats read (by their signature, whatever the file's name).
IMAGE_FORMATS = ("PNG", "TIFF", "GIF")
#: What a mask given as it is (an array, a GeoTIFF) takes as the shape: its non-zero
#: pixels (a GeoTIFF's nodata value is not the shape either).
MASK_FOREGROUND = Foreground(ARRAY_FOREGROUND, "nonzero")


@dataclass(frozen=True, eq=False)
class Input:
    """An input, read: what the pruning needs, and what maps its answer back.

    Attributes
    ----------
    mask : (H, W) bool array
        The shape's pixels.
    frame : PixelFrame
        From pixel centres to the input's coordinates: a polygon's own units, or the
        identity for an image.
    foreground : Foreground
        What was taken as the shape (the foreground rule's outcome; ``polygon`` for a
        polygon).
    raster : PolygonRaster or None
        For a polygon: the polygon, the raster options that made the mask and what the
        raster does not hold as it is (``warnings``).
    labels : (H, W) int64 array or None
        For a label image (``labels=True``): every pixel's label, 0 the background;
        ``mask`` is ``labels != 0``.
    hint : str or None
        What the reader noticed and the caller may want to change (an image that looks
        like a label image read without ``labels``).
    pixel_size : float or None
        For an image: the side of a pixel in the caller's units, which the tables
        measure in (None: pixels).

    Examples
    --------
    >>> m = np.zeros((8, 8), bool); m[2:6, 2:6] = True
    >>> shape = Input(m)
    >>> shape.kind, shape.frame == IDENTITY, shape.foreground.shape
    ('image', True, 'nonzero')
    """

    mask: np.ndarray
    frame: PixelFrame = IDENTITY
    foreground: Foreground = MASK_FOREGROUND
    raster: PolygonRaster | None = None
    labels: np.ndarray | None = None
    hint: str | None = None
    pixel_size: float | None = None
    crs: str | None = None  # a GeoTIFF's CRS (a polygon's is its raster's)
    georeference: Georeference | None = None  # a GeoTIFF's grid on the map

    def __post_init__(self) -> None:
        mask = np.asarray(self.mask)
        if mask.ndim != 2:
            raise InvalidImageError(f"a mask must be 2-D, got shape {mask.shape}")
        object.__setattr__(self, "mask", np.ascontiguousarray(mask, dtype=bool))

    def components(self) -> list[tuple[np.ndarray, tuple[int, int], int | None]]:
        """Every 8-connected component as a padded crop, its origin in the image and its
        label (None unless a label image).

        A label image's components are each label's pieces, found inside the label's
        bounding box, so that the work follows the objects' sizes; pixels of another
        label are background to it. Order: by label, then as :func:`components8` finds
        them.

        Examples
        --------
        >>> lab = np.zeros((4, 6), np.int64); lab[1:3, 0:3] = 7; lab[1:3, 3:6] = 2
        >>> [(c.shape, o, v) for c, o, v in Input(lab != 0, labels=lab).components()]
        [((4, 5), (0, 2), 2), ((4, 5), (0, -1), 7)]
        """
        from ..grid import components8

        if self.labels is None:
            return [(crop, origin, None) for crop, origin in components8(self.mask)]
        from .foreground import label_boxes

        out: list[tuple[np.ndarray, tuple[int, int], int | None]] = []
        for v, box in label_boxes(self.labels):
            top, left = box[0].start, box[1].start
            own = self.labels[box] == v
            for crop, (r, c) in components8(own):
                out.append((crop, (r + top, c + left), v))
        return out

    @property
    def kind(self) -> Kind:
        return "image" if self.raster is None else "geojson"

    @property
    def warnings(self) -> list[dict[str, Any]]:
        """What the raster of a polygon does not hold as it is (empty for an image)."""
        return [] if self.raster is None else [w.to_dict() for w in self.raster.warnings]


def _table(source: Any) -> Mapping[str, Any]:
    """A GeoDataFrame or GeoSeries of one feature as GeoJSON with its CRS; a table of
    several is refused: each feature is its own shape (one raster would merge them)."""
    if len(source) != 1:
        raise InvalidPolygonError(
            f"a table of {len(source)} features: each is its own shape; prune them one by "
            "one, or all with skelprune.geo.centerlines(table)"
        )
    obj = dict(source.__geo_interface__)
    from .crs import crs_name  # not at import: it loads shapely

    name = crs_name(source.crs)
    if name is not None:
        obj["crs"] = {"type": "name", "properties": {"name": name}}
    return obj


def _guess(source: Any) -> tuple[Kind, Any]:
    """The kind of an input given without one, and the input as its reader takes it."""
    if isinstance(source, np.ndarray | bytes | bytearray | memoryview):
        return "image", source
    if (
        hasattr(source, "__geo_interface__")
        and hasattr(source, "crs")
        and hasattr(source, "geometry")
    ):  # a GeoDataFrame or GeoSeries
        return "geojson", _table(source)
    if isinstance(source, Mapping) or hasattr(source, "__geo_interface__"):
        return "geojson", source
    if isinstance(source, str) and source.lstrip().startswith("{"):
        return "geojson", source  # GeoJSON text
    if isinstance(source, str | os.PathLike):
        path = Path(source)
        if path.name.lower().endswith(GEOJSON_SUFFIXES):
            try:
                return "geojson", _geojson(path.read_bytes(), "a GeoJSON file")
            except OSError as exc:
                raise InvalidPolygonError(
                    f"cannot read {os.fspath(source)!r}: {exc.strerror}"
                ) from None
        return "image", path  # the image (or, when georeferenced, the GeoTIFF) reader opens it
    return "image", np.asarray(source)  # an array-like (nested lists)


def _geojson(source: Any, what: str = "GeoJSON text") -> Mapping[str, Any]:
    if isinstance(source, Mapping):
        return source
    if hasattr(source, "__geo_interface__"):  # shapely and the like
        return source.__geo_interface__
    if isinstance(source, str | bytes | bytearray | memoryview):
        try:
            obj = json.loads(bytes(source) if not isinstance(source, str) else source)
        except (ValueError, UnicodeDecodeError) as exc:
            raise InvalidPolygonError(f"not {what}: {exc}") from None
        if not isinstance(obj, dict):
            raise InvalidPolygonError("not a GeoJSON object")
        return obj
    raise InvalidPolygonError(f"expected a GeoJSON object, got {type(source).__name__}")


def read_input(
    source: Any,
    *,
    read: ReadOptions | None = None,
    raster: RasterOptions | None = None,
    kind: Kind | None = None,
    max_pixels: int | None = None,
    max_vertices: int | None = None,
) -> Input:
    """Read any input into an :class:`Input`.

    Parameters
    ----------
    source : array, bytes, str, os.PathLike, GeoJSON mapping, shapely geometry or Input
        An image array (``(H, W)``, or ``(H, W, C)`` with ``C`` in 1–4, 2 and 4 with
        alpha last), PNG bytes, a file's path (``.geojson`` and ``.json``: a GeoJSON
        polygon; a georeferenced TIFF (``.tif``, ``.tiff``): a GeoTIFF mask, its non-zero
        pixels mapped to its CRS's coordinates: :mod:`.geotiff`; anything else: a PNG or
        TIFF image, told by its first bytes), GeoJSON
        as a mapping or as text, or any object with ``__geo_interface__`` (a shapely
        (Multi)Polygon). GeoJSON is a ``Polygon``, ``MultiPolygon``, ``Feature`` or
        ``FeatureCollection``. An :class:`Input` is returned as it is.
    read : ReadOptions, optional
        Image input: which pixels are the shape. Default: the ``auto`` rule for a PNG,
        the non-zero pixels of an array (an array is a mask).
    raster : RasterOptions, optional
        Polygon input: how it becomes pixels (default: a pixel size fitted to it).
    kind : {"image", "geojson"}, optional
        What ``source`` is, when the caller knows: then it is data, never a file's path
        (image: PNG bytes or an array; geojson: a mapping, or text or bytes of JSON).
    max_pixels, max_vertices : int, optional
        Refuse images and rasters of more pixels than this (before decoding or
        allocating them), polygons of more positions.

    Returns
    -------
    Input

    Raises
    ------
    InvalidImageError, InvalidPolygonError, ImageTooLargeError, EmptyMaskError
        What the readers refuse, with the reason.

    Examples
    --------
    >>> img = np.full((6, 6), 255, np.uint8); img[2:4, 1:5] = 0   # black on white
    >>> shape = read_input(img, read=ReadOptions("auto"))
    >>> int(shape.mask.sum()), shape.foreground.shape
    (8, 'dark')

    A polygon, with the frame back to its own coordinates:

    >>> square = {"type": "Polygon",
    ...           "coordinates": [[[0, 0], [10, 0], [10, 10], [0, 10], [0, 0]]]}
    >>> shape = read_input(square, raster=RasterOptions(pixel_size=1.0))
    >>> shape.mask.shape, shape.frame.point(2, 2), shape.kind
    ((14, 14), (0.5, 9.5), 'geojson')
    """
    if isinstance(source, Input):
        return source
    data: tuple[type, ...] = (np.ndarray, bytes, bytearray, memoryview)
    if kind is None:
        kind, source = _guess(source)
        data = (*data, Path)  # a path given as such
    if kind == "geojson":
        from .polygon import read_polygon

        polygon = read_polygon(
            _geojson(source), raster, max_vertices=max_vertices, max_pixels=max_pixels
        )
        return Input(polygon.mask, polygon.frame, POLYGON_FOREGROUND, polygon)
    if kind != "image":
        raise ValueError(f"kind must be 'image' or 'geojson', got {kind!r}")
    if not isinstance(source, data):
        # never open a file by a name that came as data
        raise InvalidImageError(
            "image input must be PNG or TIFF bytes or an array, not a file name"
        )
    if (
        isinstance(source, Path)
        and source.name.lower().endswith(GEOTIFF_SUFFIXES)
        and is_georeferenced(source)
    ):
        from .geotiff import read_geotiff

        mask, frame, crs = read_geotiff(source, max_pixels=max_pixels)
        geo = Georeference.of_frame(frame, crs)
        return Input(mask, frame, MASK_FOREGROUND, crs=crs, georeference=geo)
    if isinstance(source, bytes | bytearray | memoryview):
        from .tiff import is_tiff

        if is_tiff(bytes(source[:4])):
            from .geotiff import geotiff_georeference, read_geotiff_bytes

            tags = geotiff_georeference(bytes(source))
            if tags is not None:  # a GeoTIFF sent as data: its map, as from a file
                mask, frame, crs = read_geotiff_bytes(bytes(source), tags, max_pixels)
                geo = Georeference.of_frame(frame, crs)  # as the file's reader records it
                return Input(mask, frame, MASK_FOREGROUND, crs=crs, georeference=geo)
    if read is None:
        read = ReadOptions(ARRAY_FOREGROUND) if isinstance(source, np.ndarray) else ReadOptions()
    values, alpha = _image_values(source, max_pixels)
    pixel_size = None if raster is None else raster.pixel_size
    return image_input(values, alpha, read, pixel_size)


def image_input(
    values: np.ndarray,
    alpha: np.ndarray | None,
    read: ReadOptions,
    pixel_size: float | None = None,
) -> Input:
    """The :class:`Input` of an image's values: its shape by the foreground rule (or its
    labels), cleaned as ``read`` says."""
    from .foreground import clean_labels, clean_mask, label_hint, label_values, select

    fill, least = read.fill_holes, read.min_area
    if read.labels:
        labels = label_values(values, alpha)
        if fill or least:
            labels = clean_labels(labels, fill, least)
        taken = Foreground(read.foreground, "labels", fill_holes=fill, min_area=least)
        return Input(labels != 0, IDENTITY, taken, labels=labels, pixel_size=pixel_size)
    mask, taken = select(values, read.foreground, alpha)
    if fill or least:
        mask = clean_mask(mask, fill, least)
        taken = replace(taken, fill_holes=fill, min_area=least)
    hint = label_hint(values, alpha)
    return Input(mask, IDENTITY, taken, hint=hint, pixel_size=pixel_size)


def _format(data: bytes) -> str:
    """The image format of a file's first bytes, or an error naming what is read."""
    from .gif import is_gif
    from .png import PNG_SIGNATURE
    from .tiff import is_tiff

    if data[:8] == PNG_SIGNATURE:
        return "PNG"
    if is_tiff(data):
        return "TIFF"
    if is_gif(data):
        return "GIF"
    known = {
        b"\xff\xd8\xff": "a JPEG image",
        b"GIF8": "a GIF image of a version not read (GIF87a and GIF89a are)",
        b"BM": "a BMP image",
        b"SQLite format 3": "an SQLite file (a GeoPackage?)",
        b"\x00\x00\x27\x0a": "a Shapefile",
        b"%PDF": "a PDF",
        b"PK\x03\x04": "a ZIP archive",
        # a volume: skelprune.prune, `skelprune prune` and the service read it, as a volume
        b"\x93NUMPY": "a NumPy .npy file: a volume, which skelprune.prune reads, not an image",
    }
    what = next((name for sig, name in known.items() if data.startswith(sig)), None)
    if what is None and data[4:8] == b"ftyp":
        what = "an HEIF/MP4 file"
    if what is None:
        what = "empty" if not data else "a format not recognised"
    raise InvalidImageError(
        f"not a PNG, TIFF or GIF file: none of their signatures ({what}); "
        f"images are read from {', '.join(IMAGE_FORMATS[:-1])} and {IMAGE_FORMATS[-1]} "
        "files, polygons from GeoJSON (.geojson, .json)"
    )


def check_image_size(data: bytes, max_pixels: int | None) -> tuple[int, int]:
    """A PNG's or TIFF's ``(width, height)`` from its header; refuses more than
    ``max_pixels`` pixels, and a file of another format, before anything is decoded."""
    data = bytes(data)
    kind = _format(data[:64])
    if kind == "PNG":
        from .png import check_png_size

        return check_png_size(data, max_pixels)
    if kind == "GIF":
        from .gif import gif_size

        return gif_size(data, max_pixels)
    from .tiff import tiff_size

    width, height = tiff_size(data)
    if max_pixels is not None and width * height > max_pixels:
        raise ImageTooLargeError(
            f"image has {width * height} pixels ({width}×{height}), the limit is {max_pixels}"
        )
    return width, height


def _image_values(source: Any, max_pixels: int | None) -> tuple[np.ndarray, np.ndarray | None]:
    """An image's values and its alpha (where it uses transparency), every format."""
    from . import png

    if isinstance(source, np.ndarray):
        values, alpha = png._array_values(source)
        if max_pixels is not None and values.shape[0] * values.shape[1] > max_pixels:
            raise ImageTooLargeError(
                f"image has {values.shape[0] * values.shape[1]} pixels "
                f"({values.shape[1]}×{values.shape[0]}), the limit is {max_pixels}"
            )
        return values, alpha
    if isinstance(source, Path):
        try:
            data = source.read_bytes()
        except OSError as exc:
            raise InvalidImageError(f"cannot read {os.fspath(source)!r}: {exc.strerror}") from None
    else:
        data = bytes(source)
    kind = _format(data)
    if kind == "TIFF":
        from .tiff import read_tiff

        return read_tiff(data, max_pixels=max_pixels), None
    if kind == "GIF":
        from .gif import read_gif

        return read_gif(data, max_pixels)
    return png.read_values(data, max_pixels)
