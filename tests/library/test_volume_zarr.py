"""Zarr and OME-Zarr volumes: read as the same array gives, their voxel size from
OME-Zarr's scale metadata, bad stores refused with a clear error, and the CLI."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import skelprune
from skelprune.errors import ImageTooLargeError, InvalidImageError
from skelprune.io.zarr import chunk_boxes, is_zarr, open_zarr_volume
from skelprune.volume import is_volume, read_zarr
from testkit.volumes import touching_trees

zarr = pytest.importorskip("zarr")  # the zarr extra

VOLUME = touching_trees(5, 40, seed=4).labels


def _doc(res) -> str:
    return json.dumps(res.to_dict(), sort_keys=True)


def _array(path: Path, data: np.ndarray, fmt: int = 3, chunks=(16, 16, 16)):
    z = zarr.open_array(
        str(path), mode="w", shape=data.shape, chunks=chunks, dtype=data.dtype, zarr_format=fmt
    )
    z[...] = data
    return z


def _ome(path: Path, data: np.ndarray, scale, axes="zyx", top_scale=None) -> None:
    """An OME-Zarr 0.4 image written by hand: one level ``0``."""
    g = zarr.open_group(str(path), mode="w", zarr_format=2)
    _array(path / "0", data, fmt=2, chunks=data.shape)
    ms = {
        "version": "0.4",
        "axes": [{"name": a, "type": "space" if a in "zyx" else a} for a in axes],
        "datasets": [
            {"path": "0", "coordinateTransformations": [{"type": "scale", "scale": scale}]}
        ],
    }
    if top_scale is not None:
        ms["coordinateTransformations"] = [{"type": "scale", "scale": top_scale}]
    g.attrs["multiscales"] = [ms]


@pytest.mark.parametrize("fmt", [2, 3])
def test_a_zarr_array_prunes_as_its_array(tmp_path: Path, fmt: int) -> None:
    path = tmp_path / "cells.zarr"
    _array(path, VOLUME, fmt)
    assert is_zarr(path) and is_volume(str(path))
    assert _doc(skelprune.prune(str(path))) == _doc(skelprune.prune(VOLUME))


def test_ome_zarr_scale_is_the_spacing_unless_one_is_given(tmp_path: Path) -> None:
    path = tmp_path / "image.zarr"
    _ome(path, VOLUME, [2.0, 1.0, 0.5], top_scale=[1.0, 1.0, 2.0])  # the two multiply
    store = open_zarr_volume(path)
    assert store.spacing == (2.0, 1.0, 1.0) and store.shape == VOLUME.shape
    res = skelprune.prune(path)
    assert res.spacing == (2.0, 1.0, 1.0)
    assert _doc(res) == _doc(skelprune.prune(VOLUME, spacing=(2, 1, 1)))
    assert skelprune.prune(path, spacing=(1, 1, 3)).spacing == (1.0, 1.0, 3.0)


def test_ome_zarr_time_and_channel_axes_of_one_are_dropped(tmp_path: Path) -> None:
    path = tmp_path / "tczyx.zarr"
    _ome(path, VOLUME[None, None], [1.0, 1.0, 3.0, 1.0, 1.0], axes="tczyx")
    arr, spacing = read_zarr(path)
    assert np.array_equal(arr, VOLUME) and spacing == (3.0, 1.0, 1.0)
    _ome(path, np.stack([VOLUME, VOLUME])[None], [1.0] * 5, axes="tczyx")
    with pytest.raises(InvalidImageError, match="other than z, y and x must be of length 1"):
        open_zarr_volume(path)


def test_bad_stores_are_refused_clearly(tmp_path: Path) -> None:
    with pytest.raises(InvalidImageError, match="no such folder"):
        skelprune.prune(tmp_path / "missing.zarr")
    (tmp_path / "empty.zarr").mkdir()
    with pytest.raises(InvalidImageError, match=r"holds no \.zarray, \.zgroup or zarr\.json"):
        skelprune.prune(tmp_path / "empty.zarr")
    _array(tmp_path / "flat.zarr", np.ones((4, 5), np.uint8), chunks=(4, 5))
    with pytest.raises(InvalidImageError, match=r"3-D array.*2 spatial dimensions"):
        skelprune.prune(tmp_path / "flat.zarr")
    _array(tmp_path / "float.zarr", np.ones((4, 5, 6), np.float32), chunks=(4, 5, 6))
    with pytest.raises(InvalidImageError, match="float32 values"):
        skelprune.prune(tmp_path / "float.zarr")
    zarr.open_group(str(tmp_path / "group.zarr"), mode="w")
    with pytest.raises(InvalidImageError, match="without OME-Zarr multiscales"):
        skelprune.prune(tmp_path / "group.zarr")
    _array(tmp_path / "big.zarr", VOLUME)
    with pytest.raises(ImageTooLargeError, match="the limit is 1000"):
        read_zarr(tmp_path / "big.zarr", max_voxels=1000)
    bad = tmp_path / "badmeta.zarr"
    bad.mkdir()
    (bad / ".zarray").write_text("{not json")
    with pytest.raises(InvalidImageError, match="cannot open"):
        skelprune.prune(bad)


def test_chunk_boxes_cover_the_volume_with_their_halo(tmp_path: Path) -> None:
    _array(tmp_path / "c.zarr", VOLUME, chunks=(16, 16, 16))
    store = open_zarr_volume(tmp_path / "c.zarr")
    boxes = list(chunk_boxes(store))
    assert len(boxes) == 27 and boxes[1] == (slice(0, 16), slice(0, 16), slice(16, 32))
    assert list(chunk_boxes(store, halo=3))[1] == (slice(0, 19), slice(0, 19), slice(13, 35))
    count = np.zeros(VOLUME.shape, int)
    for b in boxes:
        count[b] += 1
    assert (count == 1).all()
    assert np.array_equal(store.read(boxes[13]), VOLUME[boxes[13]])


def test_the_cli_prunes_a_store(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from skelprune.cli import app

    path = tmp_path / "cells.zarr"
    _array(path, VOLUME)
    run = CliRunner().invoke(app, ["prune", str(path)])
    assert run.exit_code == 0, run.output
    assert json.loads(run.stdout) == skelprune.prune(VOLUME).to_dict()
    (tmp_path / "empty.zarr").mkdir()
    run = CliRunner().invoke(app, ["prune", str(tmp_path / "empty.zarr")])
    assert run.exit_code == 1 and "is not a Zarr store" in run.output
