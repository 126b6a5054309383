"""A TIFF's structure read by a bounded walker: its pages (the IFD chain) and their tags,
every tag the readers use checked for its type and count, before any other code (the
decoder included) looks at the file.

A TIFF's pages are a chain of offsets that a file can make loop back, or make millions
long in a few megabytes (an empty page is six bytes). The walker follows the chain with
a set of the offsets seen (a loop is refused, naming the page it goes back to), stops
after ``max_pages`` pages, and reads at most :data:`MAX_IFD_BYTES` bytes of directory
entries in all, so that its time and memory are bounded by its budget whatever the file
says. A tag's values are read only when asked for, each within the file.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import ImageTooLargeError, InvalidImageError

__all__ = [
    "MAX_IFD_BYTES",
    "Layout",
    "TiffPage",
    "TiffStructure",
    "page_layout",
    "read_structure",
]

#: Bytes of directory entries read in all, over every page (4096 pages of 64 tags of a
#: BigTIFF: 5 MiB): past it the file is refused, however few pages it has.
MAX_IFD_BYTES = 8 << 20
#: Bytes a TIFF field type takes per value, and its name.
TYPES: dict[int, tuple[int, str]] = {
    1: (1, "BYTE"),
    2: (1, "ASCII"),
    3: (2, "SHORT"),
    4: (4, "LONG"),
    5: (8, "RATIONAL"),
    6: (1, "SBYTE"),
    7: (1, "UNDEFINED"),
    8: (2, "SSHORT"),
    9: (4, "SLONG"),
    10: (8, "SRATIONAL"),
    11: (4, "FLOAT"),
    12: (8, "DOUBLE"),
    13: (4, "IFD"),
    16: (8, "LONG8"),
    17: (8, "SLONG8"),
    18: (8, "IFD8"),
}
_NUMPY = {
    1: "u1",
    3: "u2",
    4: "u4",
    6: "i1",
    7: "u1",
    8: "i2",
    9: "i4",
    11: "f4",
    12: "f8",
    13: "u4",
    16: "u8",
    17: "i8",
    18: "u8",
}
#: Integer types, unsigned: what sizes, offsets and codes are written as.
UNSIGNED = (1, 3, 4, 16)
#: Tag names, for the messages.
NAMES = {
    256: "ImageWidth",
    257: "ImageLength",
    258: "BitsPerSample",
    259: "Compression",
    262: "PhotometricInterpretation",
    273: "StripOffsets",
    274: "Orientation",
    277: "SamplesPerPixel",
    278: "RowsPerStrip",
    279: "StripByteCounts",
    284: "PlanarConfiguration",
    317: "Predictor",
    322: "TileWidth",
    323: "TileLength",
    324: "TileOffsets",
    325: "TileByteCounts",
    339: "SampleFormat",
    32997: "ImageDepth",
    33550: "ModelPixelScale",
    33922: "ModelTiepoint",
    34264: "ModelTransformation",
    34735: "GeoKeyDirectory",
    34736: "GeoDoubleParams",
    34737: "GeoAsciiParams",
    42113: "GDAL_NODATA",
}


def tag_name(code: int) -> str:
    """A tag's name (its number if the readers do not use it)."""
    return NAMES.get(code, f"tag {code}")


@dataclass(frozen=True)
class Entry:
    """One directory entry: the tag's type, its count and where its values lie."""

    type: int
    count: int
    at: int  # offset of the values in the file


@dataclass(frozen=True)
class TiffPage:
    """One page (IFD) of a TIFF: its entries, their values read on demand."""

    index: int
    entries: dict[int, Entry]
    data: Any  # the file's bytes
    order: str  # "<" or ">"

    def __contains__(self, code: int) -> bool:
        return code in self.entries

    def values(self, code: int, types: tuple[int, ...], count: int | None = None) -> np.ndarray:
        """The values of tag ``code`` (``types`` allowed, ``count`` values if given).

        Raises
        ------
        InvalidImageError
            Naming the tag, its type or count, when they are not what the readers take.
        """
        e = self.entries[code]
        if e.type not in types:
            allowed = " or ".join(TYPES[t][1] for t in types)
            raise InvalidImageError(
                f"corrupt TIFF: page {self.index}'s {tag_name(code)} is of type "
                f"{TYPES.get(e.type, (0, str(e.type)))[1]}; it must be {allowed}"
            )
        if count is not None and e.count != count:
            raise InvalidImageError(
                f"corrupt TIFF: page {self.index}'s {tag_name(code)} holds {e.count} values; "
                f"it must hold {count}"
            )
        if e.type == 2:
            return np.frombuffer(self.data, "u1", e.count, e.at)
        if e.type in (5, 10):
            pairs = np.frombuffer(
                self.data, self.order + ("u4" if e.type == 5 else "i4"), 2 * e.count, e.at
            )
            return pairs[0::2] / np.where(pairs[1::2] == 0, np.nan, pairs[1::2])
        return np.frombuffer(self.data, self.order + _NUMPY[e.type], e.count, e.at)

    def one(self, code: int, default: int | None = None, least: int = 0) -> int:
        """The one unsigned integer of tag ``code`` (``default`` when absent), at least
        ``least``.

        Raises
        ------
        InvalidImageError
            Absent without a default, of another type or count, or below ``least``.
        """
        if code not in self.entries:
            if default is None:
                raise InvalidImageError(
                    f"corrupt TIFF: page {self.index} has no {tag_name(code)} tag"
                )
            return default
        value = int(self.values(code, UNSIGNED, 1)[0])
        if value < least:
            raise InvalidImageError(
                f"corrupt TIFF: page {self.index}'s {tag_name(code)} is {value}; it must be "
                f"at least {least}"
            )
        return value

    def text(self, code: int) -> str:
        """Tag ``code``'s ASCII value, up to its first NUL."""
        raw = bytes(self.values(code, (2,)))
        return raw.split(b"\x00", 1)[0].decode("latin-1")


