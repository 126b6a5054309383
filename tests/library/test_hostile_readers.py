"""The readers refuse by name what they cannot read: the TIFF walker's budgets and tag
checks, every ``.npy`` header field, the GeoKeys, CRSs that are no map of the Earth;
GIF masks; label volumes split in one pass; the screens count labels; the one rule for
numbers that are not finite."""

from __future__ import annotations

import io
import json
import math
import struct
import subprocess
import sys

import numpy as np
import pytest
import tifffile
from PIL import Image

import skelprune
from skelprune.budget import estimate, label_count, volume_estimate
from skelprune.errors import ImageTooLargeError, InvalidImageError, InvalidOptionError
from skelprune.io.geotiff import geotiff_georeference
from skelprune.io.gif import read_gif
from skelprune.io.input import check_image_size, read_input
from skelprune.io.tiff import MAX_STACK_PAGES, read_tiff, read_tiff_stack, tiff_pages
from skelprune.io.tiff_ifd import MAX_IFD_BYTES, read_structure
from skelprune.options import ReadOptions, VolumeOptions
from skelprune.output.finite import finite_tree
from skelprune.volume import check_volume_size, read_volume, volume_components
from testkit.hostile_cases import geotiff_with, label_png
from testkit.hostile_files import (
    TiffPageSpec,
    empty_pages_tiff,
    looping_tiff,
    npy_bytes,
    npy_with_header,
    tiff_with,
    tile_bomb_tiff,
    write_tiff,
)


# ------------------------------------------------------------------ the TIFF walker
def test_a_page_chain_that_loops_is_refused_naming_where_it_goes_back() -> None:
    data = looping_tiff(100)
    assert len(data) < 1100
    with pytest.raises(InvalidImageError, match=r"page 100's directory .* back to page 0"):
        read_structure(data, 10_000)
    assert tiff_pages(data) == 0  # not a volume: the image reader names the loop
    with pytest.raises(InvalidImageError, match="loops"):
        read_tiff(data)
    loop_to_self = write_tiff([TiffPageSpec([])], {0: 0})
    with pytest.raises(InvalidImageError, match="back to page 0"):
        check_image_size(loop_to_self, None)


def test_millions_of_empty_pages_are_walked_only_to_the_page_budget() -> None:
    data = empty_pages_tiff(2_700_000)
    structure = read_structure(data, MAX_STACK_PAGES)
    assert len(structure.pages) == MAX_STACK_PAGES and structure.more
    with pytest.raises(InvalidImageError, match="more than 4096 pages"):
        read_tiff(data)
    with pytest.raises(InvalidImageError, match="more than 4096 pages"):
        read_tiff_stack(data)
    with pytest.raises(InvalidImageError, match="more than 4096 pages"):
        check_volume_size(data, 1 << 30)


def test_directories_past_the_byte_budget_are_refused() -> None:
    tags = [(40000 + k, 3, [1]) for k in range(4000)]  # 48 KB of entries a page
    page = TiffPageSpec(tags)
    data = write_tiff([page] * 200)
    assert len(data) * 0 + 200 * 4000 * 12 > MAX_IFD_BYTES
    with pytest.raises(InvalidImageError, match=f"more than {MAX_IFD_BYTES} bytes"):
        read_structure(data, 4096)


@pytest.mark.parametrize(
    ("replace", "words"),
    [
        ({256: (3, [4, 4])}, "ImageWidth holds 2 values"),
        ({256: (2, b"4\x00")}, "ImageWidth is of type ASCII"),
        ({257: (3, [0])}, "ImageLength is 0"),
        ({258: (3, [8, 8, 16]), 277: (3, [3])}, "BitsPerSample 8,8,16"),
        ({322: (3, [16]), 323: (3, [0])}, "TileLength is 0"),
        ({278: (3, [0])}, "RowsPerStrip is 0"),
        ({284: (3, [3])}, "PlanarConfiguration is 3"),
        ({274: (3, [6])}, "Orientation 6"),
        ({273: (4, [8, 9])}, "2 StripOffsets and 1 StripByteCounts"),
        ({259: (12, [1.0])}, "Compression is of type DOUBLE"),
    ],
)
def test_each_tag_is_refused_by_name_for_its_type_count_or_value(replace, words) -> None:
    with pytest.raises(InvalidImageError, match=words):
        read_tiff(tiff_with(replace))


