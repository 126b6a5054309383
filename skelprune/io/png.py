"""Decoding of PNG files and arrays into boolean shape masks.

Rules (docs/service.md): greyscale, RGB, RGBA, palette (with or without transparency) and
16-bit PNGs are accepted. Which pixels are the shape is decided by the foreground rule
of :mod:`skelprune.io.foreground` (``auto`` by default: the background is the grey level
holding most of the border; ``nonzero`` and ``zero`` on request).

Choices made where the PNG format leaves room:

- An image uses transparency when at least one pixel is fully transparent: alpha 0 in
  an alpha channel, a palette entry with alpha 0 that some pixel uses, or a pixel equal
  to the tRNS colour key (whose alpha is then 0, and 1 elsewhere). An RGBA file whose
  alpha is 255 everywhere is therefore read by its grey values, like the RGB file it
  really is.
- Values are taken exactly, before any rounding: 16-bit samples keep all 16 bits in
  every colour type (grey, grey and alpha, RGB, RGBA, and a 16-bit tRNS key, compared
  exactly): for ``nonzero``, a colour pixel belongs to the shape unless it is pure black.
- The chunk structure (lengths, CRCs, a final IEND) is checked before Pillow decodes, and
  the image data must inflate to every scanline the header promises, so a truncated or
  corrupted file is refused instead of half-decoded.
"""

from __future__ import annotations

import io
import os
import re
import struct
import zlib
from pathlib import Path

import numpy as np
from PIL import Image, UnidentifiedImageError

from skelprune.errors import ImageTooLargeError, InvalidImageError

from .foreground import Foreground, check_rule, select

__all__ = ["PNG_SIGNATURE", "check_png_size", "png_size", "read_mask", "read_shape", "read_values"]

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
_MAX_DIMENSION = 2**31 - 1  # PNG spec limit for width and height
_ALPHA_MODES = {"RGBA", "LA", "PA", "RGBa", "La"}


def _ihdr(data: bytes) -> tuple[int, int, int, int]:
    """Return ``(width, height, bit_depth, colour_type)`` from the IHDR chunk."""
    if len(data) < 8 or data[:8] != PNG_SIGNATURE:
        raise InvalidImageError("not a PNG file: the 8-byte PNG signature is missing")
    if len(data) < 33:
        raise InvalidImageError(f"truncated PNG: {len(data)} bytes, the IHDR chunk needs 33")
    length, ctype = struct.unpack(">I4s", data[8:16])
    if ctype != b"IHDR" or length != 13:
        raise InvalidImageError("corrupt PNG: the first chunk is not a 13-byte IHDR")
    width, height, depth, colour = struct.unpack(">IIBB", data[16:26])
    if not (0 < width <= _MAX_DIMENSION and 0 < height <= _MAX_DIMENSION):
        raise InvalidImageError(f"corrupt PNG: invalid size {width}×{height} in IHDR")
    return width, height, depth, colour


def png_size(data: bytes) -> tuple[int, int]:
    """Read the size of a PNG from its header, without decoding it.

    Parameters
    ----------
    data : bytes
        The PNG file (at least its first 33 bytes).

    Returns
    -------
    tuple of int
        ``(width, height)`` in pixels.

    Raises
    ------
    InvalidImageError
        Bad signature, data shorter than the IHDR chunk, or an invalid IHDR.

    Examples
    --------
    >>> import io, numpy as np
    >>> from PIL import Image
    >>> buf = io.BytesIO(); Image.fromarray(np.zeros((3, 5), np.uint8)).save(buf, "PNG")
    >>> png_size(buf.getvalue())
    (5, 3)
    """
    width, height, _, _ = _ihdr(bytes(data[:33]))
    return width, height


def check_png_size(data: bytes, max_pixels: int | None) -> tuple[int, int]:
    """The PNG's (width, height) from its header; refuses more than ``max_pixels`` pixels
    before anything is decoded.

    Raises
    ------
    InvalidImageError
        Not a PNG header.
    ImageTooLargeError
        More pixels than ``max_pixels``.
    """
    width, height = png_size(data)
    if max_pixels is not None and width * height > max_pixels:
        raise ImageTooLargeError(
            f"image has {width * height} pixels ({width}×{height}), the limit is {max_pixels}"
        )
    return width, height


