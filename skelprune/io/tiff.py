"""Decoding of TIFF files into image values, with PNG's hostile-input guarantees.

Single-image TIFFs of the kinds PNG holds: bilevel, 8/16/32-bit integers (unsigned or
signed), 32/64-bit floats, one to four samples (2 and 4: the last is alpha), in strips or
tiles, uncompressed, LZW, Deflate (Adobe or old-style) or PackBits, with or without a
horizontal predictor. Values are taken as stored, as ``tifffile`` reads them (a bilevel
image's set bits are 1, whatever its photometric interpretation; a palette image gives
its indices).

Before anything is decoded (docs/tables.md#tiff):

- the file must hold exactly one image: a multi-page or 3-D TIFF is refused, naming its
  page count;
- the size comes from the header and is checked against ``max_pixels``, and the bytes it
  decodes to (pixels × samples × bits) against :data:`MAX_DECODED_BYTES_PER_PIXEL` per
  allowed pixel;
- every strip or tile must lie inside the file, and must decode to the bytes the header
  promises for it: a strip that ends early is refused (400), one that inflates beyond
  its share (a compression bomb) is refused as soon as it passes it, without holding more
  than that share (413).

Codecs: Deflate uses the standard library's ``zlib``; LZW and PackBits need
``imagecodecs`` (imported for those files only), its output bounded by the header.
"""

from __future__ import annotations

import io
import os
import zlib
from typing import Any

import numpy as np

from ..errors import ImageTooLargeError, InvalidImageError

__all__ = [
    "COMPRESSIONS",
    "MAX_STACK_PAGES",
    "is_georeferenced",
    "is_tiff",
    "read_tiff",
    "read_tiff_stack",
    "tiff_pages",
    "tiff_size",
]

#: TIFF compression codes read, and their names.
COMPRESSIONS = {1: "none", 5: "LZW", 8: "Deflate", 32946: "Deflate", 32773: "PackBits"}
_SIGNATURES = (b"II*\x00", b"MM\x00*", b"II+\x00", b"MM\x00+")
#: Bits per sample read (1: bilevel).
_BITS = (1, 8, 16, 32, 64)
#: Decoded bytes allowed per allowed pixel (4 samples of 32 bits): with ``max_pixels``,
#: the most a TIFF may decode to.
MAX_DECODED_BYTES_PER_PIXEL = 16


def is_tiff(data: bytes) -> bool:
    """Whether ``data`` starts with a TIFF (or BigTIFF) signature."""
    return bytes(data[:4]) in _SIGNATURES


#: The GeoTIFF tags that place an image on a map (pixel scale, tie points, a
#: transformation matrix, the geo keys): a TIFF with any of them is read as a GeoTIFF.
GEO_TAGS = (33550, 33922, 34264, 34735)


def is_georeferenced(path: os.PathLike[str] | str) -> bool:
    """Whether the TIFF file at ``path`` carries a georeference (its first page's header
    only; a file that is not a readable TIFF is not).

    Examples
    --------
    >>> import tempfile, pathlib, tifffile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "plain.tif"
    >>> tifffile.imwrite(path, np.zeros((4, 4), np.uint8))
    >>> is_georeferenced(path)
    False
    """
    import tifffile

    try:
        with open(path, "rb") as f:  # opened once: the signature, then the header
            if not is_tiff(f.read(4)):
                return False
            f.seek(0)
            with tifffile.TiffFile(f) as tif:
                tags = tif.pages.first.tags
                return any(code in tags for code in GEO_TAGS)
    except Exception:  # a broken header: the image reader names what is wrong
        return False


def _page(data: bytes) -> Any:
    """The one page of a TIFF, its header parsed (nothing decoded)."""
    import tifffile

    try:
        tif = tifffile.TiffFile(io.BytesIO(data))
    except Exception as exc:  # tifffile raises many kinds on a broken header
        raise InvalidImageError(f"cannot read TIFF: {_plain(exc)}") from None
    with tif:
        try:
            n = len(tif.pages)
        except Exception as exc:
            raise InvalidImageError(f"corrupt TIFF: {_plain(exc)}") from None
        if n != 1:
            raise InvalidImageError(
                f"multi-page TIFF: {n} pages; an image is one page (a stack of pages is "
                "read as a volume, docs/volumes.md)"
            )
        page = tif.pages.first
        if getattr(page, "imagedepth", 1) != 1:
            raise InvalidImageError(
                f"3-D TIFF: 1 page of {page.imagedepth} slices; skelprune reads "
                "single-image 2-D TIFFs"
            )
        return page


