"""Label volumes on a real Dask cluster: the components pruned as tasks, and a Zarr
store pruned chunk by chunk, give the answer of the whole array pruned in one process."""

from __future__ import annotations

import json
from dataclasses import replace
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
distributed = pytest.importorskip("distributed")  # the parallel extra

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


def test_prune_many_prunes_a_zarr_store_chunk_by_chunk_on_its_cluster(tmp_path: Path) -> None:
    from skelprune.limits import DATASET_LIMITS
    from skelprune.parallel import prune_many

    labels = touching_trees(8, 48, seed=4).labels
    path = _store(tmp_path / "in" / "cells.zarr", labels)
    out = tmp_path / "out"
    small = replace(DATASET_LIMITS, max_pixels=1000)
    fit = replace(DATASET_LIMITS, max_pixels=500_000)  # the overlay's default scale shrinks
    with dask_cluster(tmp_path / "dask", workers=2) as address:
        (done,) = prune_many(
            tmp_path / "in", client=address, out=out, files=("csv", "png"), limits=fit
        )
        (refused,) = prune_many(path, client=address, limits=small)
        with distributed.Client(address) as client:  # what ran: the chunked path's tasks
            ran = client.run_on_scheduler(lambda dask_scheduler: set(dask_scheduler.task_prefixes))
    whole = skelprune.prune(path)
    assert done.status == "done"
    assert (out / "cells.json").read_bytes() == skelprune.encode(whole, "json") + b"\n"
    assert (out / "cells.csv").read_bytes() == skelprune.encode(whole, "csv")
    # the overlay's scale held to the run's limits as for a store pruned whole
    answered = skelprune.prune(path, limits=fit, answers=("json", "png", "csv"))
    assert (out / "cells.png").read_bytes() == skelprune.encode(answered, "png")
    assert {"chunk_labels", "prune_labels"} <= ran  # (dask drops the leading _)
    # a label's box, not the whole volume, is held to the run's size limit
    assert refused.status == "failed" and refused.problem["kind"] == "image-too-large"
    assert "max_box_voxels=1000" in refused.problem["detail"]