def _check_chunks(data: bytes) -> None:
    """Walk the chunk list: every chunk complete, every CRC right, IEND present."""
    pos = 8
    n = len(data)
    colour = data[25] if n > 25 else 0
    palette = False
    while True:
        if pos + 8 > n:
            raise InvalidImageError(f"truncated PNG: file ends at byte {n} before the IEND chunk")
        length, ctype = struct.unpack(">I4s", data[pos : pos + 8])
        end = pos + 12 + length
        name = ctype.decode("latin-1")
        if end > n:
            raise InvalidImageError(
                f"truncated PNG: chunk {name!r} at byte {pos} needs {length + 12} bytes, "
                f"only {n - pos} left"
            )
        (crc,) = struct.unpack(">I", data[end - 4 : end])
        if zlib.crc32(data[pos + 4 : end - 4]) != crc:
            raise InvalidImageError(f"corrupt PNG: CRC mismatch in chunk {name!r} at byte {pos}")
        if ctype == b"IHDR" and pos != 8:
            # Pillow would decode with the last IHDR, after the size was checked on the
            # first one: a second header could smuggle in any size.
            raise InvalidImageError(f"corrupt PNG: a second IHDR chunk at byte {pos}")
        if ctype == b"PLTE":
            palette = True
        if ctype == b"IDAT" and colour == 3 and not palette:
            raise InvalidImageError("corrupt PNG: a palette image without a PLTE chunk")
        if ctype == b"IEND":
            return
        pos = end


#: Samples per pixel of each PNG colour type.
_CHANNELS = {0: 1, 2: 3, 3: 1, 4: 2, 6: 4}
#: Adam7 passes: (first row, row step, first column, column step).
_ADAM7 = (
    (0, 8, 0, 8),
    (0, 8, 4, 8),
    (4, 8, 0, 4),
    (0, 4, 2, 4),
    (2, 4, 0, 2),
    (0, 2, 1, 2),
    (1, 2, 0, 1),
)


