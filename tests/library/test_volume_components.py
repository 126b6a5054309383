"""A sparse volume's components found from its foreground voxels are scipy's, crop for
crop and in scipy's order (the fuller volumes take scipy's pass itself)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from skelprune.grid3d.components import SPARSE, binary_pieces, sparse_components
from skelprune.grid3d.distance import pad


def scipy_pieces(inside: np.ndarray) -> list:
    lab, _ = ndimage.label(inside, structure=np.ones((3, 3, 3), bool))
    return [
        (pad(lab[box] == i), (box[0].start - 1, box[1].start - 1, box[2].start - 1), None)
        for i, box in enumerate(ndimage.find_objects(lab), start=1)
    ]


def same(a: list, b: list) -> bool:
    return len(a) == len(b) and all(
        x[1:] == y[1:] and x[0].dtype == y[0].dtype and np.array_equal(x[0], y[0])
        for x, y in zip(a, b, strict=True)
    )


@pytest.mark.parametrize("seed", range(40))
def test_sparse_volumes_give_scipys_pieces(seed: int) -> None:
    rng = np.random.default_rng(seed)
    shape = tuple(int(n) for n in rng.integers(1, 40, 3))
    inside = rng.random(shape) < rng.uniform(0.002, SPARSE)  # specks, pairs, chains
    if seed % 4 == 0:  # and a tube winding through, touching the border
        t = np.linspace(0, 1, 200)
        z = ((shape[0] - 1) * t).astype(int)
        y = ((shape[1] - 1) * (0.5 + 0.5 * np.sin(7 * t))).astype(int)
        x = ((shape[2] - 1) * (0.5 + 0.5 * np.cos(5 * t))).astype(int)
        inside[z, y, x] = True
    assert same(binary_pieces(inside), scipy_pieces(inside))


def test_a_full_volume_and_an_empty_one() -> None:
    ball = (np.indices((20, 21, 22)) - 10) ** 2
    inside = ball.sum(0) < 64  # over SPARSE: scipy's own pass
    assert same(binary_pieces(inside), scipy_pieces(inside))
    assert binary_pieces(np.zeros((3, 4, 5), bool)) == []
    assert sparse_components(np.zeros(0, np.int64), (3, 4, 5))[1] == 0
