"""16-bit PNGs read with all their bits in every colour type, and palettes without one."""

from __future__ import annotations

import struct
import zlib

import numpy as np
import pytest

from skelprune.errors import InvalidImageError
from skelprune.io.png import read_mask, read_shape
from testkit.pngfile import SIGNATURE, chunk, png16


def expected() -> np.ndarray:
    mask = np.zeros((6, 7), bool)
    mask[2:5, 1:4] = True
    return mask


@pytest.mark.parametrize("colour", [0, 2, 4, 6])
def test_levels_that_differ_in_the_low_byte_only_are_two_levels(colour: int) -> None:
    """A background of 256 and a shape of 511: one level in the high byte."""
    channels = {0: 1, 2: 3, 4: 2, 6: 4}[colour]
    grey = np.where(expected(), 511, 256).astype(np.uint16)
    samples = np.repeat(grey[..., None], channels, axis=2)
    if colour in (4, 6):
        samples[..., -1] = 65535  # opaque
    mask, taken = read_shape(png16(samples, colour))
    assert taken.shape == "light" and np.array_equal(mask, expected())
    assert read_mask(png16(samples, colour), foreground="nonzero").all()  # no zero


@pytest.mark.parametrize("colour", [4, 6])
def test_a_zero_one_mask_with_alpha_reads_with_nonzero(colour: int) -> None:
    channels = {4: 2, 6: 4}[colour]
    samples = np.zeros((6, 7, channels), np.uint16)
    samples[..., :-1] = expected()[..., None]
    samples[..., -1] = 65535
    assert np.array_equal(read_mask(png16(samples, colour), foreground="nonzero"), expected())


def test_a_16_bit_colour_key_matches_all_16_bits() -> None:
    samples = np.full((6, 7, 3), 256, np.uint16)
    samples[expected()] = 257  # differs from the key in the low byte only: opaque
    key = struct.pack(">HHH", 256, 256, 256)
    mask = read_mask(png16(samples, 2, trns=key), foreground="nonzero")
    assert np.array_equal(mask, expected())


def test_a_16_bit_grey_key_matches_all_16_bits() -> None:
    samples = np.full((6, 7, 1), 256, np.uint16)
    samples[expected()] = 257
    mask = read_mask(png16(samples, 0, trns=struct.pack(">H", 256)), foreground="nonzero")
    assert np.array_equal(mask, expected())


def test_a_palette_image_without_a_palette_is_invalid() -> None:
    head = struct.pack(">IIBBBBB", 4, 4, 8, 3, 0, 0, 0)
    rows = b"".join(b"\x00" + bytes(4) for _ in range(4))
    data = (
        SIGNATURE + chunk(b"IHDR", head) + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b"")
    )
    with pytest.raises(InvalidImageError, match="without a PLTE chunk"):
        read_mask(data)


def test_too_much_text_in_all_is_refused_without_the_decoders_names() -> None:
    """Seventy zTXt chunks of 1 MB each, inflated: over the decoder's total for text."""
    head = struct.pack(">IIBBBBB", 4, 4, 8, 0, 0, 0, 0)
    rows = b"".join(b"\x00" + bytes(4) for _ in range(4))
    text = b"".join(
        chunk(b"zTXt", b"k%d\x00\x00" % i + zlib.compress(b"a" * 1_000_000)) for i in range(70)
    )
    data = (
        SIGNATURE
        + chunk(b"IHDR", head)
        + text
        + chunk(b"IDAT", zlib.compress(rows))
        + chunk(b"IEND", b"")
    )
    with pytest.raises(InvalidImageError) as err:
        read_mask(data)
    assert "text chunks are too large" in str(err.value)
    assert "MAX_TEXT" not in str(err.value)
