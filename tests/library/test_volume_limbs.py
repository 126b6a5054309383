"""The volume limb test's whole balls, read ball by ball, are those of the distance
transform it replaces: ``d2(s) ≥ r2(s)``, the distance to the nearest voxel not covered
by the branch alone (whole-number spacings, where both are exact)."""

from __future__ import annotations

import numpy as np
import pytest

from skelprune.grid3d.distance import squared_distance
from skelprune.grid3d.limbs import _whole_balls


@pytest.mark.parametrize("seed", range(30))
def test_whole_balls_equal_the_distance_transforms_test(seed: int) -> None:
    rng = np.random.default_rng(seed)
    spacing = tuple(float(s) for s in rng.integers(1, 4, 3))
    shape = tuple(int(n) for n in rng.integers(6, 24, 3))
    before = rng.integers(0, 3, shape).astype(np.int32)
    # mostly this branch's alone, some voxels shared or uncovered, in blobs
    after = np.where(rng.random(shape) < rng.uniform(0.0, 0.08), 1, 0).astype(np.int32)
    before[before == 0] = np.where(rng.random(int((before == 0).sum())) < 0.8, 1, 0)
    n = 40
    z, y, x = (rng.integers(0, s, n) for s in shape)
    r2 = rng.uniform(0.5, 30.0, n)
    r2[::3] = np.round(r2[::3])  # whole numbers too: the ball's own boundary
    whole = np.zeros(n, np.bool_)
    _whole_balls(after, before, z, y, x, r2, np.array(spacing), whole)
    d2 = squared_distance((after == 0) & (before > 0), spacing)
    assert np.array_equal(whole, d2[z, y, x] >= r2)
