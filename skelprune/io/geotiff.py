"""GeoTIFF masks (a segmentation model's output): the mask, and the frame and CRS that
put the answer back on the map.

The first band is read; the shape is its non-zero pixels that are not the band's
``nodata`` value. The raster must be north-up with square pixels (no rotation or shear:
the frame maps a pixel to the map by one size and one origin), as segmentation masks
on a map grid are.

Two readers, one answer: a file (:func:`read_geotiff`) is read with rasterio (the ``geo``
extra: anything GDAL reads, any CRS); bytes (:func:`read_geotiff_bytes`, what the
service receives) are decoded by the hostile-input TIFF reader (:mod:`.tiff`) and their
georeference taken from the GeoTIFF tags (the model tie point and pixel scale, or the
model transformation; the CRS's EPSG code; GDAL's nodata tag), so that no untrusted
bytes reach GDAL.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InvalidImageError, SkelpruneError
from .frame import PixelFrame
from .tiff_ifd import TiffPage

#: File name endings read as GeoTIFF masks (any case).
GEOTIFF_SUFFIXES = (".tif", ".tiff")

__all__ = [
    "GEOTIFF_SUFFIXES",
    "Georeference",
    "geo_keys",
    "geotiff_georeference",
    "read_geotiff",
    "read_geotiff_bytes",
]


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


@dataclass(frozen=True)
class Georeference:
    """Where a GeoTIFF's pixels lie: the affine ``transform`` from a pixel's corner
    ``(col, row)`` to map coordinates, as GDAL and rasterio write it
    ``(a, b, c, d, e, f)``: ``x = a·col + b·row + c``, ``y = d·col + e·row + f``, the CRS
    name (``EPSG:…``) and the band's nodata value (None: none)."""

    transform: tuple[float, float, float, float, float, float]
    crs: str | None
    nodata: float | None = None

    @classmethod
    def of_frame(cls, frame: PixelFrame, crs: str | None) -> Georeference:
        """The north-up grid of a GeoTIFF's frame (pixel centres on the map).

        >>> Georeference.of_frame(PixelFrame(5.0, 95.0, 10.0, flip_y=True), None).transform
        (10.0, 0.0, 0.0, 0.0, -10.0, 100.0)
        """
        a = frame.pixel_size
        return cls((a, 0.0, frame.x0 - 0.5 * a, 0.0, -a, frame.y0 + 0.5 * a), crs)

    def frame(self) -> PixelFrame:
        """The frame from pixel centres to the map; a rotated, sheared, south-up or
        non-square grid is refused."""
        a, b, c, d, e, f = self.transform
        if b != 0 or d != 0 or e >= 0 or not np.isclose(a, -e, rtol=1e-9):
            raise InvalidImageError(
                "the GeoTIFF is not north-up with square pixels (its transform is "
                f"{self.transform}); warp it to a map grid first"
            )
        # pixel (col, row)'s centre is the transform of (col + 0.5, row + 0.5)
        return PixelFrame(x0=c + 0.5 * a, y0=f + 0.5 * e, pixel_size=a, flip_y=True)

    def to_dict(self) -> dict[str, Any]:
        """What a document records of it (``georeference``)."""
        return {"crs": self.crs, "transform": list(self.transform)}


#: GeoKeys read: the model type, the raster type, and those that name the CRS by its
#: EPSG code (projected first); the value GeoTIFF uses for a user-defined one.
_MODEL_TYPE, _RASTER_TYPE = 1024, 1025
_CRS_KEYS = (3072, 2048)  # ProjectedCSTypeGeoKey, GeographicTypeGeoKey
_USER_DEFINED = 32767
_GEOCENTRIC = 3
_KEY_DIRECTORY, _DOUBLES, _ASCII = 34735, 34736, 34737


def geotiff_georeference(data: bytes) -> Georeference | None:
    """The georeference of a TIFF's bytes, from its header (nothing decoded), or None
    for a TIFF without GeoTIFF tags.

    Raises
    ------
    InvalidImageError
        GeoTIFF tags that give no grid (no tie point and scale, nor a transformation), a
        tag or GeoKey of another type or count than GeoTIFF writes, a geocentric model,
        or a CRS that is not an EPSG code pyproj knows (when pyproj is installed).

    Examples
    --------
    >>> import io, tifffile
    >>> buf = io.BytesIO()
    >>> tifffile.imwrite(buf, np.zeros((4, 6), np.uint8), extratags=[
    ...     (33550, 12, 3, (10.0, 10.0, 0.0)), (33922, 12, 6, (0, 0, 0, 5e5, 6.6e6, 0)),
    ...     (34735, 3, 8, (1, 1, 0, 1, 3072, 0, 1, 32633))])
    >>> geo = geotiff_georeference(buf.getvalue())
    >>> geo.crs, geo.transform
    ('EPSG:32633', (10.0, 0.0, 500000.0, 0.0, -10.0, 6600000.0))
    """
    from .tiff import GEO_TAGS, _page

    page = _page(data).page
    if not any(code in page for code in GEO_TAGS):
        return None
    keys = geo_keys(page)
    if keys.get(_MODEL_TYPE) == _GEOCENTRIC:
        raise InvalidImageError(
            "the GeoTIFF's model is geocentric (x, y, z from the Earth's centre); a mask "
            "lies on a map grid: a projected or geographic CRS"
        )
    transform = _transform(page, keys.get(_RASTER_TYPE, 1) == 2)
    crs_code = next((keys[k] for k in _CRS_KEYS if k in keys), None)
    crs: str | None = None
    if crs_code is not None:
        if crs_code == _USER_DEFINED:
            raise InvalidImageError(
                "the GeoTIFF's CRS is user-defined (no EPSG code); reproject it to a CRS "
                "with an EPSG code, or read the file from disk"
            )
        crs = _epsg(crs_code)
    nodata = None
    if 42113 in page:  # GDAL_NODATA: the value as ASCII
        try:
            nodata = float(page.text(42113).strip())
        except ValueError:
            raise InvalidImageError("the GeoTIFF's nodata tag is not a number") from None
    return Georeference(transform, crs, nodata)


