"""Label volumes on a real Dask cluster: the components pruned as tasks, and a Zarr
store pruned chunk by chunk, give the answer of the whole array pruned in one process."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import skelprune
from skelprune.errors import ImageTooLargeError
from skelprune.parallel.volume_chunks import prune_zarr_chunked
from skelprune.volume import prune_volume_labels
from testkit.daskcluster import dask_cluster
from testkit.volumes import touching_trees

zarr = pytest.importorskip("zarr")  # the zarr extra

pytestmark = [pytest.mark.slow, pytest.mark.timeout(900)]


def _doc(res) -> tuple[str, str]:
    return json.dumps(res.to_dict(), sort_keys=True), res.to_swc()


def _store(path: Path, data: np.ndarray, chunks=(24, 24, 24)) -> str:
    z = zarr.open_array(str(path), mode="w", shape=data.shape, chunks=chunks, dtype=data.dtype)
    z[...] = data
    return str(path)


def test_chunks_and_tasks_on_dask_give_the_whole_arrays_answer(tmp_path: Path) -> None:
    labels = touching_trees(12, 64, seed=9).labels
    whole = skelprune.prune(labels)
    binary = labels != 0
    whole_binary = skelprune.prune(binary)
    path = _store(tmp_path / "cells.zarr", labels)
    path_binary = _store(tmp_path / "mask.zarr", binary)
    done: list[int] = []
    with dask_cluster(tmp_path / "dask", workers=2) as address:
        tasks = prune_volume_labels(labels, client=address)
        chunked = prune_zarr_chunked(path, address, progress=done.append)
        chunked_binary = prune_zarr_chunked(path_binary, address)
        with pytest.raises(ImageTooLargeError, match="max_box_voxels=1000"):
            prune_zarr_chunked(path, address, max_box_voxels=1000)
    assert _doc(tasks) == _doc(whole)
    assert _doc(chunked) == _doc(whole)
    assert sum(done) == 12  # every label once
    assert np.array_equal(chunked.volume, labels != 0)
    assert _doc(chunked_binary) == _doc(whole_binary)
