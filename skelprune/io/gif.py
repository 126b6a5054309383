"""GIF masks (the format of DRIVE and other vessel data sets), read as PNGs are, with the
same hostile-input guarantees.

Before anything is decoded, the file's blocks are walked (linear in its bytes, nothing
inflated): the file must hold exactly one image (an animation is refused, naming its
frames), the logical screen and the image must lie within ``max_pixels`` and the image
inside the screen, and every block must end inside the file. The one frame is then
decoded by Pillow, whose LZW output is bounded by the frame's size. Values are the
palette's colours (grey for a grey palette), as a PNG's palette is read; a transparent
index is the alpha.
"""

from __future__ import annotations

import io
import struct

import numpy as np

from ..errors import ImageTooLargeError, InvalidImageError

__all__ = ["GIF_SIGNATURES", "gif_size", "is_gif", "read_gif"]

GIF_SIGNATURES = (b"GIF87a", b"GIF89a")


def is_gif(data: bytes) -> bool:
    """Whether ``data`` starts with a GIF signature."""
    return bytes(data[:6]) in GIF_SIGNATURES


def _frames(data: bytes) -> tuple[int, int, list[tuple[int, int, int, int]]]:
    """The logical screen's ``(width, height)`` and each image's ``(left, top, width,
    height)``, from the blocks (at most two images are looked for)."""
    if not is_gif(data):
        raise InvalidImageError("not a GIF file: the GIF signature is missing")
    if len(data) < 13:
        raise InvalidImageError("truncated GIF: the screen descriptor is cut short")
    width, height, packed = struct.unpack_from("<HHB", data, 6)
    at = 13 + (3 << ((packed & 7) + 1) if packed & 0x80 else 0)
    frames: list[tuple[int, int, int, int]] = []

    def sub_blocks(pos: int) -> int:
        while True:
            if pos >= len(data):
                raise InvalidImageError("truncated GIF: a data block runs past the file's end")
            size = data[pos]
            pos += 1 + size
            if size == 0:
                return pos

    while True:
        if at >= len(data):
            raise InvalidImageError("truncated GIF: the file ends before its trailer")
        kind = data[at]
        if kind == 0x3B:  # trailer
            return width, height, frames
        if kind == 0x21:  # extension: label, then sub-blocks
            at = sub_blocks(at + 2)
        elif kind == 0x2C:  # image descriptor
            if at + 10 > len(data):
                raise InvalidImageError("truncated GIF: an image descriptor is cut short")
            left, top, w, h, local = struct.unpack_from("<HHHHB", data, at + 1)
            frames.append((left, top, w, h))
            if len(frames) > 1:
                return width, height, frames
            at += 10 + (3 << ((local & 7) + 1) if local & 0x80 else 0)
            at = sub_blocks(at + 1)  # the LZW minimum code size, then the data
        else:
            raise InvalidImageError(f"corrupt GIF: unknown block 0x{kind:02x} at byte {at}")


def gif_size(data: bytes, max_pixels: int | None = None) -> tuple[int, int]:
    """``(width, height)`` of a one-image GIF, from its blocks; refuses an animation, an
    image outside its screen, and more than ``max_pixels`` pixels, before decoding.

    >>> from PIL import Image
    >>> buf = io.BytesIO(); Image.new("L", (5, 3)).save(buf, "GIF")
    >>> gif_size(buf.getvalue())
    (5, 3)
    """
    data = bytes(data)
    width, height, frames = _frames(data)
    if len(frames) != 1:
        counted = "no image" if not frames else "more than 1 frame"
        raise InvalidImageError(
            f"a GIF mask is one image; this GIF holds {counted} (an animation is not read)"
        )
    left, top, w, h = frames[0]
    for pixels, what in ((width * height, "screen"), (w * h, "image")):
        if max_pixels is not None and pixels > max_pixels:
            raise ImageTooLargeError(
                f"the GIF's {what} has {pixels} pixels, the limit is {max_pixels}"
            )
    if width == 0 or height == 0 or left + w > width or top + h > height:
        raise InvalidImageError(
            f"corrupt GIF: its image ({w}×{h} at {left},{top}) does not lie inside its "
            f"{width}×{height} screen"
        )
    return width, height


def read_gif(data: bytes, max_pixels: int | None = None) -> tuple[np.ndarray, np.ndarray | None]:
    """A one-image GIF's values and its alpha where it uses transparency, after every
    check of :func:`gif_size`.

    Examples
    --------
    >>> from PIL import Image
    >>> buf = io.BytesIO()
    >>> Image.fromarray(np.array([[0, 255], [255, 0]], np.uint8)).save(buf, "GIF")
    >>> values, alpha = read_gif(buf.getvalue())
    >>> values.tolist(), alpha
    ([[0, 255], [255, 0]], None)
    """
    from PIL import Image

    from .png import _image_values

    data = bytes(data)
    width, height = gif_size(data, max_pixels)
    try:
        im = Image.open(io.BytesIO(data), formats=["GIF"])
        im.load()
    except Image.DecompressionBombError:
        raise ImageTooLargeError("image too large to decode safely") from None
    except Exception as exc:  # Pillow raises many kinds on a broken file
        raise InvalidImageError(f"cannot decode GIF: {str(exc)[:200]}") from None
    if im.size != (width, height):
        raise InvalidImageError(
            f"corrupt GIF: decoded size {im.size[0]}×{im.size[1]} differs from its "
            f"{width}×{height} screen"
        )
    if im.mode == "P" and _grey_palette(im):
        values = np.asarray(im.convert("L"))
        key = im.info.get("transparency")
        if isinstance(key, int):
            opaque = np.asarray(im) != key
            if not opaque.all():
                return values, opaque.astype(np.uint8)
        return values, None
    return _image_values(im)


def _grey_palette(im: object) -> bool:
    """Whether every colour of a palette image's palette is a grey."""
    palette = im.getpalette() or []  # type: ignore[attr-defined]
    rgb = np.asarray(palette[: len(palette) // 3 * 3]).reshape(-1, 3)
    return bool(np.all(rgb[:, 0] == rgb[:, 1]) and np.all(rgb[:, 1] == rgb[:, 2]))