@dataclass(frozen=True)
class TiffStructure:
    """A TIFF's pages, as far as the walk went."""

    pages: list[TiffPage]
    big: bool  # a BigTIFF
    more: bool  # the chain goes on past the pages read


_HEADERS = {b"II*\x00": ("<", False), b"MM\x00*": (">", False)}
_HEADERS.update({b"II+\x00": ("<", True), b"MM\x00+": (">", True)})


def read_structure(data: Any, max_pages: int) -> TiffStructure:
    """The pages of a TIFF's bytes, at most ``max_pages`` (``more`` says whether the
    chain goes on), each directory inside the file.

    Raises
    ------
    InvalidImageError
        Not a TIFF; a directory or a tag's values outside the file; a tag of an unknown
        type; a page chain that loops; more than :data:`MAX_IFD_BYTES` of directories.

    >>> import io, tifffile
    >>> buf = io.BytesIO()
    >>> tifffile.imwrite(buf, np.zeros((3, 4, 5), np.uint8), photometric="minisblack")
    >>> s = read_structure(buf.getvalue(), 10); len(s.pages), s.more
    (3, False)
    """
    size = len(data)
    head = bytes(data[:4])
    if head not in _HEADERS:
        raise InvalidImageError("not a TIFF file: the TIFF signature is missing")
    order, big = _HEADERS[head]
    if big:
        if size < 16:
            raise InvalidImageError("truncated TIFF: the BigTIFF header is cut short")
        offset_size, zero = struct.unpack(order + "HH", bytes(data[4:8]))
        if offset_size != 8 or zero != 0:
            raise InvalidImageError("corrupt TIFF: a BigTIFF header with other than 8-byte offsets")
        (first,) = struct.unpack(order + "Q", bytes(data[8:16]))
        count_fmt, entry_fmt, next_fmt = order + "Q", order + "HHQ8s", order + "Q"
    else:
        if size < 8:
            raise InvalidImageError("truncated TIFF: the header is cut short")
        (first,) = struct.unpack(order + "I", bytes(data[4:8]))
        count_fmt, entry_fmt, next_fmt = order + "H", order + "HHI4s", order + "I"
    count_size, entry_size = struct.calcsize(count_fmt), struct.calcsize(entry_fmt)
    next_size, inline = struct.calcsize(next_fmt), (8 if big else 4)
    value_at = 12 if big else 8
    pages: list[TiffPage] = []
    seen: dict[int, int] = {}
    budget = MAX_IFD_BYTES
    at = first
    while at != 0:
        if len(pages) == max_pages:
            return TiffStructure(pages, big, True)
        if at in seen:
            raise InvalidImageError(
                f"corrupt TIFF: page {len(pages)}'s directory offset points back to page "
                f"{seen[at]} (the page chain loops)"
            )
        index = len(pages)
        if at + count_size > size:
            raise InvalidImageError(
                f"truncated TIFF: page {index}'s directory at byte {at} lies outside the "
                f"file of {size} bytes"
            )
        seen[at] = index
        (n,) = struct.unpack(count_fmt, bytes(data[at : at + count_size]))
        end = at + count_size + n * entry_size
        if end + next_size > size:
            raise InvalidImageError(
                f"truncated TIFF: page {index}'s directory of {n} tags ends past the file "
                f"of {size} bytes"
            )
        budget -= end + next_size - at
        if budget < 0:
            raise InvalidImageError(
                f"TIFF directories of more than {MAX_IFD_BYTES} bytes in all are not read "
                f"(page {index})"
            )
        block = bytes(data[at + count_size : end])
        entries: dict[int, Entry] = {}
        for k in range(n):
            tag, kind, count, raw = struct.unpack_from(entry_fmt, block, k * entry_size)
            if kind not in TYPES:
                raise InvalidImageError(
                    f"corrupt TIFF: page {index}'s {tag_name(tag)} has the unknown type {kind}"
                )
            length = count * TYPES[kind][0]
            where = at + count_size + k * entry_size + value_at
            if length > inline:
                (where,) = struct.unpack(order + ("Q" if big else "I"), raw)
            if where + length > size:
                raise InvalidImageError(
                    f"truncated TIFF: page {index}'s {tag_name(tag)} ({count} values at byte "
                    f"{where}) lies outside the file of {size} bytes"
                )
            entries.setdefault(tag, Entry(kind, count, where))
        pages.append(TiffPage(index, entries, data, order))
        (at,) = struct.unpack(next_fmt, bytes(data[end : end + next_size]))
    return TiffStructure(pages, big, False)