def test_a_tag_outside_the_file_and_an_unknown_type_are_named() -> None:
    data = bytearray(tiff_with({33432: (2, b"a long copyright text\x00")}))
    entry = bytes(data).index(struct.pack("<HH", 33432, 2))
    struct.pack_into("<I", data, entry + 8, len(data) + 100)  # its values past the end
    with pytest.raises(InvalidImageError, match=r"tag 33432 .* outside the file"):
        read_tiff(bytes(data))
    struct.pack_into("<H", data, entry + 2, 99)  # a type TIFF does not define
    with pytest.raises(InvalidImageError, match="tag 33432 has the unknown type 99"):
        read_tiff(bytes(data))


def test_the_tile_bomb_limit_follows_the_image_not_the_tile() -> None:
    data = tile_bomb_tiff(16384)
    assert len(data) < 300_000
    with pytest.raises(ImageTooLargeError, match=r"16384×16384 tiles .* 1×1 image"):
        read_tiff(data)
    # a small image in ordinary tiles (the grid a few times the image) is read
    m = np.zeros((100, 100), np.uint8)
    m[20:80, 30:70] = 255
    buf = io.BytesIO()
    tifffile.imwrite(buf, m, tile=(256, 256), compression="zlib")
    assert np.array_equal(read_tiff(buf.getvalue()), m)


def test_an_orientation_other_than_top_left_is_refused_and_top_left_is_read() -> None:
    m = np.arange(16, dtype=np.uint8).reshape(4, 4)
    assert read_tiff(tiff_with({274: (3, [1])})).shape == (4, 4)
    with pytest.raises(InvalidImageError, match=r"Orientation 3 .* top-left"):
        read_tiff(tiff_with({274: (3, [3])}))
    assert m.shape == (4, 4)


# ------------------------------------------------------------------ .npy headers
NPY = "{{'descr': {descr}, 'fortran_order': False, 'shape': {shape}, }}"


@pytest.mark.parametrize(
    ("descr", "shape", "error", "words"),
    [
        ("'|u1'", "(4294967296, 4294967296, 2)", ImageTooLargeError, "36893488147419103232 voxels"),
        ("'|u1'", "(99999999999999999999999, 2, 2)", ImageTooLargeError, "voxels"),
        (
            "'|u1'",
            "(-1, 16, 16)",
            InvalidImageError,
            r"shape \(-1, 16, 16\) has a dimension below 1",
        ),
        ("'|u1'", "(0, 16, 16)", InvalidImageError, "below 1"),
        ("'|u1'", "(True, 16, 16)", InvalidImageError, "not a tuple of whole numbers"),
        ("('|u1', (2, 2))", "(2, 2, 2)", InvalidImageError, "dtype '|V4' is not read"),
        ("[('a', '|u1')]", "(2, 2, 2)", InvalidImageError, "dtype"),
        ("'|V0'", "(2, 2, 2)", InvalidImageError, "dtype '|V0'"),
        ("'<m8[s]'", "(2, 2, 2)", InvalidImageError, "dtype '<m8"),
        ("'<f8'", "(2, 2, 2)", InvalidImageError, "booleans or integer labels"),
        ("'|u1'", "(1+1, 2, 2)", InvalidImageError, "not a .npy header dictionary"),
    ],
)
def test_every_npy_header_field_is_checked(descr, shape, error, words) -> None:
    data = npy_with_header(NPY.format(descr=descr, shape=shape), bytes(256))
    for read in (lambda: check_volume_size(data, 1 << 24), lambda: read_volume(data, 1 << 24)):
        with pytest.raises(error, match=words) as info:
            read()
        assert " at 0x" not in str(info.value)


def test_a_header_length_too_short_is_refused() -> None:
    with pytest.raises(InvalidImageError, match=r"cannot read the .npy header"):
        check_volume_size(b"\x93NUMPY\x01\x00\x02\x00{}", 100)


def test_a_valid_npy_volume_is_still_read() -> None:
    v = np.zeros((3, 4, 5), np.uint16)
    v[1, 1:3, 1:4] = 7
    assert np.array_equal(read_volume(npy_bytes(v), 1000), v)
    assert check_volume_size(npy_bytes(v), 60) == (3, 4, 5)


def test_a_2d_npy_file_is_told_how_to_be_read_as_an_image() -> None:
    flat = npy_bytes(np.ones((4, 5), bool))
    with pytest.raises(InvalidImageError, match=r"2 dimensions \(a .npy file is read as a vol"):
        read_volume(flat, 1000)
    with pytest.raises(InvalidImageError, match=r"this one has 2 dimensions$"):
        read_volume(np.ones((4, 5), bool))  # an array is told only what it is


# ------------------------------------------------------------------ GeoTIFF and CRSs
KEYS = [1, 1, 0, 2, 1024, 0, 1, 1, 3072, 0, 1]


