"""The branch graph of volume skeletons: paths, ends, junctions and cycles against the
shapes' known topology (docs/volumes.md)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage
from skimage.measure import euler_number

from skelprune.grid3d import VolumeGraph, curve_skeleton, lost_volume, step_lengths
from skelprune.grid3d.graph import euler_characteristic
from testkit.volumes import linked_tori, random_blobs, random_tree, torus, tube, y_tubes


def tunnels(v: np.ndarray) -> int:
    """Tunnels of a volume: components + cavities − Euler characteristic."""
    comps = ndimage.label(v, structure=np.ones((3, 3, 3)))[1]
    cavities = ndimage.label(~np.pad(v, 1))[1] - 1
    return comps + cavities - int(euler_number(v, connectivity=3))


def graph_of(v: np.ndarray, spacing=(1.0, 1.0, 1.0)) -> tuple[VolumeGraph, object]:
    sk = curve_skeleton(v, spacing)
    return VolumeGraph(sk.z, sk.y, sk.x, spacing), sk


def check_paths(g: VolumeGraph) -> None:
    """Paths are 26-connected, disjoint, off the junctions, and their step counts are
    their steps, the steps into their junction points included."""
    pts = np.column_stack([g.z, g.y, g.x])
    seen = np.zeros(len(pts), bool)
    for b in range(len(g)):
        path = g.path(b)
        assert path.size and not seen[path].any() and (g.junction_of[path] < 0).all()
        seen[path] = True
        a0, a1 = g.attach[b].tolist()
        chain = [a0] * (a0 >= 0) + path.tolist() + [a1] * (a1 >= 0)
        if g.loop[b] and path.size > 2:
            chain.append(path[0])
        d = np.abs(np.diff(pts[chain], axis=0))
        assert (d.max(axis=1) == 1).all()
        kinds = np.bincount(4 * d[:, 0] + 2 * d[:, 1] + d[:, 2] - 1, minlength=7)
        np.testing.assert_array_equal(kinds, g.steps[b])
    for j, members in enumerate(g.junctions):
        assert (g.junction_of[members] == j).all()
        seen[members] = True
    # what is neither is a dissolved cluster's voxel beside the path through it
    for p in np.flatnonzero(~seen):
        assert (np.abs(pts - pts[p]).max(axis=1)[g.path_points] == 1).any()


def test_tube_is_one_branch_end_to_end() -> None:
    s = tube(length=40, radius=4)
    g, sk = graph_of(s.volume())
    check_paths(g)
    assert (len(g), g.n_endpoints, len(g.junctions), g.n_cycles) == (1, 2, 0, 0)
    ends = np.column_stack([sk.z, sk.y, sk.x])[g.end_points()]
    tips = s.tip_voxels()
    assert np.abs(np.sort(ends[:, 2]) - np.sort(tips[:, 2])).max() <= 2
    assert abs(g.length()[0] - 40) <= 4


def test_torus_is_one_cycle() -> None:
    for tilt in (0.0, 0.6):
        g, _ = graph_of(torus(tilt=tilt).volume())
        check_paths(g)
        assert (g.n_endpoints, g.n_cycles, g.n_components) == (0, 1, 1)
        assert g.loop.sum() == 1


def test_two_fused_rings_give_two_cycles() -> None:
    v = linked_tori().volume()
    g, _ = graph_of(v)
    check_paths(g)
    assert tunnels(v) == 2
    assert (g.n_endpoints, g.n_cycles, g.n_components) == (0, 2, 1)


def test_y_of_tubes_has_three_ends_and_one_junction() -> None:
    s = y_tubes()
    g, sk = graph_of(s.volume())
    check_paths(g)
    assert (len(g), g.n_endpoints, len(g.junctions), g.n_cycles) == (3, 3, 1, 0)
    ends = np.column_stack([sk.z, sk.y, sk.x])[g.end_points()]
    dist = np.linalg.norm(ends[:, None, :] - s.tip_voxels()[None, :, :], axis=2)
    assert dist.min(axis=0).max() <= 2.0  # every tip has an end point beside it


def test_stretched_tube_keeps_its_topology_and_length() -> None:
    """One physical tube sampled at two resolutions along z."""
    for axis_spacing in [(1.0, 1.0, 1.0), (3.0, 1.0, 1.0), (1.0, 1.0, 3.0)]:
        s = tube(length=45, radius=6, spacing=axis_spacing)
        v = s.volume()
        g, sk = graph_of(v, axis_spacing)
        check_paths(g)
        assert (len(g), g.n_endpoints, len(g.junctions), g.n_cycles) == (1, 2, 0, 0)
        assert abs(g.length()[0] - 45) <= 7, axis_spacing
        assert lost_volume(v, sk.z, sk.y, sk.x, sk.r2, axis_spacing) <= 0.05 * v.sum()


@pytest.mark.parametrize("spacing", [(1.0, 1.0, 1.0), (3.0, 1.0, 1.0)])
def test_random_trees_cycles_are_the_volume_tunnels(spacing) -> None:
    for seed in range(3):
        s = random_tree(seed, size=64, spacing=spacing)
        v = s.volume()
        g, _ = graph_of(v, spacing)
        check_paths(g)
        assert g.n_components == 1
        assert g.n_cycles == tunnels(v)


def test_random_volumes_cycles_are_the_volume_tunnels() -> None:
    for seed in range(20):
        v = ndimage.binary_fill_holes(random_blobs(seed))  # no cavities: a curve skeleton
        g, _ = graph_of(v)
        check_paths(g)
        assert g.n_cycles == tunnels(v)
        assert g.n_components == ndimage.label(v, structure=np.ones((3, 3, 3)))[1]


def test_euler_characteristic_matches_skimage() -> None:
    rng = np.random.default_rng(3)
    for density in (0.05, 0.2, 0.5, 0.8):
        for _ in range(5):
            v = rng.random((7, 8, 9)) < density
            z, y, x = np.nonzero(v)
            assert euler_characteristic(z, y, x) == euler_number(v, connectivity=3)


def test_lengths_are_in_physical_units() -> None:
    z = np.array([0, 1, 2, 2])
    y = np.array([0, 0, 1, 2])
    x = np.array([0, 0, 0, 1])
    g = VolumeGraph(z, y, x, spacing=(3.0, 2.0, 1.0))
    assert len(g) == 1 and g.n_endpoints == 2
    expected = 3.0 + np.hypot(3.0, 2.0) + np.hypot(2.0, 1.0)
    assert g.length()[0] == pytest.approx(expected)
    assert g.length()[0] == g.steps[0] @ step_lengths((3.0, 1.0 * 2, 1.0))