#: Bits per sample read (1: bilevel).
BITS = (1, 8, 16, 32, 64)
#: How much larger than the image itself its tile grid may decode to (tiles cover the
#: image's edge whole) and, for a small image, how many bytes it may in any case.
TILE_GRID_FACTOR = 4
TILE_GRID_BYTES = 4 << 20


@dataclass(frozen=True)
class Layout:
    """What a page says of its pixels, every tag checked for its type, count and range."""

    index: int
    width: int
    height: int
    samples: int
    bits: int
    compression: int
    planar: bool
    tile: tuple[int, int] | None  # (width, length) of a tiled page
    rows_per_strip: int
    offsets: np.ndarray
    counts: np.ndarray
    depth: int
    page: TiffPage

    def segments(self) -> tuple[int, list[int]]:
        """Bytes of each strip or tile when whole, and the fewest each must decode to
        (a last strip may stop at the image's end)."""
        planes = self.samples if self.planar else 1
        per_pixel = (self.samples // planes) * self.bits
        if self.tile is not None:
            tw, tl = self.tile
            full = tl * ((tw * per_pixel + 7) // 8)
            count = planes * (-(-self.width // tw)) * (-(-self.height // tl))
            return full, [full] * count
        rows = min(self.rows_per_strip, self.height)
        row_bytes = (self.width * per_pixel + 7) // 8
        strips = -(-self.height // rows)
        least = [min(rows, self.height - i * rows) * row_bytes for i in range(strips)]
        return rows * row_bytes, least * planes

    @property
    def decoded_bytes(self) -> int:
        """Bytes the image decodes to."""
        return self.width * self.height * self.samples * self.bits // 8


def page_layout(page: TiffPage) -> Layout:
    """The checked layout of one page.

    Raises
    ------
    InvalidImageError
        A tag the readers use of another type or count than TIFF allows, or a value
        they do not read: samples of different sizes, a tile of zero size, an
        orientation other than top-left, strips and byte counts that do not pair up.
    """
    i = page.index
    width = page.one(256, least=1)
    height = page.one(257, least=1)
    samples = page.one(277, default=1, least=1)
    if 258 in page:
        e = page.entries[258]
        bits_all = page.values(258, (3,), None if e.count == 1 else samples).tolist()
    else:
        bits_all = [1]
    if len(set(bits_all)) != 1:
        raise InvalidImageError(
            f"TIFF page {i}'s samples differ in size (BitsPerSample "
            f"{','.join(map(str, bits_all))}); skelprune reads samples of one size"
        )
    bits = int(bits_all[0])
    compression = page.one(259, default=1)
    planar = page.one(284, default=1)
    if planar not in (1, 2):
        raise InvalidImageError(f"corrupt TIFF: page {i}'s PlanarConfiguration is {planar}")
    orientation = page.one(274, default=1)
    if orientation != 1:
        raise InvalidImageError(
            f"TIFF page {i} has Orientation {orientation} (its rows or columns stored in "
            "another order than top-left); skelprune reads top-left TIFFs only: write "
            "the image top-left (Orientation 1)"
        )
    for code in (317, 262):
        page.one(code, default=1)
    if 339 in page:
        e = page.entries[339]
        page.values(339, (3,), None if e.count == 1 else samples)
    depth = page.one(32997, default=1, least=1)
    tiled = 322 in page or 323 in page
    if tiled:
        tile: tuple[int, int] | None = (page.one(322, least=1), page.one(323, least=1))
        offsets_code, counts_code = 324, 325
        rows = height
    else:
        tile = None
        offsets_code, counts_code = 273, 279
        rows = page.one(278, default=height, least=1)
    for code in (offsets_code, counts_code):
        if code not in page:
            raise InvalidImageError(f"corrupt TIFF: page {i} has no {tag_name(code)} tag")
    offsets = page.values(offsets_code, (3, 4, 16))
    counts = page.values(counts_code, (3, 4, 16))
    if offsets.size != counts.size:
        raise InvalidImageError(
            f"corrupt TIFF: page {i} has {offsets.size} {tag_name(offsets_code)} and "
            f"{counts.size} {tag_name(counts_code)}"
        )
    layout = Layout(
        i,
        width,
        height,
        samples,
        bits,
        compression,
        planar == 2,
        tile,
        rows,
        offsets,
        counts,
        depth,
        page,
    )
    if tile is not None:
        full, least = layout.segments()
        grid = full * len(least)
        allowed = max(TILE_GRID_FACTOR * layout.decoded_bytes, TILE_GRID_BYTES)
        if grid > allowed:
            raise ImageTooLargeError(
                f"TIFF page {i}'s {tile[0]}×{tile[1]} tiles decode to {grid} bytes for a "
                f"{width}×{height} image of {layout.decoded_bytes} bytes; at most {allowed} "
                f"(tiles no larger than about the image)"
            )
    return layout