def test_a_valid_geotiff_gives_its_grid_and_crs() -> None:
    geo = geotiff_georeference(geotiff_with())
    assert geo is not None and geo.crs == "EPSG:32633"
    assert geo.transform == (10.0, 0.0, 500000.0, 0.0, -10.0, 6600000.0)


@pytest.mark.parametrize(
    ("data", "words"),
    [
        (geotiff_with(scale=(2, b"10,10\x00")), "ModelPixelScale is of type ASCII"),
        (geotiff_with(scale=(12, [10.0, 10.0])), "ModelPixelScale holds 2 values"),
        (geotiff_with(tie=(12, [0, 0, 0, 5e5])), "ModelTiepoint holds 4 values"),
        (
            geotiff_with([1, 1, 0, 1, 3072, 34736, 1, 0], tag34736=(12, [32633.0])),
            "3072 is stored as 1 doubles",
        ),
        (geotiff_with([1, 1, 0, 1, 3072, 34736, 1, 0], tag34736=(12, [math.nan])), "3072"),
        (geotiff_with([1, 1, 0, 1, 3072, 0, 2, 32633]), "3072 is stored as 2"),
        (geotiff_with([*KEYS, 0]), "code is 0"),
        (geotiff_with([*KEYS, 9999]), "EPSG:9999"),
        (geotiff_with([*KEYS, 65535]), "EPSG:65535"),
        (geotiff_with([*KEYS, 4978]), "geocentric"),
        (geotiff_with([1, 1, 0, 1, 1024, 0, 1, 3]), "model is geocentric"),
        (geotiff_with([1, 1, 0, 9, 1024]), "fewer than its header says"),
        (
            geotiff_with(keys=None, tag34735=(12, [1.0, 1, 0, 0])),
            "GeoKeyDirectory is of type DOUBLE",
        ),
        (geotiff_with(scale=(12, [1e308, 1e308, 0])), "pixel size 1e.308"),
        (geotiff_with(scale=(12, [math.inf, 10, 0])), "not finite"),
    ],
)
def test_each_malformed_geokey_set_is_refused_by_name(data: bytes, words: str) -> None:
    with pytest.raises(InvalidImageError, match=words):
        geotiff_georeference(data)
    with pytest.raises(InvalidImageError):
        read_input(data)


@pytest.mark.parametrize(
    ("crs", "words"),
    [
        ("IAU_2015:30100", "not the Earth's"),
        ("IAU_2015:49900", "not the Earth's"),
        ("EPSG:5703", "vertical"),
        ("EPSG:4978", "geocentric"),
    ],
)
def test_crs_that_are_no_map_of_the_earth_are_refused(crs: str, words: str) -> None:
    square = {"type": "Polygon", "coordinates": [[[0, 0], [40, 0], [40, 20], [0, 20], [0, 0]]]}
    with pytest.raises(InvalidOptionError, match=words):
        skelprune.prune(square, crs=crs)


# ------------------------------------------------------------------ GIF masks
def _gif(values: np.ndarray, **kw: object) -> bytes:
    buf = io.BytesIO()
    Image.fromarray(values).save(buf, "GIF", **kw)
    return buf.getvalue()


def test_a_gif_mask_gives_the_answer_of_the_same_png() -> None:
    m = np.zeros((30, 60), np.uint8)
    m[5:25, 5:55] = 255
    buf = io.BytesIO()
    Image.fromarray(m).save(buf, "PNG")
    from_gif = skelprune.prune(_gif(m)).to_dict()
    from_png = skelprune.prune(buf.getvalue()).to_dict()
    assert from_gif["components"] == from_png["components"]


def test_a_gif_is_checked_on_its_blocks_before_decoding() -> None:
    m = np.full((16, 16), 255, np.uint8)
    frames = [Image.fromarray(m), Image.fromarray(255 - m)]
    buf = io.BytesIO()
    frames[0].save(buf, "GIF", save_all=True, append_images=frames[1:])
    with pytest.raises(InvalidImageError, match="more than 1 frame"):
        read_gif(buf.getvalue())
    with pytest.raises(ImageTooLargeError, match="the limit is 100"):
        read_gif(_gif(m), max_pixels=100)
    with pytest.raises(InvalidImageError, match="truncated GIF"):
        read_gif(_gif(m)[:40])
    big_screen = bytearray(_gif(m))
    big_screen[6:10] = (60000).to_bytes(2, "little") * 2  # a 60000² screen, 300 bytes
    with pytest.raises(ImageTooLargeError, match="screen has 3600000000 pixels"):
        check_image_size(bytes(big_screen), 4096**2)


