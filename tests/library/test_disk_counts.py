"""Disk-count kernels (skelprune.grid._disk_counts and ._last_cover) and the
redundant-anchor pass against plain per-pixel counts."""

from __future__ import annotations

import importlib

import numpy as np
import pytest

from evaluation.perturb import boundary_noise
from skelprune.api import components
from skelprune.grid._digital import disk_half_width, isqrt
from skelprune.grid._disk_counts import BLOCK, coverage, disk_loss, disk_remove
from skelprune.grid._last_cover import capped_coverage, drop_redundant_anchors, last_cover
from testkit.shapes import blobs, dataset, load

ma = importlib.import_module("skelprune.grid.medial_axis")
disks = importlib.import_module("skelprune.grid._maximal_disks")


def true_counts(cover: np.ndarray, lazy: np.ndarray) -> np.ndarray:
    """The plain count array that ``cover`` and its per-block ``lazy`` increments stand for."""
    return cover + np.repeat(lazy, BLOCK, axis=1)[:, : cover.shape[1]]


def _disk(shape: tuple[int, int], r: int, c: int, v: int) -> np.ndarray:
    out = np.zeros(shape, bool)
    for dy in range(-isqrt(v - 1), isqrt(v - 1) + 1):
        w = disk_half_width(v, dy)
        out[r + dy, c - w : c + w + 1] = True
    return out


def _random_disks(seed: int, h: int = 70, w: int = 83, n: int = 60):
    rng = np.random.default_rng(seed)
    r2s = rng.integers(1, 200, n).astype(np.int64)
    rad = np.array([isqrt(v - 1) for v in r2s])
    rows = np.array([rng.integers(1 + a, h - 1 - a) for a in rad], dtype=np.int64)
    cols = np.array([rng.integers(1 + a, w - 1 - a) for a in rad], dtype=np.int64)
    return rng, rows, cols, r2s, [_disk((h, w), rows[k], cols[k], r2s[k]) for k in range(n)]


@pytest.mark.parametrize("seed", range(4))
def test_block_counts_match_plain_counts(seed):
    rng, rows, cols, r2s, disks = _random_disks(seed)
    h, w = disks[0].shape
    plain = np.sum(disks, axis=0)
    cov = coverage(h, w, rows, cols, r2s)
    assert np.array_equal(true_counts(cov[0], cov[3])[:, :w], plain)
    for k in rng.permutation(len(disks)):
        d = disks[k]
        assert disk_loss(*cov, rows[k], cols[k], r2s[k]) == int((plain[d] == 1).sum())
        if rng.random() < 0.7:
            disk_remove(*cov, rows[k], cols[k], r2s[k])
            plain -= d
            assert np.array_equal(true_counts(cov[0], cov[3])[:, :w], plain)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("cap", [1, 2, 4, 7])
def test_capped_counts_are_plain_counts_capped(seed, cap):
    rng, rows, cols, r2s, disks = _random_disks(seed, n=60 if seed < 3 else 150)
    w = disks[0].shape[1]
    plain = np.sum(disks, axis=0)
    union = np.logical_or.reduce(disks)
    for inside in (union, np.ones_like(union)):  # background pixels: count 0, not capped
        cov = capped_coverage(inside, rows, cols, r2s, cap)
        expected = np.where(inside, np.minimum(plain, cap), 0)
        assert np.array_equal(true_counts(cov[0], cov[3])[:, :w], expected)
        assert not cov[0][:, w:].any()
    # after j <= cap - 2 removals, the pixels counted 1 are those covered once
    cov = capped_coverage(union, rows, cols, r2s, cap)
    for k in rng.permutation(len(disks))[: max(cap - 2, 0)]:
        disk_remove(*cov, rows[k], cols[k], r2s[k])
        plain -= disks[k]
        assert np.array_equal(true_counts(cov[0], cov[3])[:, :w] == 1, plain == 1)
        for j in range(len(disks)):
            if (plain[disks[j]] > 0).all():
                want = int((plain[disks[j]] == 1).sum())
                assert disk_loss(*cov, rows[j], cols[j], r2s[j]) == want


