"""The medial axis's order of its pixels by radius: a stable sort of the raster order,
whichever sort makes it (a counting sort for radii close together, a merge sort for
radii far apart)."""

from __future__ import annotations

import importlib

import numpy as np
import pytest

ma = importlib.import_module("skelprune.grid.medial_axis")


def _expected(fg: np.ndarray, r2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    rows, cols = np.nonzero(fg)
    order = np.lexsort((cols, rows, r2[rows, cols]))
    return rows[order], cols[order]


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("top", [3, 40, 10**6])
def test_pixels_by_radius_are_the_stable_sort(seed: int, top: int) -> None:
    """Many ties (top 3), few (40), radii spread far beyond the pixels (10**6: the
    merge sort's branch)."""
    rng = np.random.default_rng(seed)
    h, w = (int(v) for v in rng.integers(2, 60, 2))
    fg = rng.random((h, w)) < rng.random()
    r2 = np.where(fg, rng.integers(1, top + 1, (h, w)), 0).astype(np.int64)
    rows, cols = ma._by_radius(fg, r2)
    want_rows, want_cols = _expected(fg, r2)
    assert np.array_equal(rows, want_rows) and np.array_equal(cols, want_cols)


def test_pixels_by_radius_of_an_empty_mask() -> None:
    fg = np.zeros((4, 5), bool)
    rows, cols = ma._by_radius(fg, np.zeros((4, 5), np.int64))
    assert rows.size == 0 and cols.size == 0