def test_a_gif_mask_prunes_through_the_cli(tmp_path) -> None:
    m = np.zeros((30, 60), np.uint8)
    m[5:25, 5:55] = 255
    (tmp_path / "vessels.gif").write_bytes(_gif(m))
    run = subprocess.run(
        [sys.executable, "-m", "skelprune.cli", "prune", str(tmp_path / "vessels.gif")],
        capture_output=True,
        text=True,
        timeout=300,
        check=True,
    )
    assert json.loads(run.stdout)["components"]


def test_a_label_image_read_without_labels_says_so_on_stderr(tmp_path) -> None:
    lab = np.zeros((30, 60), np.uint8)
    lab[5:25, 5:25], lab[5:25, 30:55], lab[10:20, 26:29] = 60, 120, 180
    Image.fromarray(lab).save(tmp_path / "cells.png")
    run = subprocess.run(
        [sys.executable, "-m", "skelprune.cli", "prune", str(tmp_path / "cells.png")],
        capture_output=True,
        text=True,
        timeout=300,
        check=True,
    )
    assert "looks like a label image" in run.stderr and "--labels" in run.stderr


# ------------------------------------------------------------------ labels
def _old_volume_components(volume: np.ndarray) -> list:
    """The per-label pass over the whole volume (labels × voxels): the oracle."""
    from scipy import ndimage

    values = np.unique(volume)
    binary = volume.dtype == np.bool_ or set(values.tolist()) <= {0, 1}
    out = []
    for value in [None] if binary else [v for v in values.tolist() if v != 0]:
        mask = volume != 0 if value is None else volume == value
        lab, _ = ndimage.label(mask, structure=np.ones((3, 3, 3), bool))
        for i, box in enumerate(ndimage.find_objects(lab), start=1):
            crop = np.pad(lab[box] == i, 1)
            out.append((crop, (box[0].start - 1, box[1].start - 1, box[2].start - 1), value))
    return out


@pytest.mark.parametrize("dtype", [np.uint8, np.int16, np.int64, np.uint64, bool])
def test_label_volumes_split_in_their_boxes_as_the_whole_volume_pass_did(dtype) -> None:
    rng = np.random.default_rng(7)
    for _ in range(6):
        v = rng.integers(-3 if np.issubdtype(dtype, np.signedinteger) else 0, 6, (9, 11, 13))
        v[rng.random(v.shape) < 0.5] = 0
        v = v.astype(dtype)
        if dtype == np.uint64:
            v[v == 5] = np.uint64(2**63 + 5)
        new, old = volume_components(v), _old_volume_components(v)
        assert len(new) == len(old)
        for (c1, o1, l1), (c2, o2, l2) in zip(new, old, strict=True):
            assert o1 == o2 and l1 == l2 and np.array_equal(c1, c2)


def test_the_screens_count_each_label() -> None:
    values = np.asarray(Image.open(io.BytesIO(label_png(512))))
    shape = read_input(label_png(512), read=ReadOptions(labels=True))
    assert label_count(shape.labels) == 65535
    assert estimate(shape.mask, labels=shape.labels).seconds > 30  # refused up front
    assert estimate(shape.mask).seconds < estimate(shape.mask, labels=shape.labels).seconds
    assert values.dtype == np.uint16
    v = np.zeros((48, 48, 48), np.uint16)
    v.reshape(-1)[:65535] = np.arange(1, 65536, dtype=np.uint16)
    assert volume_estimate(v).seconds > 30 > volume_estimate(v != 0).seconds


# ------------------------------------------------------------------ non-finite numbers
def test_numbers_that_are_not_finite_are_null_in_every_encoding() -> None:
    m = np.zeros((40, 80), bool)
    m[10:30, 5:75] = True
    m[0:40, 38:42] = True
    res = skelprune.prune(m)
    doc = res.to_dict()
    assert finite_tree(doc) is doc  # finite documents are kept as they are
    assert "nan" not in res.to_csv().lower() and "inf" not in res.to_csv().lower()
    assert "nan" not in res.to_graphml().lower()
    json.dumps(res.to_geojson(), allow_nan=False)


@pytest.mark.parametrize(
    "spacing", ["1e308,1,1", "1e-308,1,1", "5e-324,1,1", "1_0,1,1", "\u0661,1,1"]
)
def test_spacings_that_would_overflow_or_are_not_plain_numbers_are_refused(spacing) -> None:
    with pytest.raises(InvalidOptionError, match="spacing"):
        VolumeOptions(spacing=spacing)
    with pytest.raises(InvalidOptionError, match="pixel_size"):
        skelprune.prune(np.ones((8, 8), bool), pixel_size=1e308)
