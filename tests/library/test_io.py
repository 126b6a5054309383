"""PNG / array decoding into boolean masks (skelprune.io.png)."""

from __future__ import annotations

import io
import struct
import zlib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from PIL import Image

from skelprune.errors import ImageTooLargeError, InvalidImageError
from skelprune.io.png import png_size, read_mask, read_shape
from testkit import DATA
from testkit.pngfile import chunk as _chunk


def raw_png(samples: np.ndarray, colour_type: int, depth: int, *extra: bytes) -> bytes:
    """Write a PNG by hand so that every colour type / depth / tRNS can be exercised.

    ``samples`` is (H, W) or (H, W, C) of unsigned ints already at ``depth`` bits.
    """
    h, w = samples.shape[:2]
    dtype = ">u2" if depth == 16 else np.uint8
    rows = samples.reshape(h, w * (samples.size // max(h * w, 1))).astype(dtype)
    raw = b"".join(b"\x00" + row.tobytes() for row in rows)
    ihdr = struct.pack(">IIBBBBB", w, h, depth, colour_type, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + _chunk(b"IHDR", ihdr)
        + b"".join(extra)
        + _chunk(b"IDAT", zlib.compress(raw))
        + _chunk(b"IEND", b"")
    )


def pil_png(im: Image.Image, **kw: object) -> bytes:
    buf = io.BytesIO()
    im.save(buf, "PNG", **kw)
    return buf.getvalue()


DISK = np.zeros((9, 11), dtype=bool)
DISK[2:7, 3:9] = True


def test_dataset_file_by_path_and_bytes() -> None:
    path = DATA / "kimia216" / "bird-10.png"
    expected = np.asarray(Image.open(path)) == 255
    by_path = read_mask(path)
    by_str = read_mask(str(path))
    by_bytes = read_mask(path.read_bytes())
    assert by_path.dtype == bool and by_path.shape == (103, 116)
    assert np.array_equal(by_path, expected)
    assert np.array_equal(by_str, expected)
    assert np.array_equal(by_bytes, expected)
    assert png_size(path.read_bytes()) == (116, 103)


def test_greyscale_nonzero_is_shape() -> None:
    arr = np.where(DISK, 7, 0).astype(np.uint8)
    assert np.array_equal(read_mask(pil_png(Image.fromarray(arr))), DISK)


def test_one_bit() -> None:
    assert np.array_equal(read_mask(pil_png(Image.fromarray(DISK))), DISK)


def test_rgb_any_non_black_is_shape() -> None:
    arr = np.zeros((*DISK.shape, 3), np.uint8)
    arr[DISK] = (0, 0, 1)  # luma rounds to 0, but the pixel is not black
    assert np.array_equal(read_mask(pil_png(Image.fromarray(arr))), DISK)


def test_rgba_with_transparency_uses_alpha() -> None:
    arr = np.zeros((*DISK.shape, 4), np.uint8)  # colour black everywhere
    arr[..., 3] = np.where(DISK, 40, 0)
    assert np.array_equal(read_mask(pil_png(Image.fromarray(arr, "RGBA"))), DISK)


def test_rgba_fully_opaque_falls_back_to_grey() -> None:
    arr = np.zeros((*DISK.shape, 4), np.uint8)
    arr[..., 3] = 255
    arr[DISK, :3] = 200
    assert np.array_equal(read_mask(pil_png(Image.fromarray(arr, "RGBA"))), DISK)


def test_grey_alpha() -> None:
    arr = np.zeros((*DISK.shape, 2), np.uint8)
    arr[..., 1] = np.where(DISK, 255, 0)
    assert np.array_equal(read_mask(raw_png(arr, 4, 8)), DISK)


def _palette_image(index: np.ndarray) -> Image.Image:
    im = Image.fromarray(index.astype(np.uint8), "P")
    im.putpalette([255, 255, 255, 0, 0, 0] + [0] * (254 * 3))  # entry 0 white, 1 black
    return im


def test_palette_without_transparency_uses_palette_grey() -> None:
    index = np.where(DISK, 0, 1)  # shape drawn with the *white* entry 0
    assert np.array_equal(read_mask(pil_png(_palette_image(index))), DISK)


def test_palette_with_used_transparent_entry() -> None:
    index = np.where(DISK, 1, 0)  # shape is black (entry 1), background is transparent white
    data = pil_png(_palette_image(index), transparency=0)
    assert np.array_equal(read_mask(data), DISK)


def test_palette_with_unused_transparent_entry_falls_back_to_grey() -> None:
    index = np.where(DISK, 0, 1)
    data = pil_png(_palette_image(index), transparency=5)  # entry 5: no pixel uses it
    assert np.array_equal(read_mask(data), DISK)


def test_grey_colour_key_transparency() -> None:
    # Background is the key (255); black pixels are opaque, so they are shape.
    arr = np.where(DISK, 0, 255).astype(np.uint8)
    data = raw_png(arr, 0, 8, _chunk(b"tRNS", struct.pack(">H", 255)))
    assert np.array_equal(read_mask(data), DISK)


def test_rgb_colour_key_transparency() -> None:
    arr = np.zeros((*DISK.shape, 3), np.uint8)
    arr[~DISK] = (10, 20, 30)
    data = raw_png(arr, 2, 8, _chunk(b"tRNS", struct.pack(">HHH", 10, 20, 30)))
    assert np.array_equal(read_mask(data), DISK)


def test_sixteen_bit_grey_small_values_count() -> None:
    arr = np.where(DISK, 1, 0).astype(np.uint16)  # 1/65535: dark but not zero
    assert np.array_equal(read_mask(raw_png(arr, 0, 16)), DISK)


def test_sixteen_bit_grey_colour_key() -> None:
    arr = np.where(DISK, 0, 4000).astype(np.uint16)
    data = raw_png(arr, 0, 16, _chunk(b"tRNS", struct.pack(">H", 4000)))
    assert np.array_equal(read_mask(data), DISK)


def test_sixteen_bit_rgba_and_rgb_key() -> None:
    rgba = np.zeros((*DISK.shape, 4), np.uint16)
    rgba[..., 3] = np.where(DISK, 65535, 0)
    assert np.array_equal(read_mask(raw_png(rgba, 6, 16)), DISK)
    rgb = np.zeros((*DISK.shape, 3), np.uint16)
    rgb[~DISK] = (1000, 2000, 3000)
    data = raw_png(rgb, 2, 16, _chunk(b"tRNS", struct.pack(">HHH", 1000, 2000, 3000)))
    assert np.array_equal(read_mask(data), DISK)


def test_truncated_files_are_refused() -> None:
    data = pil_png(Image.fromarray(np.where(DISK, 255, 0).astype(np.uint8)))
    for cut in (len(data) - 1, len(data) - 12, len(data) - 20, 40):
        with pytest.raises(InvalidImageError, match="truncated"):
            read_mask(data[:cut])


def test_corrupt_crc_is_refused() -> None:
    data = bytearray(pil_png(Image.fromarray(np.where(DISK, 255, 0).astype(np.uint8))))
    data[45] ^= 0xFF  # inside the IDAT payload
    with pytest.raises(InvalidImageError, match="CRC mismatch"):
        read_mask(bytes(data))


@pytest.mark.parametrize(
    ("data", "reason"),
    [
        (b"", "signature"),
        (b"GIF89a" + b"\x00" * 40, "signature"),
        (b"\x89PNG\r\n\x1a\n" + b"\x00" * 10, "truncated"),
        (b"\x89PNG\r\n\x1a\n" + struct.pack(">I4s", 13, b"IDAT") + b"\x00" * 17, "IHDR"),
        (raw_png(np.zeros((0, 3), np.uint8), 0, 8), "invalid size"),
    ],
)
def test_bad_headers(data: bytes, reason: str) -> None:
    with pytest.raises(InvalidImageError, match=reason):
        png_size(data)
    with pytest.raises(InvalidImageError, match=reason):
        read_mask(data)


def test_undecodable_idat_is_refused() -> None:
    good = raw_png(np.zeros((4, 4), np.uint8), 0, 8)
    ihdr_end = 8 + 25
    bad = good[:ihdr_end] + _chunk(b"IDAT", b"not zlib at all") + _chunk(b"IEND", b"")
    with pytest.raises(InvalidImageError, match="cannot decode PNG"):
        read_mask(bad)


def test_max_pixels_checked_from_header_before_decoding() -> None:
    # Header claims 100000×100000, and nothing decodable follows: only the header is read.
    header = raw_png(np.zeros((1, 1), np.uint8), 0, 8)[:33]
    huge = header[:16] + struct.pack(">II", 100_000, 100_000) + header[24:]
    with pytest.raises(ImageTooLargeError, match="10000000000 pixels"):
        read_mask(huge + b"garbage", max_pixels=1_000_000)
    small = pil_png(Image.fromarray(np.zeros((10, 10), np.uint8)))
    assert read_mask(small, max_pixels=100).shape == (10, 10)
    with pytest.raises(ImageTooLargeError, match="limit is 99"):
        read_mask(small, max_pixels=99)


def test_missing_file() -> None:
    with pytest.raises(InvalidImageError, match="cannot read"):
        read_mask(Path("/nonexistent/x.png"))


def test_arrays() -> None:
    assert np.array_equal(read_mask(DISK), DISK)
    assert np.array_equal(read_mask(DISK.astype(np.float32) * 0.5), DISK)
    rgba = np.zeros((*DISK.shape, 4), np.uint8)
    rgba[..., 3] = DISK * 255
    assert np.array_equal(read_mask(rgba), DISK)
    with pytest.raises(InvalidImageError, match="not an image"):
        read_mask(np.zeros((2, 2, 2, 2)))
    with pytest.raises(ImageTooLargeError):
        read_mask(DISK, max_pixels=10)


@settings(max_examples=40, deadline=None)
@given(
    mask=arrays(bool, st.tuples(st.integers(1, 12), st.integers(1, 12))),
    mode=st.sampled_from(["1", "L", "LA", "RGB", "RGBA", "P", "I;16"]),
)
def test_round_trip_any_mode(mask: np.ndarray, mode: str) -> None:
    grey = np.where(mask, 255, 0).astype(np.uint8)
    im = (
        Image.fromarray(grey).convert(mode)
        if mode != "I;16"
        else Image.fromarray(mask.astype(np.uint16) * 300)
    )
    data = pil_png(im)
    assert np.array_equal(read_mask(data, foreground="nonzero"), mask)
    assert np.array_equal(read_mask(data, foreground="zero"), ~mask)
    # auto: the side holding most of the border is the background (a tie: the light side
    # is the shape); an image of one level keeps its non-zero pixels
    border = (
        np.concatenate([mask[0], mask[-1], mask[1:-1, 0], mask[1:-1, -1]])
        if min(mask.shape) > 2
        else mask.ravel()
    )
    uniform = mask.all() or not mask.any()
    expected = mask if uniform or border.sum() <= border.size - border.sum() else ~mask
    shape, taken = read_shape(data)
    assert np.array_equal(shape, expected)
    assert taken.shape == ("nonzero" if uniform else "light" if expected is mask else "dark")