def _raw_size(width: int, height: int, depth: int, colour: int, interlaced: bool) -> int:
    """Bytes of filtered scanlines the IHDR promises (each row: filter byte + samples)."""
    bits = _CHANNELS.get(colour, 1) * depth

    def rows(w: int, h: int) -> int:
        return h * (1 + (w * bits + 7) // 8) if w and h else 0

    if not interlaced:
        return rows(width, height)
    return sum(
        rows((width - c0 + dc - 1) // dc, (height - r0 + dr - 1) // dr)
        for r0, dr, c0, dc in _ADAM7
        if width > c0 and height > r0
    )


def _check_image_data(data: bytes, width: int, height: int, depth: int, colour: int) -> None:
    """The IDAT stream inflates to every scanline the header promises.

    Pillow fills what a short stream leaves out: valid chunks holding 10 of 60 rows
    would otherwise decode as a whole image. Inflated in pieces, counted, not kept.
    """
    interlaced = data[28] == 1
    need = _raw_size(width, height, depth, colour, interlaced)
    inflate = zlib.decompressobj()
    got = 0
    pos = 8
    try:
        while pos + 8 <= len(data):
            length, ctype = struct.unpack(">I4s", data[pos : pos + 8])
            if ctype == b"IDAT":
                piece = data[pos + 8 : pos + 8 + length]
                while piece and got < need:
                    got += len(inflate.decompress(piece, 1 << 20))
                    piece = inflate.unconsumed_tail
            elif ctype == b"IEND":
                break
            pos += 12 + length
    except zlib.error:
        raise InvalidImageError("cannot decode PNG: the image data is corrupt") from None
    if got < need:
        raise InvalidImageError(
            f"truncated PNG: the image data holds {got} of the {need} bytes of scanlines "
            f"its {width}×{height} header promises"
        )


def _plain(exc: BaseException) -> str:
    """The decoder's message without its internals (object addresses, module names)."""
    text = str(exc)
    if "MAX_TEXT_CHUNK" in text:
        return "a text chunk is too large"
    if "MAX_TEXT_MEMORY" in text:
        return "the text chunks are too large in all"
    text = re.sub(r"<[^<>]* at 0x[0-9a-fA-F]+>", "the data", text)
    return re.sub(r"\b\w+(ImagePlugin|File)\.\w+", "a reader limit", text) or type(exc).__name__


def _decode(data: bytes) -> Image.Image:
    try:
        im = Image.open(io.BytesIO(data), formats=["PNG"])
        im.load()
    except Image.DecompressionBombError:
        raise ImageTooLargeError("image too large to decode safely") from None
    except UnidentifiedImageError:
        raise InvalidImageError("cannot decode PNG: not a valid PNG image") from None
    except (
        OSError,
        SyntaxError,
        ValueError,
        EOFError,
        struct.error,
        zlib.error,
    ) as exc:
        raise InvalidImageError(f"cannot decode PNG: {_plain(exc)}") from None
    return im


def _is_key(arr: np.ndarray, key: object) -> np.ndarray:
    """Pixels equal to a tRNS colour key (an int for grey, an RGB tuple for colour)."""
    if arr.ndim == 3:
        return np.all(arr[..., :3] == np.asarray(key, dtype=np.int64)[:3], axis=-1)
    return arr == int(key)  # type: ignore[call-overload]


def _deep_values(data: bytes, colour: int) -> tuple[np.ndarray, np.ndarray | None]:
    """Colour and alpha of a 16-bit colour or grey-and-alpha PNG, all 16 bits.

    Pillow keeps only the high byte of these (a background of 256 and a shape of 511
    would be one level); OpenCV's decoder keeps every bit, and turns a tRNS colour key
    into an alpha channel by the exact 16-bit comparison.
    """
    import cv2

    arr = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED)
    if arr is None or arr.dtype != np.uint16 or arr.ndim != 3:
        raise InvalidImageError("cannot decode PNG: the 16-bit image data is not readable")
    alpha = arr[..., 3] if arr.shape[2] == 4 else None
    rgb = arr[..., 2::-1]  # OpenCV's BGR as RGB
    colour_values = rgb[..., 0] if colour == 4 else rgb  # grey and alpha: one grey channel
    if alpha is not None and not np.any(alpha == 0):
        alpha = None  # opaque everywhere: read by its values
    return np.ascontiguousarray(colour_values), alpha


def _image_values(im: Image.Image) -> tuple[np.ndarray, np.ndarray | None]:
    """Grey or colour values, and the alpha channel if the image uses transparency."""
    mode = im.mode
    if mode == "P":
        # Palette: Pillow maps tRNS (per-entry alpha) to RGBA for us.
        has_trns = "transparency" in im.info
        im = im.convert("RGBA" if has_trns else "RGB")
        mode = im.mode
    if mode == "1":
        return np.array(im, dtype=np.uint8), None
    arr = np.asarray(im)
    if mode in _ALPHA_MODES:
        alpha = arr[..., -1]
        colour = arr[..., :-1]
        colour = colour[..., 0] if colour.shape[-1] == 1 else colour
        return colour, (alpha if np.any(alpha == 0) else None)
    key = im.info.get("transparency")
    if key is not None and not isinstance(key, bytes):
        transparent = _is_key(arr, key)
        if transparent.any():
            return arr, (~transparent).astype(np.uint8)
    return arr, None


def _array_values(arr: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    if arr.ndim == 2:
        return arr, None
    if arr.ndim == 3 and arr.shape[2] in (1, 2, 3, 4):
        alpha = None
        if arr.shape[2] in (2, 4):
            alpha = arr[..., -1] if np.any(arr[..., -1] == 0) else None
            arr = arr[..., :-1]
        return (arr[..., 0] if arr.shape[2] == 1 else arr), alpha
    raise InvalidImageError(
        f"array of shape {arr.shape} is not an image: expected (H, W) or (H, W, 1-4)"
    )


def read_values(data: bytes, max_pixels: int | None = None) -> tuple[np.ndarray, np.ndarray | None]:
    """A PNG's values (all 16 bits of a 16-bit image) and its alpha where it uses
    transparency, after every check of the header, chunks and image data.

    Examples
    --------
    >>> import io
    >>> buf = io.BytesIO()
    >>> Image.fromarray(np.array([[0, 7], [7, 0]], np.uint8)).save(buf, "PNG")
    >>> values, alpha = read_values(buf.getvalue())
    >>> values.tolist(), alpha
    ([[0, 7], [7, 0]], None)
    """
    width, height, depth, colour = _ihdr(data)
    check_png_size(data, max_pixels)
    _check_chunks(data)
    _check_image_data(data, width, height, depth, colour)
    im = _decode(data)
    if im.size != (width, height):  # never decode something other than what was checked
        raise InvalidImageError(
            f"corrupt PNG: decoded size {im.size[0]}×{im.size[1]} differs from the "
            f"IHDR size {width}×{height}"
        )
    if depth == 16 and colour in (2, 4, 6):  # Pillow would keep the high byte
        return _deep_values(data, colour)
    return _image_values(im)


def read_shape(
    source: bytes | bytearray | memoryview | str | os.PathLike[str] | np.ndarray,
    *,
    foreground: str = "auto",
    max_pixels: int | None = None,
) -> tuple[np.ndarray, Foreground]:
    """Decode a PNG (bytes or file path) or an image array into its shape mask.

    Parameters
    ----------
    source : bytes, str, os.PathLike or numpy.ndarray
        PNG file contents, the path of a PNG file, or an image array of shape
        ``(H, W)`` or ``(H, W, C)`` with ``C`` in 1–4 (2 and 4: last channel is alpha).
    foreground : {"auto", "nonzero", "zero"}
        The foreground rule (:mod:`skelprune.io.foreground`).
    max_pixels : int, optional
        Refuse images with more pixels than this. For PNG input the check reads the
        header only, before anything is decoded.

    Returns
    -------
    mask : numpy.ndarray
        ``(H, W)`` boolean array, True on the shape.
    Foreground
        What was taken as the shape.

    Raises
    ------
    InvalidImageError
        Not a PNG, truncated or corrupt data, unreadable file, or an array that is
        not an image.
    ImageTooLargeError
        More pixels than ``max_pixels``.
    InvalidOptionError
        An unknown ``foreground`` rule.

    Examples
    --------
    >>> import numpy as np
    >>> white = np.full((4, 4), 255, np.uint8); white[1:3, 1:3] = 0
    >>> mask, fg = read_shape(white)
    >>> mask.astype(int).tolist()[1], fg.shape
    ([0, 1, 1, 0], 'dark')
    """
    check_rule(foreground)
    if isinstance(source, np.ndarray):
        values, alpha = _array_values(source)
        if max_pixels is not None and values.shape[0] * values.shape[1] > max_pixels:
            raise ImageTooLargeError(
                f"image has {values.shape[0] * values.shape[1]} pixels "
                f"({values.shape[1]}×{values.shape[0]}), the limit is {max_pixels}"
            )
    else:
        if isinstance(source, (str, os.PathLike)):
            try:
                data = Path(source).read_bytes()
            except OSError as exc:
                raise InvalidImageError(
                    f"cannot read {os.fspath(source)!r}: {exc.strerror}"
                ) from None
        else:
            data = bytes(source)
        values, alpha = read_values(data, max_pixels)
    mask, taken = select(values, foreground, alpha)
    return np.ascontiguousarray(mask, dtype=bool), taken


def read_mask(
    source: bytes | bytearray | memoryview | str | os.PathLike[str] | np.ndarray,
    *,
    foreground: str = "auto",
    max_pixels: int | None = None,
) -> np.ndarray:
    """The shape mask of a PNG or an image array: :func:`read_shape` without the report.

    Examples
    --------
    >>> import numpy as np
    >>> read_mask(np.array([[0, 3], [0, 0]])).tolist()
    [[False, True], [False, False]]
    """
    return read_shape(source, foreground=foreground, max_pixels=max_pixels)[0]
