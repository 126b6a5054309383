"""Mutation fuzzers of the readers of untrusted bytes: valid TIFF, GeoTIFF and ``.npy``
files with a few bytes changed (:func:`testkit.hostile_files.fuzz`), a fixed seed and a
budget of a few seconds each. A reader may refuse a file only by naming its problem (a
:class:`~skelprune.errors.SkelpruneError`), never with another exception."""

from __future__ import annotations

import io

import numpy as np
import tifffile

from skelprune.errors import SkelpruneError
from skelprune.io.geotiff import geotiff_georeference, read_geotiff_bytes
from skelprune.io.input import check_image_size, read_input
from skelprune.io.tiff import read_tiff, read_tiff_stack, tiff_pages
from skelprune.volume import check_volume_size, is_volume, read_volume
from testkit.hostile_cases import geotiff_with
from testkit.hostile_files import fuzz, npy_bytes

SECONDS = 3.0
LIMIT = 1 << 20


def _tiff(array: np.ndarray, **kw: object) -> bytes:
    buf = io.BytesIO()
    tifffile.imwrite(buf, array, **kw)
    return buf.getvalue()


def _tiff_seeds() -> list[bytes]:
    m = np.zeros((24, 32), np.uint8)
    m[4:20, 6:26] = 255
    return [
        _tiff(m),
        _tiff(m, compression="zlib"),
        _tiff(m, compression="lzw", predictor=True),
        _tiff(m, tile=(16, 16), compression="zlib"),
        _tiff(m.astype(np.uint16) * 200, compression="packbits"),
        _tiff(np.stack([m, m, m], -1), photometric="rgb"),
        _tiff(np.stack([m, m[::-1], m]), photometric="minisblack"),
        _tiff(m > 0),
    ]


def _read_any(data: bytes) -> None:
    """What the service and the library run on an uploaded TIFF."""
    tiff_pages(data)
    if is_volume(data):
        check_volume_size(data, LIMIT)
        read_volume(data, LIMIT)
    else:
        check_image_size(data, LIMIT)
        read_tiff(data, max_pixels=LIMIT)


def test_mutated_tiffs_are_read_or_refused_by_name() -> None:
    assert fuzz(_tiff_seeds(), _read_any, (SkelpruneError,), SECONDS) > 100


def test_mutated_tiff_stacks_are_read_or_refused_by_name() -> None:
    m = np.zeros((3, 16, 16), np.uint8)
    m[:, 4:12, 4:12] = 1
    seeds = [_tiff(m, photometric="minisblack", compression="zlib")]
    assert (
        fuzz(seeds, lambda d: read_tiff_stack(d, max_voxels=LIMIT), (SkelpruneError,), SECONDS)
        > 100
    )


def _read_geotiff(data: bytes) -> None:
    geo = geotiff_georeference(data)
    if geo is not None:
        read_geotiff_bytes(data, geo, LIMIT)
    read_input(data, max_pixels=LIMIT)


def test_mutated_geotiffs_are_read_or_refused_by_name() -> None:
    seeds = [
        geotiff_with(),
        geotiff_with([1, 1, 0, 2, 1024, 0, 1, 2, 2048, 0, 1, 4326]),
        geotiff_with(tag34264=(12, [10.0, 0, 0, 5e5, 0, -10.0, 0, 6.6e6, 0, 0, 0, 0, 0, 0, 0, 1])),
        geotiff_with(tag42113=(2, b"255\x00")),
    ]
    assert fuzz(seeds, _read_geotiff, (SkelpruneError,), SECONDS) > 100


def _read_npy(data: bytes) -> None:
    check_volume_size(data, LIMIT)
    read_volume(data, LIMIT)


def test_mutated_npy_files_are_read_or_refused_by_name() -> None:
    v = np.zeros((4, 8, 8), np.uint8)
    v[1:3, 2:6, 2:6] = 3
    seeds = [
        npy_bytes(v),
        npy_bytes(v != 0),
        npy_bytes(v.astype(">i4")),
        npy_bytes(np.asfortranarray(v)),
    ]
    assert fuzz(seeds, _read_npy, (SkelpruneError,), SECONDS) > 100
