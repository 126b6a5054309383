"""Hostile TIFF, GeoTIFF and ``.npy`` files, written byte by byte: forged tags, page
chains that loop or run for millions of pages, tile bombs, forged ``.npy`` headers; and
the mutation fuzzer that runs the readers on valid files with a few bytes changed.

The files are small (a kilobyte to a few megabytes) and each is built to break one
guarantee of the readers (docs/hostile-input.md).
"""

from __future__ import annotations

import io
import random
import struct
import time
import zlib
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "TiffPageSpec",
    "empty_pages_tiff",
    "fuzz",
    "looping_tiff",
    "mutations",
    "npy_with_header",
    "tiff_with",
    "tile_bomb_tiff",
    "write_tiff",
]

_SIZES = {1: 1, 2: 1, 3: 2, 4: 4, 5: 8, 7: 1, 11: 4, 12: 8, 16: 8}
_FORMATS = {1: "B", 2: "B", 3: "H", 4: "I", 7: "B", 11: "f", 12: "d", 16: "Q"}


@dataclass
class TiffPageSpec:
    """One page: its tags ``(code, type, values)`` and strips of bytes (their offsets
    and byte counts are added as LONGs, unless given)."""

    tags: list[tuple[int, int, Sequence[float] | bytes]]
    strips: list[bytes] = field(default_factory=list)
    tiles: bool = False


def _entry(code: int, kind: int, values: Sequence[float] | bytes) -> tuple[int, int, int, bytes]:
    if kind == 5:
        raw = b"".join(struct.pack("<II", int(v), 1) for v in values)  # type: ignore[union-attr]
        return code, kind, len(values), raw
    if isinstance(values, bytes):
        return code, kind, len(values), values
    raw = struct.pack("<" + _FORMATS[kind] * len(values), *values)
    return code, kind, len(values), raw


def write_tiff(pages: Sequence[TiffPageSpec], links: dict[int, int] | None = None) -> bytes:
    """A little-endian classic TIFF of ``pages``; ``links`` sends page ``i``'s next-IFD
    offset to page ``j``'s directory (a loop when ``j <= i``)."""
    out = bytearray(b"II*\x00\x00\x00\x00\x00")
    ifd_at: list[int] = []
    patches: list[tuple[int, int]] = []  # (where the next offset is written, page index)
    for index, page in enumerate(pages):
        offsets = []
        for strip in page.strips:
            offsets.append(len(out))
            out += strip
        if len(out) % 2:
            out += b"\x00"
        tags = list(page.tags)
        if page.strips:
            codes = (324, 325) if page.tiles else (273, 279)
            given = {t[0] for t in tags}
            if codes[0] not in given:
                tags.append((codes[0], 4, offsets))
            if codes[1] not in given:
                tags.append((codes[1], 4, [len(s) for s in page.strips]))
        entries = sorted((_entry(*t) for t in tags), key=lambda e: e[0])
        # values longer than 4 bytes go before the directory
        placed = []
        for code, kind, count, raw in entries:
            if len(raw) > 4:
                at = len(out)
                out += raw + (b"\x00" if len(raw) % 2 else b"")
                placed.append(struct.pack("<HHII", code, kind, count, at))
            else:
                placed.append(struct.pack("<HHI", code, kind, count) + raw.ljust(4, b"\x00"))
        ifd_at.append(len(out))
        out += struct.pack("<H", len(placed)) + b"".join(placed)
        patches.append((len(out), index))
        out += b"\x00\x00\x00\x00"
    struct.pack_into("<I", out, 4, ifd_at[0] if ifd_at else 0)
    links = links or {}
    for where, index in patches:
        target = links.get(index, index + 1)
        struct.pack_into("<I", out, where, ifd_at[target] if target < len(ifd_at) else 0)
    return bytes(out)


