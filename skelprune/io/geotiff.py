"""GeoTIFF masks (a segmentation model's output): the mask, and the frame and CRS that
put the answer back on the map (rasterio, the ``geo`` extra).

The first band is read; the shape is its non-zero pixels that are not the band's
``nodata`` value. The raster must be north-up with square pixels (no rotation or shear:
the frame maps a pixel to the map by one size and one origin), as segmentation masks
on a map grid are.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from ..errors import InvalidImageError
from .frame import PixelFrame

#: File name endings read as GeoTIFF masks (any case).
GEOTIFF_SUFFIXES = (".tif", ".tiff")

__all__ = ["GEOTIFF_SUFFIXES", "read_geotiff"]


def read_geotiff(
    path: str | os.PathLike[str], max_pixels: int | None = None
) -> tuple[np.ndarray, PixelFrame, str | None]:
    """The mask, the frame from pixel centres to map coordinates, and the CRS name.

    Examples
    --------
    >>> import rasterio, tempfile, pathlib
    >>> from rasterio.transform import from_origin
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "mask.tif"
    >>> m = np.zeros((4, 6), np.uint8); m[1:3, 1:5] = 1
    >>> with rasterio.open(path, "w", driver="GTiff", width=6, height=4, count=1,
    ...                    dtype="uint8", crs="EPSG:32633",
    ...                    transform=from_origin(500000, 6600000, 10, 10)) as f:
    ...     f.write(m, 1)
    >>> mask, frame, crs = read_geotiff(path)
    >>> int(mask.sum()), frame.point(0, 0), crs
    (8, (500005.0, 6599995.0), 'EPSG:32633')
    """
    try:
        import rasterio
    except ImportError:  # pragma: no cover - the geo extra installs it
        raise InvalidImageError(
            "a GeoTIFF needs rasterio: install skelprune[geo] (pip install 'skelprune[geo]')"
        ) from None
    try:
        with rasterio.open(path) as src:
            if max_pixels is not None and src.width * src.height > max_pixels:
                raise InvalidImageError(
                    f"GeoTIFF of {src.width}×{src.height} pixels exceeds the limit of {max_pixels}"
                )
            t = src.transform
            if t.b != 0 or t.d != 0 or t.e >= 0 or not np.isclose(t.a, -t.e, rtol=1e-9):
                raise InvalidImageError(
                    "the GeoTIFF is not north-up with square pixels (its transform is "
                    f"{tuple(t)[:6]}); warp it to a map grid first"
                )
            band = src.read(1)
            nodata = src.nodata
            crs: Any = src.crs
    except rasterio.errors.RasterioIOError as exc:
        raise InvalidImageError(f"cannot read {os.fspath(path)!r}: {exc}") from None
    mask = band != 0
    if nodata is not None and not np.isnan(nodata):
        mask &= band != nodata
    # pixel (col, row)'s centre is the transform of (col + 0.5, row + 0.5)
    frame = PixelFrame(x0=t.c + 0.5 * t.a, y0=t.f + 0.5 * t.e, pixel_size=t.a, flip_y=True)
    from .crs import crs_name  # shapely, which crs imports, only when a GeoTIFF is read

    return mask, frame, crs_name(crs)
