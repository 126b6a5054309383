"""The volume grid's incremental coverage against painting from scratch (docs/volumes.md)."""

from __future__ import annotations

import numpy as np
import pytest

from skelprune.grid3d.coverage import VolumeCoverage
from testkit import volume_oracle as oracle

SPACINGS = [(1.0, 1.0, 1.0), (3.0, 1.0, 1.0), (0.7, 1.3, 0.4)]


def naive(volume, z, y, x, r2, labels, live, spacing):
    """Lost voxels and, per live label, the voxels inside only its balls cover."""
    keep = np.isin(labels, list(live))
    lost = oracle.lost_volume(volume, z[keep], y[keep], x[keep], r2[keep], spacing)
    exclusive = {}
    for label in live:
        own = labels == label
        other = keep & ~own
        mine = oracle.ball_counts(volume.shape, z[own], y[own], x[own], r2[own], spacing) > 0
        rest = oracle.ball_counts(volume.shape, z[other], y[other], x[other], r2[other], spacing)
        exclusive[label] = int((volume & mine & (rest == 0)).sum())
    return lost, exclusive


@pytest.mark.parametrize("spacing", SPACINGS)
@pytest.mark.parametrize("seed", range(4))
def test_coverage_matches_repainting_through_removals_and_merges(seed, spacing) -> None:
    rng = np.random.default_rng(seed)
    shape = (7, 8, 9)
    volume = rng.random(shape) < 0.7
    n = 14
    # points anywhere in the array (balls partly outside it and over background too)
    z, y, x = (rng.integers(0, s, n) for s in shape)
    r2 = rng.uniform(0.5, 9.0, n)
    labels = rng.integers(1, 6, n)
    cov = VolumeCoverage(volume, z, y, x, r2, labels, 6, spacing)
    live = set(np.unique(labels).tolist())
    for _ in range(5):
        lost, exclusive = naive(volume, z, y, x, r2, labels, live, spacing)
        assert cov.lost == lost
        assert {k: int(cov.exclusive[k]) for k in live} == exclusive
        assert cov.uncovered().size == lost
        if len(live) < 2:
            break
        a, b = rng.choice(sorted(live), 2, replace=False).tolist()
        if rng.random() < 0.5:
            after = naive(volume, z, y, x, r2, labels, live - {a}, spacing)[0]
            assert cov.remove_label(a) == after - lost
            live.discard(a)
        else:
            cov.merge_label(a, b)
            labels = np.where(labels == a, b, labels)
            live.discard(a)