def _plain(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return (text[0] if text else type(exc).__name__)[:200]


def tiff_size(data: bytes) -> tuple[int, int]:
    """``(width, height)`` of a single-image TIFF from its header, without decoding.

    Examples
    --------
    >>> import tifffile
    >>> buf = io.BytesIO(); tifffile.imwrite(buf, np.zeros((3, 5), np.uint8))
    >>> tiff_size(buf.getvalue())
    (5, 3)
    """
    page = _page(bytes(data))
    return int(page.imagewidth), int(page.imagelength)


def _segments(page: Any) -> tuple[int, list[int], int]:
    """Bytes of each strip or tile when whole, the fewest each must decode to (a last
    strip may stop at the image's end) and the number of segments expected."""
    spp = int(page.samplesperpixel)
    planes = spp if page.planarconfig == 2 else 1
    per_pixel = (spp // planes) * int(page.bitspersample)
    width, height = int(page.imagewidth), int(page.imagelength)
    if page.is_tiled:
        tw, tl = int(page.tilewidth), int(page.tilelength)
        full = tl * ((tw * per_pixel + 7) // 8)
        count = planes * (-(-width // tw)) * (-(-height // tl))
        return full, [full] * count, count
    rows = min(int(page.rowsperstrip or height), height)
    row_bytes = (width * per_pixel + 7) // 8
    strips = -(-height // rows)
    least = [min(rows, height - i * rows) * row_bytes for i in range(strips)] * planes
    return rows * row_bytes, least, strips * planes


def _decoded_length(codec: int, raw: bytes, limit: int) -> int:
    """Bytes a segment decodes to, counted up to ``limit + 1`` at most."""
    if codec == 1:
        return len(raw)
    if codec in (8, 32946):
        inflate = zlib.decompressobj()
        try:
            got = len(inflate.decompress(raw, limit + 1))
        except zlib.error:
            raise InvalidImageError("cannot decode TIFF: the Deflate data is corrupt") from None
        return got
    try:
        import imagecodecs
    except ImportError:  # pragma: no cover - a dependency; kept for a trimmed install
        raise InvalidImageError(
            f"{COMPRESSIONS[codec]} TIFFs need imagecodecs: pip install imagecodecs"
        ) from None
    decode = imagecodecs.packbits_decode if codec == 32773 else imagecodecs.lzw_decode
    try:
        return len(decode(raw, out=limit + 1))  # never more than limit + 1 bytes
    except Exception as exc:
        if "OUTPUT_TOO_SMALL" in str(exc):  # the decoder stopped at limit + 1
            return limit + 1
        raise InvalidImageError(
            f"cannot decode TIFF: the {COMPRESSIONS[codec]} data is corrupt"
        ) from None


def read_tiff(data: bytes, *, max_pixels: int | None = None) -> np.ndarray:
    """The values of a single-image TIFF: ``(H, W)`` or ``(H, W, C)``.

    Parameters
    ----------
    data : bytes
        The TIFF file.
    max_pixels : int, optional
        Refuse images of more pixels than this (from the header, before decoding), and of
        more than :data:`MAX_DECODED_BYTES_PER_PIXEL` decoded bytes for each.

    Raises
    ------
    InvalidImageError
        Not a TIFF, several pages or slices, a kind or compression not read, a strip
        outside the file or shorter than its share, corrupt compressed data.
    ImageTooLargeError
        More pixels than allowed, or a strip decoding to more than its share.

    Examples
    --------
    >>> import tifffile
    >>> img = np.zeros((4, 6), np.uint16); img[1:3, 2:5] = 40000
    >>> buf = io.BytesIO(); tifffile.imwrite(buf, img, compression="zlib")
    >>> v = read_tiff(buf.getvalue()); v.dtype, int(v.max()), v.shape
    (dtype('uint16'), 40000, (4, 6))
    """
    data = bytes(data)
    if not is_tiff(data):
        raise InvalidImageError("not a TIFF file: the TIFF signature is missing")
    return _decode_page(_page(data), data, max_pixels)


def _decode_page(page: Any, data: bytes, max_pixels: int | None) -> np.ndarray:
    """One page's values, its header checked against the file and the limits first."""
    width, height = int(page.imagewidth), int(page.imagelength)
    if width <= 0 or height <= 0:
        raise InvalidImageError(f"corrupt TIFF: invalid size {width}×{height}")
    if max_pixels is not None and width * height > max_pixels:
        raise ImageTooLargeError(
            f"image has {width * height} pixels ({width}×{height}), the limit is {max_pixels}"
        )
    spp, bits = int(page.samplesperpixel), int(page.bitspersample)
    if bits not in _BITS or not 1 <= spp <= 4 or (bits == 1 and spp != 1):
        raise InvalidImageError(
            f"TIFF of {spp} samples of {bits} bits is not read; skelprune reads bilevel, "
            "8/16/32-bit integer and 32/64-bit float TIFFs of 1 to 4 samples"
        )
    decoded = width * height * spp * bits // 8
    if max_pixels is not None and decoded > max_pixels * MAX_DECODED_BYTES_PER_PIXEL:
        raise ImageTooLargeError(
            f"image decodes to {decoded} bytes, the limit is "
            f"{max_pixels * MAX_DECODED_BYTES_PER_PIXEL}"
        )
    codec = int(page.compression)
    if codec not in COMPRESSIONS:
        raise InvalidImageError(
            f"TIFF compression {codec} is not read; skelprune reads uncompressed, LZW, "
            "Deflate and PackBits TIFFs"
        )
    full, least, count = _segments(page)
    offsets, counts = list(page.dataoffsets), list(page.databytecounts)
    if len(offsets) != count or len(counts) != count:
        raise InvalidImageError(
            f"corrupt TIFF: {len(offsets)} strips or tiles where its {width}×{height} "
            f"header needs {count}"
        )
    for i, (at, size) in enumerate(zip(offsets, counts, strict=True)):
        if at < 0 or size < 0 or at + size > len(data):
            raise InvalidImageError(
                f"truncated TIFF: strip {i} at byte {at} needs {size} bytes, the file has "
                f"{max(len(data) - at, 0)} left"
            )
        got = _decoded_length(codec, data[at : at + size], full)
        if got > full and codec != 1:
            raise ImageTooLargeError(
                f"TIFF strip {i} decodes to more than the {full} bytes its header allows "
                "(a compression bomb?)"
            )
        if got < least[i]:
            raise InvalidImageError(
                f"truncated TIFF: strip {i} holds {got} of the {least[i]} bytes its header promises"
            )
    try:
        values = page.asarray()
    except Exception as exc:  # the checks above leave only codec-level surprises
        raise InvalidImageError(f"cannot decode TIFF: {_plain(exc)}") from None
    values = np.asarray(values)
    axes = str(page.axes)
    if axes.startswith("S") and values.ndim == 3:  # planar: samples first
        values = np.moveaxis(values, 0, -1)
    values = values.reshape(height, width, -1)
    return values[..., 0] if values.shape[-1] == 1 else values


#: The most pages of a TIFF stack read as a volume.
MAX_STACK_PAGES = 4096


def tiff_pages(data: bytes) -> int:
    """Pages of a TIFF (slices of a single 3-D page counted as pages), from its header;
    0 for bytes that are not a readable TIFF.

    >>> import tifffile
    >>> buf = io.BytesIO()
    >>> tifffile.imwrite(buf, np.zeros((3, 4, 5), np.uint8), photometric="minisblack")
    >>> tiff_pages(buf.getvalue()), tiff_pages(b"not a tiff")
    (3, 0)
    """
    import tifffile

    if not is_tiff(bytes(data[:4])):
        return 0
    try:
        with tifffile.TiffFile(io.BytesIO(data)) as tif:
            n = len(tif.pages)
            return n if n > 1 else int(getattr(tif.pages.first, "imagedepth", 1))
    except Exception:  # a broken header: the readers say what is wrong
        return 0


def read_tiff_stack(data: bytes, *, max_voxels: int | None = None) -> np.ndarray:
    """The pages of a multi-page TIFF as a ``(pages, H, W)`` volume (each page's first
    sample), every page checked as :func:`read_tiff` checks its one page.

    Raises
    ------
    InvalidImageError
        Not a TIFF, pages of different sizes, more than :data:`MAX_STACK_PAGES` pages, or
        a page :func:`read_tiff` would refuse.
    ImageTooLargeError
        More voxels than ``max_voxels`` by the headers, before anything is decoded.

    Examples
    --------
    >>> import tifffile
    >>> vol = np.zeros((3, 4, 5), np.uint8); vol[1, 1:3, 1:4] = 1
    >>> buf = io.BytesIO()
    >>> tifffile.imwrite(buf, vol, photometric="minisblack", compression="zlib")
    >>> v = read_tiff_stack(buf.getvalue()); v.shape, int(v.sum())
    ((3, 4, 5), 6)
    """
    import tifffile

    data = bytes(data)
    if not is_tiff(data):
        raise InvalidImageError("not a TIFF file: the TIFF signature is missing")
    try:
        tif = tifffile.TiffFile(io.BytesIO(data))
    except Exception as exc:  # tifffile raises many kinds on a broken header
        raise InvalidImageError(f"cannot read TIFF: {_plain(exc)}") from None
    with tif:
        try:
            n = len(tif.pages)
            if n > MAX_STACK_PAGES:
                raise InvalidImageError(
                    f"TIFF stack of {n} pages; at most {MAX_STACK_PAGES} are read"
                )
            pages: list[Any] = [tif.pages[i] for i in range(n)]
        except InvalidImageError:
            raise
        except Exception as exc:
            raise InvalidImageError(f"corrupt TIFF: {_plain(exc)}") from None
        if n == 1 and getattr(pages[0], "imagedepth", 1) != 1:
            raise InvalidImageError("a 3-D TIFF page is not read; write one page a slice")
        sizes = {(int(p.imagelength), int(p.imagewidth)) for p in pages}
        if len(sizes) != 1:
            raise InvalidImageError(
                f"the TIFF stack's pages differ in size ({len(sizes)} sizes); a volume's "
                "slices are one size"
            )
        height, width = sizes.pop()
        if max_voxels is not None and n * height * width > max_voxels:
            raise ImageTooLargeError(
                f"the stack has {n * height * width} voxels ({n}×{height}×{width}), the "
                f"limit is {max_voxels}"
            )
        slices = []
        for page in pages:
            values = _decode_page(page, data, None)
            slices.append(values if values.ndim == 2 else values[..., 0])
    return np.stack(slices)
