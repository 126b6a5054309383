"""The local scope's windows on a Dask cluster: the answer is the one of the windows run
one after the other, whatever order they finish in."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from skelprune.io.input import Input
from skelprune.local import prune_local
from skelprune.options import PruneOptions
from testkit.daskcluster import dask_cluster
from testkit.networks import network

pytestmark = [pytest.mark.slow, pytest.mark.timeout(600)]


def test_windows_on_dask_give_the_same_answer(tmp_path: Path) -> None:
    from dask.distributed import Client

    mask = network("crack", 1024, seed=3).mask
    options = PruneOptions(scope="local", window=256).resolved()
    alone = prune_local(Input(mask), options)
    seen: list[tuple[int, int]] = []
    with dask_cluster(tmp_path / "dask", workers=2) as address, Client(address) as client:
        tiled = prune_local(
            Input(mask), options, client=client, progress=lambda d, t: seen.append((d, t))
        )
    assert tiled.to_dict() == alone.to_dict()
    assert seen == [(k, 16) for k in range(1, 17)]  # a 4 × 4 grid of windows
    assert np.array_equal(tiled.skeleton_points()[0], alone.skeleton_points()[0])
