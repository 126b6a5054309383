"""One branch graph in any dimension: a plane skeleton laid in a volume is the same graph."""

from __future__ import annotations

import math

import numpy as np
import pytest

from skelprune.grid.graph import BranchGraph
from skelprune.grid3d.graph import VolumeBranchGraph
from skelprune.pruning.branch_graph import GridSteps, PointGraph
from skelprune.pruning.grid import path_length
from skelprune.skeleton import Skeleton
from testkit.shapes import dataset, load


def branch_sets(g: PointGraph) -> list[tuple[frozenset[int], bool]]:
    """Each live branch as its point set and whether it is a loop, sorted."""
    out = [(frozenset(br.points), br.loop) for br in g.branches if br.alive]
    return sorted(out, key=lambda s: (sorted(s[0]), s[1]))


def junction_sets(g: PointGraph) -> list[frozenset[int]]:
    return sorted((frozenset(j.points) for j in g.junctions if j.alive), key=sorted)


def lengths(g: PointGraph) -> list[float]:
    return sorted(path_length(br.steps, g.weights) for br in g.branches if br.alive)


def same_graph(plane: BranchGraph, volume: VolumeBranchGraph) -> None:
    assert branch_sets(plane) == branch_sets(volume)
    assert junction_sets(plane) == junction_sets(volume)
    assert lengths(plane) == lengths(volume)
    assert plane.alive_points().tolist() == volume.alive_points().tolist()
    assert plane.n_endpoints() == volume.n_endpoints()
    assert plane.total_length() == volume.total_length()
    # in the plane the one sum is na + nd·√2 bit for bit
    na, nd = plane.total_steps()
    assert plane.total_length() == na + nd * math.sqrt(2.0)


@pytest.mark.parametrize("name", [p.stem for p in dataset("kimia99")[::9]])
def test_a_plane_skeleton_in_a_volume_is_the_same_graph(name: str) -> None:
    # The pixel grid's 8 neighbours and the voxel grid's 26 at z = 0 are the same
    # neighbours in another slot order: the one graph must find the same branches,
    # junctions and lengths, and the same skeleton after the same removals.
    (path,) = [p for p in dataset("kimia99") if p.stem == name]
    sk = Skeleton.medial_axis(np.pad(load(path), 1))
    plane = sk.working_graph()
    volume = VolumeBranchGraph(np.zeros_like(sk.rows), sk.rows, sk.cols)
    same_graph(plane, volume)
    removed = 0
    while plane.end_branches() and removed < 40:
        # the end branch whose free end comes first, in both graphs
        p = min(plane.endpoint(b) for b in plane.end_branches())
        (bp,) = [b for b in plane.end_branches() if plane.endpoint(b) == p]
        (bv,) = [b for b in volume.end_branches() if volume.endpoint(b) == p]
        assert plane.counts_without(bp)[1] == volume.counts_without(bv)[2]  # diagonal steps
        plane.remove_end_branch(bp)
        volume.remove_end_branch(bv)
        removed += 1
        same_graph(plane, volume)
    assert removed > 0


def test_the_graph_needs_no_grid() -> None:
    # a ring of four points (0-1-2-3) with a tail (3-4), on no grid: one kind of step
    nbr = np.array([[1, 3, -1], [0, 2, -1], [1, 3, -1], [2, 0, 4], [3, -1, -1]])
    g = PointGraph(nbr, GridSteps(np.zeros(3, np.int64), np.ones(1)))
    assert [(br.points, br.node) for br in g.branches] == [([2, 1, 0], [0, 0]), ([4], [0, None])]
    assert g.end_branches() == [1] and g.total_steps() == (5,)
    copy = g.copy()
    assert copy.remove_end_branch(1) == (0, 0, 0)  # the ring closes through the junction
    assert g.total_steps() == (5,) and copy.total_steps() == (4,)
    assert [br.loop for br in copy.branches if br.alive] == [True]
    assert copy.alive_points().tolist() == [0, 1, 2, 3] and copy.n_endpoints() == 0
