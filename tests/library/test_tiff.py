"""TIFF input: the PNG kinds and compressions read alike, and the hostile cases refused
before anything large is decoded."""

from __future__ import annotations

import io
import struct
import zlib

import numpy as np
import pytest
import tifffile

import skelprune
from skelprune.errors import EmptyMaskError, ImageTooLargeError, InvalidImageError
from skelprune.io.tiff import read_tiff


def shape_mask() -> np.ndarray:
    m = np.zeros((48, 64), bool)
    m[8:40, 10:54] = True
    m[20:28, 25:40] = False
    return m


def tiff(a: np.ndarray, **kw) -> bytes:
    buf = io.BytesIO()
    tifffile.imwrite(buf, a, **kw)
    return buf.getvalue()


KINDS = {
    "bilevel": lambda m: m,
    "uint8": lambda m: np.where(m, 0, 255).astype(np.uint8),  # black on white
    "uint16": lambda m: np.where(m, 60000, 100).astype(np.uint16),
    "int32": lambda m: np.where(m, 7, -3).astype(np.int32),
    "float32": lambda m: np.where(m, 0.75, 0.25).astype(np.float32),
    "rgb": lambda m: np.repeat(np.where(m, 250, 5).astype(np.uint8)[..., None], 3, axis=2),
}
COMPRESSIONS = [None, "lzw", "zlib", "packbits"]


@pytest.mark.parametrize("compression", COMPRESSIONS)
@pytest.mark.parametrize("kind", sorted(KINDS))
def test_tiff_kinds_read_as_the_shape(kind, compression):
    m = shape_mask()
    data = tiff(KINDS[kind](m), compression=compression)
    shape = skelprune.read_input(data, kind="image")
    assert np.array_equal(shape.mask, m)
    # the same skeleton as the mask itself
    got = skelprune.prune(data).to_dict()["components"]
    assert got == skelprune.prune(m).to_dict()["components"]


def test_tiled_and_predictor_and_16bit_labels():
    lab = np.zeros((64, 64), np.uint16)
    lab[4:30, 4:60] = 40000
    lab[30:60, 4:60] = 3
    data = tiff(lab, tile=(16, 16), compression="zlib", predictor=True)
    assert np.array_equal(read_tiff(data), lab)
    res = skelprune.prune(data, labels=True)
    assert [c.label for c in res.components] == [3, 40000]


def test_a_tiff_file_by_path(tmp_path):
    path = tmp_path / "shape.TIF"
    path.write_bytes(tiff(KINDS["uint8"](shape_mask()), compression="lzw"))
    assert skelprune.prune(path).components[0].area == int(shape_mask().sum())


def test_multi_page_and_3d_tiffs_are_refused_naming_the_pages():
    stack = np.zeros((5, 32, 32), np.uint8)
    with pytest.raises(InvalidImageError, match="multi-page TIFF: 5 pages"):
        read_tiff(tiff(stack, photometric="minisblack"))
    # given to prune, a stack is a volume
    with pytest.raises(EmptyMaskError, match="no voxel inside"):
        skelprune.prune(tiff(stack, photometric="minisblack"))
    stack[1:4, 8:24, 8:24] = 1
    assert skelprune.prune(tiff(stack, photometric="minisblack")).to_dict()["depth"] == 5
    volume = tiff(stack, photometric="minisblack", volumetric=True, tile=(16, 16))
    with pytest.raises(InvalidImageError, match="3-D TIFF: 1 page of 5 slices"):
        read_tiff(volume)


def test_size_is_checked_from_the_header_before_decoding():
    data = tiff(np.zeros((300, 400), np.uint8), compression="zlib")
    with pytest.raises(ImageTooLargeError, match="120000 pixels"):
        read_tiff(data, max_pixels=100_000)


def forged(width: int, height: int, real_rows: int, compression: str = "zlib") -> bytes:
    """A TIFF whose header promises ``width × height`` bytes in one strip that decodes to
    ``real_rows`` rows of it (more: a compression bomb; fewer: a short strip)."""
    import imagecodecs

    encode = {
        "zlib": lambda b: zlib.compress(b, 9),
        "lzw": imagecodecs.lzw_encode,
        "packbits": imagecodecs.packbits_encode,
    }[compression]
    good = tiff(np.zeros((height, width), np.uint8), compression=compression, rowsperstrip=height)
    page = tifffile.TiffFile(io.BytesIO(good)).pages[0]
    (offset,), (count,) = page.dataoffsets, page.databytecounts
    body = encode(bytes(width * real_rows))
    out = bytearray(good[:offset]) + body + good[offset + count :]
    tag = page.tags[279]  # the strip's byte count, in the IFD (before the data)
    struct.pack_into("<I" if tag.dtype == 4 else "<H", out, tag.valueoffset, len(body))
    return bytes(out)


def deflate_bomb(width: int, height: int, real_rows: int) -> bytes:
    return forged(width, height, real_rows, "zlib")


@pytest.mark.parametrize("compression", ["zlib", "lzw", "packbits"])
def test_compression_bomb_is_refused(compression):
    data = forged(100, 100, 5000, compression)  # 500 kB decoded for a 10 kB image
    assert len(data) < 12_000
    with pytest.raises(ImageTooLargeError, match="compression bomb"):
        read_tiff(data)


@pytest.mark.parametrize("compression", ["zlib", "lzw", "packbits"])
def test_short_strips_are_refused(compression):
    with pytest.raises(InvalidImageError, match="truncated TIFF: strip 0 holds 4000 of"):
        read_tiff(forged(100, 100, 40, compression))


def test_truncated_files_are_refused():
    whole = tiff(np.zeros((100, 100), np.uint8))
    page = tifffile.TiffFile(io.BytesIO(whole)).pages[0]
    cut = whole[: page.dataoffsets[0] + 50]
    with pytest.raises(InvalidImageError, match=r"truncated TIFF|cannot read TIFF|corrupt TIFF"):
        read_tiff(cut)


def test_garbage_after_the_signature_is_a_clear_error():
    with pytest.raises(InvalidImageError, match="TIFF"):
        read_tiff(b"II*\x00" + b"\xff" * 20)


@pytest.mark.parametrize(
    ("head", "named"),
    [
        (b"\xff\xd8\xff\xe0" + bytes(20), "JPEG"),
        (b"SQLite format 3\x00" + bytes(20), "GeoPackage"),
        (b"\x00\x00\x27\x0a" + bytes(96), "Shapefile"),
        (
            b"hello",
            "not a PNG, TIFF or GIF file: none of their signatures .a format not",
        ),
    ],
)
def test_unsupported_files_are_named_with_the_formats_read(head, named):
    with pytest.raises(InvalidImageError, match=named) as err:
        skelprune.prune(head)
    assert "PNG, TIFF and GIF" in str(err.value) and "GeoJSON" in str(err.value)


@pytest.mark.parametrize("compression", ["lzw", "packbits", "zlib"])
def test_corrupt_compressed_data_is_a_clear_error(compression):
    data = bytearray(forged(64, 64, 64, compression))
    page = tifffile.TiffFile(io.BytesIO(bytes(data))).pages[0]
    at = page.dataoffsets[0]
    data[at : at + 8] = b"\xff\x00\xff\x00\xff\x00\xff\x00"  # the stream's start broken
    with pytest.raises((InvalidImageError, ImageTooLargeError), match="TIFF"):
        read_tiff(bytes(data))
