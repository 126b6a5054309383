"""Input: PNG masks and GeoJSON polygons to boolean masks, and the pixel frame.

The first stage of the pipeline (input → medial axis → graph → pruning → metrics →
output). :func:`read_input` reads any input (PNG, array, GeoJSON, shapely geometry)
into one :class:`Input`: the mask, the frame back to the input's coordinates and what was
taken as the shape. Below it, :func:`read_mask` / :func:`read_shape` decode PNG files and
arrays (:mod:`.png`), taking as the shape what :mod:`.foreground`'s rule says,
:func:`polygon_mask` rasterises GeoJSON polygons (:mod:`.polygon`; :func:`polygon_raster`
keeps the polygon and the topology check's warnings, :mod:`.fit` fits the pixel size), and
:class:`PixelFrame` maps pixel results back to the polygon's coordinates (:mod:`.frame`).

The names are imported when first used: the pipeline needs the frame and the foreground
rules, not the polygon machinery (shapely, OpenCV).
"""

from typing import TYPE_CHECKING

from .._lazy import lazy_exports

if TYPE_CHECKING:
    from .foreground import Foreground
    from .frame import IDENTITY, PixelFrame
    from .input import GEOJSON_SUFFIXES, Input, read_input
    from .png import PNG_SIGNATURE, check_png_size, png_size, read_mask, read_shape
    from .polygon import (
        DEFAULT_LONGEST_SIDE,
        PolygonRaster,
        parse_geojson,
        polygon_mask,
        polygon_raster,
        rasterize,
    )

_LAZY = {
    "Foreground": "foreground",
    "IDENTITY": "frame",
    "PixelFrame": "frame",
    "GEOJSON_SUFFIXES": "input",
    "Input": "input",
    "read_input": "input",
    "PNG_SIGNATURE": "png",
    "check_png_size": "png",
    "png_size": "png",
    "read_mask": "png",
    "read_shape": "png",
    "DEFAULT_LONGEST_SIDE": "polygon",
    "PolygonRaster": "polygon",
    "polygon_raster": "polygon",
    "parse_geojson": "polygon",
    "polygon_mask": "polygon",
    "rasterize": "polygon",
}


__getattr__, __dir__ = lazy_exports(__name__, _LAZY)


__all__ = [
    "DEFAULT_LONGEST_SIDE",
    "GEOJSON_SUFFIXES",
    "IDENTITY",
    "PNG_SIGNATURE",
    "Foreground",
    "Input",
    "PixelFrame",
    "PolygonRaster",
    "check_png_size",
    "parse_geojson",
    "png_size",
    "polygon_mask",
    "polygon_raster",
    "rasterize",
    "read_input",
    "read_mask",
    "read_shape",
]