def _epsg(code: int) -> str:
    """``EPSG:code``, refused when it is no CRS (0, a code pyproj does not know) or a
    vertical or geocentric one."""
    from .crs import check_crs, has_pyproj

    name = f"EPSG:{code}"
    if code == 0:
        raise InvalidImageError("the GeoTIFF's CRS code is 0, which names no CRS")
    if has_pyproj():
        try:
            check_crs(name, "the GeoTIFF's CRS")
        except SkelpruneError as exc:
            raise InvalidImageError(str(exc)) from None
    return name


def geo_keys(page: TiffPage) -> dict[int, int]:
    """The GeoKeys a GeoTIFF's page holds as one SHORT each (the model, raster and CRS
    keys; other keys are not read).

    Raises
    ------
    InvalidImageError
        A key directory that is not SHORTs, shorter than its header says, or a key read
        here stored as doubles or text, or with other than one value.
    """
    if _KEY_DIRECTORY not in page:
        return {}
    shorts = page.values(_KEY_DIRECTORY, (3,))
    if shorts.size < 4 or shorts.size < 4 + 4 * int(shorts[3]):
        raise InvalidImageError(
            f"the GeoTIFF's key directory holds {shorts.size} values, fewer than its header says"
        )
    keys: dict[int, int] = {}
    for k in range(int(shorts[3])):
        key, where, count, value = (int(v) for v in shorts[4 + 4 * k : 8 + 4 * k])
        if key not in (_MODEL_TYPE, _RASTER_TYPE, *_CRS_KEYS):
            continue
        if where != 0 or count != 1:
            stored = {_DOUBLES: "doubles", _ASCII: "text"}.get(where, f"tag {where}")
            raise InvalidImageError(
                f"the GeoTIFF's GeoKey {key} is stored as {count} {stored}; GeoTIFF writes "
                "it as one SHORT"
            )
        keys[key] = value
    return keys


def _transform(
    page: TiffPage, pixel_is_point: bool
) -> tuple[float, float, float, float, float, float]:
    if 34264 in page:
        m = page.values(34264, (12,), 16).astype(float)
        t = (m[0], m[1], m[3], m[4], m[5], m[7])
    else:
        if 33550 not in page or 33922 not in page:
            raise InvalidImageError(
                "the GeoTIFF has no grid: neither a tie point with a pixel scale nor a "
                "model transformation"
            )
        scale = page.values(33550, (12,), 3)
        tie = page.values(33922, (12,))
        if tie.size < 6 or tie.size % 6:
            raise InvalidImageError(
                f"the GeoTIFF's ModelTiepoint holds {tie.size} values; a tie point is 6"
            )
        sx, sy = float(scale[0]), float(scale[1])
        i, j, x, y = float(tie[0]), float(tie[1]), float(tie[3]), float(tie[4])
        t = (sx, 0.0, x - i * sx, 0.0, -sy, y + j * sy)
    if pixel_is_point:  # PixelIsPoint: the tie is a centre
        t = (t[0], t[1], t[2] - 0.5 * t[0], t[3], t[4], t[5] - 0.5 * t[4])
    with np.errstate(all="ignore"):
        values = tuple(float(v) for v in t)
    if not all(np.isfinite(values)):
        raise InvalidImageError("the GeoTIFF's transform is not finite")
    from ..options_checks import SCALE_RANGE

    low, high = SCALE_RANGE
    if not all(low <= abs(v) <= high for v in (values[0], values[4])):
        raise InvalidImageError(
            f"the GeoTIFF's pixel size {values[0]:g} × {-values[4]:g} is outside {low:g} to "
            f"{high:g}: lengths and areas in it would not be finite"
        )
    return values  # type: ignore[return-value]


def read_geotiff_bytes(
    data: bytes, georeference: Georeference, max_pixels: int | None = None
) -> tuple[np.ndarray, PixelFrame, str | None]:
    """:func:`read_geotiff` of a GeoTIFF's bytes: the mask, the frame and the CRS name;
    the pixels decoded by :func:`~skelprune.io.tiff.read_tiff` (its limits and checks).

    Examples
    --------
    >>> import io, tifffile
    >>> buf = io.BytesIO(); m = np.zeros((4, 6), np.uint8); m[1:3, 1:5] = 1
    >>> tifffile.imwrite(buf, m, extratags=[
    ...     (33550, 12, 3, (10.0, 10.0, 0.0)), (33922, 12, 6, (0, 0, 0, 5e5, 6.6e6, 0)),
    ...     (34735, 3, 8, (1, 1, 0, 1, 3072, 0, 1, 32633))])
    >>> data = buf.getvalue()
    >>> mask, frame, crs = read_geotiff_bytes(data, geotiff_georeference(data))
    >>> int(mask.sum()), frame.point(0, 0), crs
    (8, (500005.0, 6599995.0), 'EPSG:32633')
    """
    from .tiff import read_tiff

    frame = georeference.frame()
    values = read_tiff(data, max_pixels=max_pixels)
    band = values if values.ndim == 2 else values[..., 0]  # the first band
    mask = band != 0
    nodata = georeference.nodata
    if nodata is not None and not np.isnan(nodata):
        mask &= band != nodata
    return mask, frame, georeference.crs
