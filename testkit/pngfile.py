"""PNG files written chunk by chunk, for the readers' edge cases (16-bit samples, a
``tRNS`` chunk, broken chunks) that Pillow does not write."""

from __future__ import annotations

import struct
import zlib

import numpy as np

__all__ = ["SIGNATURE", "chunk", "png16"]

#: The eight bytes every PNG starts with.
SIGNATURE = b"\x89PNG\r\n\x1a\n"


def chunk(kind: bytes, payload: bytes) -> bytes:
    """One PNG chunk: its length, type, payload and CRC.

    >>> chunk(b"IEND", b"").hex()
    '0000000049454e44ae426082'
    """
    crc = struct.pack(">I", zlib.crc32(kind + payload))
    return struct.pack(">I", len(payload)) + kind + payload + crc


def png16(samples: np.ndarray, colour: int, trns: bytes | None = None) -> bytes:
    """A 16-bit PNG of ``samples`` (H, W, channels) in colour type ``colour``, rows
    unfiltered, with a ``tRNS`` chunk of ``trns`` if given.

    >>> from skelprune.io.png import read_mask
    >>> grey = np.zeros((3, 4, 1), np.uint16); grey[1, 1:3] = 65535
    >>> int(read_mask(png16(grey, 0)).sum())
    2
    """
    h, w = samples.shape[:2]
    rows = b"".join(b"\x00" + samples[r].astype(">u2").tobytes() for r in range(h))
    head = struct.pack(">IIBBBBB", w, h, 16, colour, 0, 0, 0)
    extra = chunk(b"tRNS", trns) if trns is not None else b""
    return (
        SIGNATURE
        + chunk(b"IHDR", head)
        + extra
        + chunk(b"IDAT", zlib.compress(rows))
        + chunk(b"IEND", b"")
    )
