"""Block coverage counts (skelprune._coverage) against plain per-pixel counts."""

from __future__ import annotations

import numpy as np
import pytest

from skelprune._coverage import (
    coverage,
    disk_covered_twice,
    disk_loss,
    disk_remove,
    true_counts,
)
from skelprune._digital import disk_half_width, isqrt


def _disk(shape: tuple[int, int], r: int, c: int, v: int) -> np.ndarray:
    out = np.zeros(shape, bool)
    for dy in range(-isqrt(v - 1), isqrt(v - 1) + 1):
        w = disk_half_width(v, dy)
        out[r + dy, c - w : c + w + 1] = True
    return out


@pytest.mark.parametrize("seed", range(4))
def test_block_counts_match_plain_counts(seed):
    rng = np.random.default_rng(seed)
    h, w = 70, 83
    n = 60
    r2s = rng.integers(1, 200, n).astype(np.int64)
    rad = np.array([isqrt(v - 1) for v in r2s])
    rows = np.array([rng.integers(1 + a, h - 1 - a) for a in rad], dtype=np.int64)
    cols = np.array([rng.integers(1 + a, w - 1 - a) for a in rad], dtype=np.int64)
    disks = [_disk((h, w), rows[k], cols[k], r2s[k]) for k in range(n)]
    plain = np.sum(disks, axis=0)
    cov = coverage(h, w, rows, cols, r2s)
    assert np.array_equal(true_counts(cov[0], cov[3])[:, :w], plain)
    for k in rng.permutation(n):
        d = disks[k]
        assert disk_covered_twice(*cov, rows[k], cols[k], r2s[k]) == bool((plain[d] >= 2).all())
        assert disk_loss(*cov, rows[k], cols[k], r2s[k]) == int((plain[d] == 1).sum())
        if rng.random() < 0.7:
            disk_remove(*cov, rows[k], cols[k], r2s[k])
            plain -= d
            assert np.array_equal(true_counts(cov[0], cov[3])[:, :w], plain)
