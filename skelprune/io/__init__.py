"""Input: any input (PNG or TIFF file or bytes, array, GeoJSON, shapely geometry,
GeoTIFF) read into one :class:`Input` by :func:`read_input`: the mask, the
:class:`PixelFrame` back to the input's coordinates and the :class:`Foreground` taken as
the shape.

The first stage of the pipeline (input → medial axis → graph → pruning → metrics →
output). The readers below it are reached through their modules: :mod:`.png`
(``read_mask``, ``read_shape``, ``png_size``: PNG files and arrays, taking as the shape
what :mod:`.foreground`'s rule says), :mod:`.tiff`, :mod:`.geotiff`, :mod:`.polygon`
(``polygon_mask``, ``polygon_raster``: GeoJSON polygons rasterised, with the topology
check's warnings; :mod:`.fit` fits the pixel size) and :mod:`.frame`.

The names are imported when first used: the pipeline needs the frame and the foreground
rules, not the polygon machinery (shapely, OpenCV).
"""

from typing import TYPE_CHECKING

from .._lazy import lazy_exports

if TYPE_CHECKING:
    from .foreground import Foreground
    from .frame import PixelFrame
    from .input import Input, read_input

_LAZY = {
    "Foreground": "foreground",
    "PixelFrame": "frame",
    "Input": "input",
    "read_input": "input",
}


__getattr__, __dir__ = lazy_exports(__name__, _LAZY)


__all__ = ["Foreground", "Input", "PixelFrame", "read_input"]
