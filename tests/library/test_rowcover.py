"""The row-wise coverage kernels against painting every disk pixel by pixel."""

from __future__ import annotations

import numpy as np
import pytest

from skelprune.grid._rowcover import cover_counts, exclusive_losses, uncover, uncover_count


def random_disks(rng: np.random.Generator, h: int, w: int, n: int):
    """``n`` disks inside an ``h × w`` image, radii from 1 pixel to a third of the side."""
    r2 = rng.integers(1, (min(h, w) // 3) ** 2, n)
    rad = np.sqrt(r2).astype(np.int64) + 1
    rows = np.array([rng.integers(a, h - a) for a in rad], np.int64)
    cols = np.array([rng.integers(a, w - a) for a in rad], np.int64)
    return rows, cols, r2.astype(np.int64)


def painted(h: int, w: int, rows, cols, r2) -> list[np.ndarray]:
    """Each disk ``|p − s|² < r²`` as a boolean image."""
    yy, xx = np.mgrid[:h, :w]
    return [(yy - r) ** 2 + (xx - q) ** 2 < v for r, q, v in zip(rows, cols, r2, strict=True)]


@pytest.mark.parametrize("seed", range(8))
def test_counts_and_exclusive_losses_equal_painting(seed: int) -> None:
    rng = np.random.default_rng(seed)
    h, w = rng.integers(20, 90, 2)
    rows, cols, r2 = random_disks(rng, h, w, int(rng.integers(1, 30)))
    disks = painted(h, w, rows, cols, r2)
    c = cover_counts(h, w, rows, cols, r2)
    assert np.array_equal(c, np.sum(disks, axis=0))
    mask = rng.random((h, w)) < 0.9
    # a subset of the disks, with drop indices (repeats allowed)
    sub = rng.permutation(rows.size)[: int(rng.integers(1, rows.size + 1))]
    n_drop = int(rng.integers(1, 6))
    drop = rng.integers(0, n_drop, sub.size).astype(np.int64)
    loss = exclusive_losses(mask, c, rows[sub], cols[sub], r2[sub], drop, n_drop)
    mine = np.zeros(rows.size, bool)
    mine[sub] = True
    others = np.zeros((h, w), bool)
    last = np.full((h, w), -1)
    for i, d in enumerate(disks):
        if not mine[i]:
            others |= d
    for j, i in enumerate(sub):
        last[disks[i]] = np.maximum(last[disks[i]], drop[j])
    want = np.bincount(last[mask & ~others & (last >= 0)], minlength=n_drop)
    assert np.array_equal(loss, want)


@pytest.mark.parametrize("seed", range(8))
def test_uncover_equals_painting(seed: int) -> None:
    rng = np.random.default_rng(100 + seed)
    h, w = rng.integers(20, 90, 2)
    rows, cols, r2 = random_disks(rng, h, w, int(rng.integers(2, 30)))
    disks = painted(h, w, rows, cols, r2)
    gone = rng.permutation(rows.size)[: rows.size // 2 + 1]
    deep = rng.random((h, w)) < 0.7
    c = cover_counts(h, w, rows, cols, r2)
    c2 = c.copy()
    before = np.sum(disks, axis=0)
    after = before - np.sum([disks[i] for i in gone], axis=0)
    uncover(c, rows[gone], cols[gone], r2[gone])
    assert np.array_equal(c, after)
    n = uncover_count(c2, deep, rows[gone], cols[gone], r2[gone])
    assert np.array_equal(c2, after)
    assert n == int((deep & (before > 0) & (after == 0)).sum())
