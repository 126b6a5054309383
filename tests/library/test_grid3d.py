"""The volume grid: distances, balls and the curve skeleton against naive references
and the topology of synthetic volumes (docs/volumes.md)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage
from skimage.measure import euler_number

from skelprune.errors import EmptyMaskError, InvalidImageError, InvalidOptionError
from skelprune.grid3d import (
    OFFSETS,
    ball_counts,
    curve_skeleton,
    exclusive_volume,
    lost_volume,
    reconstruction,
    squared_distance,
)
from skelprune.grid3d._topology import ADJ6, ADJ26, FACES, N18, is_simple
from testkit import volume_oracle as oracle
from testkit.volumes import ball, random_blobs, random_tree, tube

SPACINGS = [(1.0, 1.0, 1.0), (3.0, 1.0, 1.0), (0.7, 1.3, 0.4)]


def noise(seed: int, shape=(10, 11, 12), density: float = 0.6) -> np.ndarray:
    """Voxel noise: many components, tunnels and cavities."""
    return np.random.default_rng(seed).random(shape) < density


def naive_simple(cube: np.ndarray) -> bool:
    """Simple point test on a 3×3×3 cube by labelling, as the definition reads."""
    fg = cube.copy()
    fg[1, 1, 1] = False
    n26 = ndimage.label(fg, structure=np.ones((3, 3, 3)))[1]
    n18 = np.ones((3, 3, 3), bool)
    n18[[0, 0, 0, 0, 2, 2, 2, 2], [0, 0, 2, 2, 0, 0, 2, 2], [0, 2, 0, 2, 0, 2, 0, 2]] = False
    bg = ~cube & n18
    bg[1, 1, 1] = False
    lab, _ = ndimage.label(bg, structure=ndimage.generate_binary_structure(3, 1))
    faces = [(0, 1, 1), (2, 1, 1), (1, 0, 1), (1, 2, 1), (1, 1, 0), (1, 1, 2)]
    touching = {lab[f] for f in faces if lab[f] > 0}
    return n26 == 1 and len(touching) == 1


def code_of(cube: np.ndarray) -> int:
    return sum(1 << i for i, o in enumerate(OFFSETS) if cube[tuple(o + 1)])


def test_simple_point_test_matches_its_definition() -> None:
    rng = np.random.default_rng(0)
    for density in (0.1, 0.3, 0.5, 0.7, 0.9):
        for _ in range(400):
            cube = rng.random((3, 3, 3)) < density
            cube[1, 1, 1] = True
            assert is_simple(code_of(cube), ADJ26, ADJ6, N18, FACES) == naive_simple(cube)


@pytest.mark.parametrize("spacing", SPACINGS)
def test_squared_distance_is_the_brute_force_minimum(spacing) -> None:
    for seed in range(3):
        v = random_blobs(seed, (8, 9, 10)) | noise(seed, (8, 9, 10), 0.3)
        got = squared_distance(v, spacing)
        want = oracle.squared_distance(v, spacing)
        np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("spacing", SPACINGS)
def test_union_of_all_balls_is_the_volume(spacing) -> None:
    for seed in range(4):
        v = random_blobs(seed)
        r2 = squared_distance(v, spacing)
        z, y, x = np.nonzero(v)
        assert np.array_equal(reconstruction(v.shape, z, y, x, r2[z, y, x], spacing), v)


@pytest.mark.parametrize("spacing", SPACINGS)
def test_ball_counts_and_lost_volume_match_painting_from_scratch(spacing) -> None:
    rng = np.random.default_rng(1)
    for seed in range(4):
        v = random_blobs(seed)
        r2 = squared_distance(v, spacing)
        z, y, x = np.nonzero(v)
        pick = rng.random(z.size) < 0.05
        z, y, x = z[pick], y[pick], x[pick]
        want = oracle.ball_counts(v.shape, z, y, x, r2[z, y, x], spacing)
        got = ball_counts(v.shape, z, y, x, r2[z, y, x], spacing)
        np.testing.assert_array_equal(got, want)
        assert lost_volume(v, z, y, x, r2[z, y, x], spacing) == oracle.lost_volume(
            v, z, y, x, r2[z, y, x], spacing
        )
        # balls of any radius, partly outside the array: clipped, never wrapped
        big = rng.uniform(0.5, 60.0, z.size)
        np.testing.assert_array_equal(
            ball_counts(v.shape, z, y, x, big, spacing),
            oracle.ball_counts(v.shape, z, y, x, big, spacing),
        )


def test_exclusive_volume_is_what_removing_the_balls_loses() -> None:
    v = random_blobs(5)
    sk = curve_skeleton(v)
    counts = ball_counts(v.shape, sk.z, sk.y, sk.x, sk.r2)
    before = lost_volume(v, sk.z, sk.y, sk.x, sk.r2)
    rng = np.random.default_rng(2)
    for _ in range(5):
        gone = rng.random(len(sk)) < 0.3
        after = lost_volume(v, sk.z[~gone], sk.y[~gone], sk.x[~gone], sk.r2[~gone])
        lost = exclusive_volume(counts, v, sk.z[gone], sk.y[gone], sk.x[gone], sk.r2[gone])
        assert lost == after - before


def skeleton_is_thin(mask: np.ndarray) -> bool:
    """Every voxel is a curve end point or not simple in the skeleton."""
    padded = np.pad(mask, 1)
    for p in np.argwhere(padded):
        cube = padded[p[0] - 1 : p[0] + 2, p[1] - 1 : p[1] + 2, p[2] - 1 : p[2] + 2]
        if cube.sum() - 1 != 1 and naive_simple(cube):
            return False
    return True


def components(mask: np.ndarray) -> int:
    return int(ndimage.label(mask, structure=np.ones((3, 3, 3)))[1])


@pytest.mark.parametrize("spacing", SPACINGS)
@pytest.mark.parametrize("make", [random_blobs, noise])
def test_skeleton_is_thin_homotopic_and_on_the_distance_map(make, spacing) -> None:
    for seed in range(6):
        v = make(seed)
        sk = curve_skeleton(v, spacing)
        mask = sk.mask()
        assert np.all(v[sk.z, sk.y, sk.x])
        np.testing.assert_array_equal(sk.r2, squared_distance(v, spacing)[sk.z, sk.y, sk.x])
        assert skeleton_is_thin(mask)
        assert components(mask) == components(v)
        # same components, tunnels and cavities: the same Euler characteristic
        assert euler_number(mask, connectivity=3) == euler_number(v, connectivity=3)


def test_cavity_leaves_a_closed_shell() -> None:
    grid = np.indices((21, 21, 21)) - 10
    d2 = (grid**2).sum(0)
    hollow = (d2 < 81) & (d2 >= 9)  # a ball with a ball-shaped cavity
    sk = curve_skeleton(hollow)
    mask = sk.mask()
    assert euler_number(mask, connectivity=3) == 2  # a sphere: one component, one cavity
    inside = ndimage.binary_fill_holes(mask) & ~mask
    assert inside[10, 10, 10]


def test_ball_gives_a_point_that_reconstructs_it() -> None:
    s = ball(7.5)
    v = s.volume()
    sk = curve_skeleton(v)
    centre = tuple(np.rint(s.tip_voxels()[0]).astype(int))
    assert list(zip(sk.z, sk.y, sk.x, strict=True)) == [centre]
    assert lost_volume(v, sk.z, sk.y, sk.x, sk.r2) == 0


def test_random_tree_skeleton_keeps_topology_and_reconstructs_most() -> None:
    for seed in range(3):
        s = random_tree(seed, size=64)
        v = s.volume()
        sk = curve_skeleton(v, s.spacing)
        assert components(sk.mask()) == components(v) == 1
        assert euler_number(sk.mask(), connectivity=3) == euler_number(v, connectivity=3)
        assert lost_volume(v, sk.z, sk.y, sk.x, sk.r2, s.spacing) <= 0.15 * v.sum()


def test_thick_tube_reconstructs_almost_exactly() -> None:
    v = tube(length=40, radius=6).volume()
    sk = curve_skeleton(v)
    assert lost_volume(v, sk.z, sk.y, sk.x, sk.r2) <= 0.02 * v.sum()


def test_bad_input_gets_a_clear_error() -> None:
    with pytest.raises(InvalidImageError, match="3-D"):
        curve_skeleton(np.ones((4, 4), bool))
    with pytest.raises(EmptyMaskError):
        curve_skeleton(np.zeros((4, 4, 4), bool))
    for bad in [(1, 1), (1, 0, 1), (1, float("nan"), 1), "abc", None]:
        with pytest.raises(InvalidOptionError, match="spacing"):
            curve_skeleton(np.ones((4, 4, 4), bool), bad)
