"""Run sets (skelprune.grid._intervals) and the owner coverage, against brute-force painting."""

from __future__ import annotations

import numpy as np
import pytest

from skelprune.grid._intervals import disk_runs, owner_runs, union
from skelprune.grid.coverage import Coverage
from skelprune.grid.reconstruction import reconstruction
from testkit.oracle import disk_pixels

SHAPE = (48, 56)


def to_mask(runs: np.ndarray, shape=SHAPE) -> np.ndarray:
    out = np.zeros(shape, bool)
    for r, lo, hi in runs:
        out[r, lo : hi + 1] = True
    return out


def to_runs(mask: np.ndarray) -> np.ndarray:
    """The canonical run set of a mask, by brute force."""
    runs = []
    for r, row in enumerate(mask):
        padded = np.concatenate([[False], row, [False]])
        edges = np.flatnonzero(padded[1:] != padded[:-1])
        runs += [(r, a, b - 1) for a, b in zip(edges[::2], edges[1::2], strict=True)]
    return np.array(runs, np.int64).reshape(-1, 3)


def random_disks(rng: np.random.Generator, n: int, walk: bool):
    """Disks inside SHAPE: a random walk (like a branch) or scattered centres."""
    if walk:
        steps = rng.integers(-1, 2, size=(n, 2))
        pts = np.cumsum(steps, axis=0) + np.array(SHAPE) // 2
    else:
        pts = np.stack(
            [rng.integers(12, SHAPE[0] - 12, n), rng.integers(12, SHAPE[1] - 12, n)], axis=1
        )
    pts = np.clip(pts, 12, [SHAPE[0] - 13, SHAPE[1] - 13]).astype(np.int64)
    r2 = rng.integers(1, 120, n).astype(np.int64)
    return pts[:, 0].copy(), pts[:, 1].copy(), r2


def random_mask(rng: np.random.Generator, p: float) -> np.ndarray:
    m = rng.random(SHAPE) < p
    # Some long runs besides scattered pixels.
    for _ in range(5):
        r, a = rng.integers(0, SHAPE[0]), rng.integers(0, SHAPE[1])
        m[r, a : a + rng.integers(1, 30)] = True
    return m


@pytest.mark.parametrize("seed", range(20))
def test_disk_runs_equal_painted_union(seed):
    rng = np.random.default_rng(seed)
    rows, cols, r2 = random_disks(rng, int(rng.integers(1, 30)), walk=seed % 2 == 0)
    pts = np.arange(rows.size)
    runs = disk_runs(rows, cols, r2, pts)
    np.testing.assert_array_equal(runs, to_runs(reconstruction(SHAPE, rows, cols, r2)))
    some = pts[::3]
    np.testing.assert_array_equal(
        disk_runs(rows, cols, r2, some),
        to_runs(reconstruction(SHAPE, rows[some], cols[some], r2[some])),
    )


def test_disk_runs_match_the_oracle_disks():
    rows, cols, r2 = np.array([20]), np.array([20]), np.array([50])
    flat = np.zeros(SHAPE[0] * SHAPE[1], bool)
    flat[disk_pixels(rows, cols, r2, SHAPE)[0]] = True
    np.testing.assert_array_equal(
        to_mask(disk_runs(rows, cols, r2, np.arange(1))), flat.reshape(SHAPE)
    )


@pytest.mark.parametrize("seed", range(10))
def test_owner_runs_one_union_per_label(seed):
    rng = np.random.default_rng(100 + seed)
    rows, cols, r2 = random_disks(rng, 40, walk=True)
    labels = rng.integers(1, 6, rows.size)
    runs, off = owner_runs(rows, cols, r2, labels, 7)
    assert off[0] == off[1] == 0 and off[7] == runs.shape[0]
    for b in range(7):
        sel = labels == b
        np.testing.assert_array_equal(
            runs[off[b] : off[b + 1]], to_runs(reconstruction(SHAPE, rows[sel], cols[sel], r2[sel]))
        )


@pytest.mark.parametrize("seed", range(20))
def test_union(seed):
    rng = np.random.default_rng(200 + seed)
    a = random_mask(rng, 0.3 if seed % 2 else 0.05)
    b = random_mask(rng, 0.5 if seed % 3 else 0.02)
    ra, rb = to_runs(a), to_runs(b)
    np.testing.assert_array_equal(union(ra, rb), to_runs(a | b))
    np.testing.assert_array_equal(union(rb, ra), to_runs(a | b))
    np.testing.assert_array_equal(union(ra, ra[:0]), ra)
    np.testing.assert_array_equal(union(rb[:0], rb), rb)


def brute_state(rows, cols, r2, labels, alive, n_labels):
    """Owners per pixel, exclusive areas and lost area, painted from scratch."""
    sets = np.zeros((n_labels, *SHAPE), bool)
    for b in range(n_labels):
        sel = alive & (labels == b)
        sets[b] = reconstruction(SHAPE, rows[sel], cols[sel], r2[sel])
    count = sets.sum(axis=0)
    owner = sets.argmax(axis=0)
    exclusive = np.bincount(owner[count == 1], minlength=n_labels)
    return count, exclusive, int((count == 0).sum())


@pytest.mark.parametrize("tile", [4, 8, 32])
@pytest.mark.parametrize("seed", range(16))
def test_coverage_against_brute_force(seed, tile):
    """Random removals and merges of whole owners keep the exact coverage: the counts of
    the open tiles, two owners or more in the closed ones, the exclusive and lost areas."""
    rng = np.random.default_rng(300 + seed)
    n_labels = 8
    rows, cols, r2 = random_disks(rng, 60, walk=seed % 2 == 0)
    labels = rng.integers(1, n_labels, rows.size)
    mask = np.ones(SHAPE, bool)
    cov = Coverage(mask, rows, cols, r2, labels, n_labels, tile=tile)
    alive = np.ones(rows.size, bool)
    labels = labels.copy()

    def check():
        count, exclusive, lost = brute_state(rows, cols, r2, labels, alive, n_labels)
        counts = cov.counts()
        shut = counts == -1
        np.testing.assert_array_equal(counts[~shut], count[~shut])
        assert (count[shut] >= 2).all()
        np.testing.assert_array_equal(cov.uncovered(), np.flatnonzero(count == 0))
        live = np.unique(labels[alive])
        np.testing.assert_array_equal(cov.exclusive[live], exclusive[live])
        assert cov.lost == lost

    check()
    while np.unique(labels[alive]).size > 1:
        live = np.unique(labels[alive])
        a, b = rng.choice(live, 2, replace=False)
        pts = np.flatnonzero(alive & (labels == a))
        if rng.random() < 0.5:
            before = cov.lost
            gone = cov.remove_label(int(a))
            assert gone == cov.lost - before
            alive[pts] = False
        else:
            cov.merge_label(int(a), int(b))
            labels[pts] = b
        check()
