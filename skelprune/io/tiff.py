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

import contextlib
import io
import mmap
import os
import zlib
from collections.abc import Iterator
from typing import Any

import numpy as np

from ..errors import ImageTooLargeError, InvalidImageError, SkelpruneError
from .tiff_ifd import BITS, Layout, page_layout, read_structure

__all__ = [
    "COMPRESSIONS",
    "MAX_STACK_PAGES",
    "is_georeferenced",
    "is_tiff",
    "read_tiff",
    "read_tiff_stack",
    "stack_layouts",
    "tiff_pages",
    "tiff_size",
]

#: TIFF compression codes read, and their names.
COMPRESSIONS = {1: "none", 5: "LZW", 8: "Deflate", 32946: "Deflate", 32773: "PackBits"}
_SIGNATURES = (b"II*\x00", b"MM\x00*", b"II+\x00", b"MM\x00+")
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
    try:
        with open(path, "rb") as f, mapped(f) as data:
            if not is_tiff(data[:4]):
                return False
            first = read_structure(data, 1).pages[0]
            return any(code in first for code in GEO_TAGS)
    except (OSError, ValueError, IndexError, SkelpruneError):  # the reader names it
        return False


@contextlib.contextmanager
def mapped(f: Any) -> Iterator[Any]:
    """A file's bytes, mapped (empty bytes for an empty file)."""
    if os.fstat(f.fileno()).st_size == 0:
        yield b""
        return
    with mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as m:
        yield m


def _page(data: bytes) -> Layout:
    """The one page of a TIFF, its structure read by the bounded walker and its tags
    checked (nothing decoded)."""
    structure = read_structure(data, MAX_STACK_PAGES)
    n = len(structure.pages)
    if n != 1:
        counted = f"more than {n}" if structure.more else str(n)
        raise InvalidImageError(
            f"multi-page TIFF: {counted} pages; an image is one page (a stack of pages is "
            "read as a volume, docs/volumes.md)"
        )
    page = page_layout(structure.pages[0])
    if page.depth != 1:
        raise InvalidImageError(
            f"3-D TIFF: 1 page of {page.depth} slices; skelprune reads single-image 2-D TIFFs"
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
    page = _page(data)
    return page.width, page.height


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


def _decode_page(page: Layout, data: bytes, max_pixels: int | None, tif: Any = None) -> np.ndarray:
    """One page's values, its header checked against the file and the limits first
    (``tif``: the file open in tifffile, for the pages of a stack)."""
    width, height = page.width, page.height
    if max_pixels is not None and width * height > max_pixels:
        raise ImageTooLargeError(
            f"image has {width * height} pixels ({width}×{height}), the limit is {max_pixels}"
        )
    spp, bits = page.samples, page.bits
    if bits not in BITS or not 1 <= spp <= 4 or (bits == 1 and spp != 1):
        raise InvalidImageError(
            f"TIFF of {spp} samples of {bits} bits is not read; skelprune reads bilevel, "
            "8/16/32-bit integer and 32/64-bit float TIFFs of 1 to 4 samples"
        )
    decoded = page.decoded_bytes
    if max_pixels is not None and decoded > max_pixels * MAX_DECODED_BYTES_PER_PIXEL:
        raise ImageTooLargeError(
            f"image decodes to {decoded} bytes, the limit is "
            f"{max_pixels * MAX_DECODED_BYTES_PER_PIXEL}"
        )
    codec = page.compression
    if codec not in COMPRESSIONS:
        raise InvalidImageError(
            f"TIFF compression {codec} is not read; skelprune reads uncompressed, LZW, "
            "Deflate and PackBits TIFFs"
        )
    full, least = page.segments()
    count = len(least)
    offsets, counts = page.offsets.tolist(), page.counts.tolist()
    if len(offsets) != count:
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
    try:  # the chain and the tags checked: tifffile walks no further than this page
        if tif is None:
            with _tifffile(data) as one:
                values, axes = _values(one, page.index)
        else:
            values, axes = _values(tif, page.index)
    except Exception as exc:  # the checks above leave only codec-level surprises
        raise InvalidImageError(f"cannot decode TIFF: {_plain(exc)}") from None
    if axes.startswith("S") and values.ndim == 3:  # planar: samples first
        values = np.moveaxis(values, 0, -1)
    values = values.reshape(height, width, -1)
    return values[..., 0] if values.shape[-1] == 1 else values


#: The most pages of a TIFF stack read as a volume.
MAX_STACK_PAGES = 4096


def _tifffile(data: bytes) -> Any:
    import tifffile

    return tifffile.TiffFile(io.BytesIO(data))


def _values(tif: Any, index: int) -> tuple[np.ndarray, str]:
    tpage = tif.pages[index]
    return np.asarray(tpage.asarray()), str(tpage.axes)


def tiff_pages(data: bytes) -> int:
    """Pages of a TIFF (slices of a single 3-D page counted as pages), from its header
    read by the bounded walker (:data:`MAX_STACK_PAGES` + 1 for more); 0 for bytes that
    are not a readable TIFF.

    >>> import tifffile
    >>> buf = io.BytesIO()
    >>> tifffile.imwrite(buf, np.zeros((3, 4, 5), np.uint8), photometric="minisblack")
    >>> tiff_pages(buf.getvalue()), tiff_pages(b"not a tiff")
    (3, 0)
    """
    if not is_tiff(bytes(data[:4])):
        return 0
    try:
        structure = read_structure(data, MAX_STACK_PAGES + 1)
        n = len(structure.pages)
        return n if n != 1 else page_layout(structure.pages[0]).depth
    except SkelpruneError:  # a broken header: the readers say what is wrong
        return 0


def stack_layouts(data: Any) -> list[Layout]:
    """The checked layouts of a TIFF stack's pages (one size, at most
    :data:`MAX_STACK_PAGES`), read by the bounded walker.

    Raises
    ------
    InvalidImageError
        Not a TIFF, a broken structure or tag, more pages than allowed, a 3-D page, or
        pages of different sizes.
    """
    structure = read_structure(data, MAX_STACK_PAGES)
    if structure.more:
        raise InvalidImageError(
            f"TIFF stack of more than {MAX_STACK_PAGES} pages; at most {MAX_STACK_PAGES} are read"
        )
    pages = [page_layout(p) for p in structure.pages]
    if any(p.depth != 1 for p in pages):
        raise InvalidImageError("a 3-D TIFF page is not read; write one page a slice")
    sizes = {(p.height, p.width) for p in pages}
    if len(sizes) != 1:
        raise InvalidImageError(
            f"the TIFF stack's pages differ in size ({len(sizes)} sizes); a volume's "
            "slices are one size"
        )
    return pages


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
    data = bytes(data)
    pages = stack_layouts(data)
    n, height, width = len(pages), pages[0].height, pages[0].width
    if max_voxels is not None and n * height * width > max_voxels:
        raise ImageTooLargeError(
            f"the stack has {n * height * width} voxels ({n}×{height}×{width}), the "
            f"limit is {max_voxels}"
        )
    slices = []
    try:
        tif = _tifffile(data)
    except Exception as exc:  # tifffile raises many kinds on a broken header
        raise InvalidImageError(f"cannot read TIFF: {_plain(exc)}") from None
    with tif:
        for page in pages:
            values = _decode_page(page, data, None, tif)
            slices.append(values if values.ndim == 2 else values[..., 0])
    return np.stack(slices)
