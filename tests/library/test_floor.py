"""The noise-floor choice's lost areas against painting every skeleton of the sequence."""

from __future__ import annotations

import numpy as np
import pytest

from skelprune.api import components
from skelprune.grid.medial_axis import squared_distance
from skelprune.pruning.bayesian import pruning_sequence
from skelprune.pruning.choice import RIM, floor_lost
from skelprune.skeleton import Skeleton
from testkit.oracle import disk_pixels, uncovered
from testkit.shapes import DRAWN, blobs


@pytest.mark.parametrize(
    "mask",
    [pytest.param(DRAWN[name](), id=name) for name in list(DRAWN)[:3]]
    + [pytest.param(blobs(seed, size=40, n=3, holes=1), id=f"blobs-{seed}") for seed in (1, 2)],
)
def test_floor_lost_equals_painting(mask: np.ndarray) -> None:
    steps = 0
    for crop, _ in components(mask):
        start = Skeleton.medial_axis(crop)
        norm = start.normalisation(9.0)
        if norm.alpha is None:
            continue
        seq = pruning_sequence(start, norm.alpha, norm.lbar)
        lost = floor_lost(seq)
        deep = (squared_distance(start.mask) > RIM).ravel()
        disks = disk_pixels(start.rows, start.cols, start.r2, start.mask.shape)
        graph = start.working_graph()
        want = [uncovered(deep, disks, graph.alive_points())]
        for b in seq.removed:
            graph.remove_end_branch(b)
            want.append(uncovered(deep, disks, graph.alive_points()))
        assert lost.tolist() == want
        steps += len(want)
    assert steps > 0  # the case had a sequence