def _plain_page(width: int = 4, height: int = 4, extra: Iterable = ()) -> TiffPageSpec:
    data = bytes([0, 255] * (width * height // 2 + 1))[: width * height]
    return TiffPageSpec(
        [
            (256, 3, [width]),
            (257, 3, [height]),
            (258, 3, [8]),
            (259, 3, [1]),
            (262, 3, [1]),
            (277, 3, [1]),
            (278, 3, [height]),
            *extra,
        ],
        [data],
    )


def tiff_with(
    replace: dict[int, tuple[int, Sequence[float] | bytes]] | None = None,
    drop: Iterable[int] = (),
    width: int = 4,
    height: int = 4,
) -> bytes:
    """A valid 8-bit TIFF of one strip, tags replaced (``code: (type, values)``) or
    dropped: a forged tag's file."""
    page = _plain_page(width, height)
    replace = replace or {}
    page.tags = [t for t in page.tags if t[0] not in replace and t[0] not in set(drop)]
    page.tags += [(code, kind, values) for code, (kind, values) in replace.items()]
    return write_tiff([page])


def looping_tiff(pages: int = 100) -> bytes:
    """``pages`` one-pixel pages whose last page's chain points back to the first (a
    file of about a kilobyte per ten pages... with empty pages, 1 KB in all)."""
    empty = [TiffPageSpec([]) for _ in range(pages)]
    return write_tiff(empty, {pages - 1: 0})


def empty_pages_tiff(pages: int) -> bytes:
    """A TIFF of ``pages`` pages of no tags: six bytes each (2.7 million in 16 MB)."""
    out = bytearray(b"II*\x00\x08\x00\x00\x00")
    at = 8
    block = bytearray()
    for i in range(pages):
        nxt = at + 6 * (i + 1) if i < pages - 1 else 0
        block += struct.pack("<HI", 0, nxt)
    return bytes(out + block)


def tile_bomb_tiff(tile: int = 16384, pages: int = 1) -> bytes:
    """A 1×1 8-bit image in one ``tile``² tile of Deflate zeros: a few hundred KB that
    would inflate to ``tile``² bytes (``pages`` of them: a stack)."""
    raw = zlib.compress(bytes(tile * tile), 9)
    page = TiffPageSpec(
        [
            (256, 3, [1]),
            (257, 3, [1]),
            (258, 3, [8]),
            (259, 3, [8]),
            (262, 3, [1]),
            (277, 3, [1]),
            (322, 3, [tile]),
            (323, 3, [tile]),
        ],
        [raw],
        tiles=True,
    )
    return write_tiff([page] * pages)


def npy_with_header(header: str, body: bytes = b"", version: int = 1) -> bytes:
    """A ``.npy`` file whose header dictionary is ``header`` as written (forged shapes,
    dtypes), padded as numpy pads it."""
    text = header.encode("latin-1")
    head = 10 if version == 1 else 12
    pad = (-(head + len(text) + 1)) % 64
    text += b" " * pad + b"\n"
    size = struct.pack("<H", len(text)) if version == 1 else struct.pack("<I", len(text))
    return b"\x93NUMPY" + bytes([version, 0]) + size + text + body


def npy_bytes(array: np.ndarray) -> bytes:
    """A valid ``.npy`` file of ``array``."""
    buf = io.BytesIO()
    np.save(buf, array)
    return buf.getvalue()


def mutations(seed: bytes, rng: random.Random) -> bytes:
    """``seed`` with a few bytes changed: flipped bits, bytes set to extremes, a run
    copied over another, or the file cut short."""
    data = bytearray(seed)
    for _ in range(rng.randint(1, 4)):
        choice = rng.random()
        at = rng.randrange(len(data))
        if choice < 0.35:
            data[at] ^= 1 << rng.randrange(8)
        elif choice < 0.7:
            data[at] = rng.choice((0, 1, 0x7F, 0x80, 0xFF))
        elif choice < 0.9:
            n = rng.randint(2, 8)
            src = rng.randrange(len(data))
            data[at : at + n] = data[src : src + n]
        else:
            del data[at:]
            if not data:
                data = bytearray(seed[:1])
    return bytes(data)


def fuzz(
    seeds: Sequence[bytes],
    read: Callable[[bytes], object],
    allowed: tuple[type[BaseException], ...],
    seconds: float,
    rng_seed: int = 45,
    most: int = 100_000,
) -> int:
    """Run ``read`` on mutations of ``seeds`` for about ``seconds`` (at most ``most``
    files, the same files for the same seed); any exception but ``allowed`` is raised
    with the mutated file attached (``exc.fuzzed``). Returns how many were read."""
    rng = random.Random(rng_seed)
    end = time.monotonic() + seconds
    n = 0
    while n < most and time.monotonic() < end:
        data = mutations(rng.choice(seeds), rng)
        n += 1
        try:
            read(data)
        except allowed:
            pass
        except BaseException as exc:
            exc.fuzzed = data  # type: ignore[attr-defined]
            raise
    return n