def _thinning_input(crop):
    r2 = ma.squared_distance(crop)
    anchor = ma._anchors(r2, ma._domination_table(r2), ma.VECTORS, ma.VECTOR_KIND)
    ar, ac = np.nonzero(anchor)
    order = np.lexsort((ac, ar, r2[ar, ac]))
    drop_redundant_anchors(anchor, r2, ar[order].astype(np.int64), ac[order].astype(np.int64))
    fg = crop.copy()
    ma._ordered_thinning(fg, r2, anchor, ma.SIMPLE)
    rows, cols = np.nonzero(fg)
    order = np.lexsort((cols, rows, r2[rows, cols]))
    return fg, r2, rows[order].astype(np.int64), cols[order].astype(np.int64)


@pytest.mark.parametrize("case", range(6))
def test_thinning_with_capped_counts_is_the_exact_thinning(case):
    """Capped counts, remade with a larger cap as removals use them up, thin exactly
    as exact counts do (cap 3 is remade after every removal, then at 12 and 48)."""
    masks = dataset("kimia216")
    mask = (
        load(masks[case * 40], factor=2)
        if case < 3
        else boundary_noise(blobs(case, size=90, n=4), "gaussian", 1.5, rng=case, margin=2)
    )
    thinned = 0
    for crop, _ in components(mask):
        fg, r2, rows, cols = _thinning_input(crop)
        exact = fg.copy()
        ma._thin(exact, r2, rows, cols, ma.SIMPLE, ma.DEGREE, 0)
        thinned += int(fg.sum() - exact.sum())
        for cap in (2, 3, 4, 5):
            capped = fg.copy()
            ma._thin(capped, r2, rows, cols, ma.SIMPLE, ma.DEGREE, cap)
            assert np.array_equal(capped, exact), cap
    assert thinned > 0  # the thinning removed something to compare


@pytest.mark.parametrize("seed", range(4))
def test_last_cover_is_the_largest_covering_index(seed):
    _, rows, cols, r2s, disks = _random_disks(seed)
    expected = np.full(disks[0].shape, -1)
    for k, d in enumerate(disks):
        expected[d] = k
    union = np.logical_or.reduce(disks)
    assert np.array_equal(last_cover(union, rows, cols, r2s), expected)
    # tiles holding only background never fill up: still the same answer
    assert np.array_equal(last_cover(np.ones_like(union), rows, cols, r2s), expected)


def _drop_plainly(anchor, r2, rows, cols) -> None:
    """The pass as specified: drop a disk every pixel of which has two live covers."""
    disks = [_disk(anchor.shape, r, c, r2[r, c]) for r, c in zip(rows, cols, strict=True)]
    cover = np.sum(disks, axis=0)
    for (r, c), d in zip(zip(rows, cols, strict=True), disks, strict=True):
        if (cover[d] >= 2).all():
            anchor[r, c] = False
            cover -= d


@pytest.mark.parametrize("case", range(6))
def test_drop_redundant_anchors_matches_plain_counts(case):
    masks = dataset("kimia216")
    mask = (
        load(masks[case * 30])
        if case < 3
        else boundary_noise(blobs(case, size=56, n=5), "gaussian", 1.0, rng=case, margin=2)
    )
    for crop, _ in components(mask):
        r2 = ma.squared_distance(crop)
        anchor = ma._anchors(r2, ma._domination_table(r2[r2 > 0]), ma.VECTORS, ma.VECTOR_KIND)
        ar, ac = np.nonzero(anchor)
        order = np.lexsort((ac, ar, r2[ar, ac]))
        rows, cols = ar[order].astype(np.int64), ac[order].astype(np.int64)
        fast, plain = anchor.copy(), anchor.copy()
        drop_redundant_anchors(fast, r2, rows, cols)
        _drop_plainly(plain, r2, rows, cols)
        assert np.array_equal(fast, plain)
        assert 0 < fast.sum() < anchor.sum()


@pytest.mark.parametrize("size", [1, 2, 64, 256])
def test_domination_table_is_the_containment_threshold(size):
    """``need[R, v]``: the least r2 whose disk at offset ``v`` holds the disk of radius² R,
    worked out here from the definition: test every candidate r2 against every pixel."""
    need = disks._cached_domination_table(size)
    assert need.shape == (size + 1, len(disks._KINDS))
    reach = isqrt(size) + 1
    dy, dx = np.mgrid[-reach : reach + 1, -reach : reach + 1]
    d2 = dy * dy + dx * dx
    for big_r in range(1, size + 1):
        inside = d2 < big_r
        for j, (a, b) in enumerate(disks._KINDS):
            far = ((dy - a) ** 2 + (dx - b) ** 2)[inside]
            least = next(t for t in range(1, 4 * size + 64) if (far < t).all())
            assert need[big_r, j] == least, (big_r, (a, b))
