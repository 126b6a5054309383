"""The squared distance transform is scipy's exact one, squared and rounded, to the pixel."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from skelprune.grid.medial_axis import squared_distance
from testkit.shapes import dataset, load


def _reference(mask: np.ndarray) -> np.ndarray:
    d = ndimage.distance_transform_edt(mask)
    return np.rint(d * d).astype(np.int64)


@pytest.mark.parametrize("seed", range(6))
def test_random_masks_of_every_density(seed: int) -> None:
    rng = np.random.default_rng(seed)
    for _ in range(40):
        h, w = (int(v) for v in rng.integers(1, 70, 2))
        mask = rng.random((h, w)) < rng.random()  # shapes touching the border too
        assert np.array_equal(squared_distance(mask), _reference(mask)), (h, w)


def test_dataset_shapes_and_a_large_disk() -> None:
    for path in dataset("kimia99")[::7]:
        padded = np.pad(load(path), 1)
        assert padded.ndim == 2 and padded.any()
        assert np.array_equal(squared_distance(padded), _reference(padded))
    yy, xx = np.mgrid[:700, :700]
    disk = (yy - 349.5) ** 2 + (xx - 349.5) ** 2 < 340**2
    assert np.array_equal(squared_distance(disk), _reference(disk))


def test_no_background_follows_scipy() -> None:
    full = np.ones((5, 7), bool)
    assert np.array_equal(squared_distance(full), _reference(full))
    assert not squared_distance(np.zeros((3, 3), bool)).any()
