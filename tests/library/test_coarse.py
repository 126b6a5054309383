"""The coarse stage of ``prune(coarse="dce")``: roughness-raised DCE stop, one branch per
convex vertex (``skelprune/grid/coarse.py``)."""

from __future__ import annotations

import numba
import numpy as np
import pytest

from evaluation.perturb import boundary_noise, noisy_rectangle
from skelprune.api import components
from skelprune.grid._generating import SegmentRaster, rim_label_set
from skelprune.grid.coarse import (
    COARSE_VERTICES,
    ROUGHNESS_FLOOR,
    boundary_roughness,
    coarse_partition,
    coarse_removals,
    coarse_threshold,
)
from skelprune.grid.dce import (
    COARSE_PIXEL_THRESHOLD,
    boundary_partition,
    generated_in_several_segments,
    generating_segments,
    remove_unsupported,
)
from skelprune.grid.graph import BranchGraph
from skelprune.grid.medial_axis import medial_axis, squared_distance
from testkit.shapes import dataset, load

SHAPES = dataset("kimia216")[::6] + dataset("kimia99")[::6]


def _axis(mask: np.ndarray):
    crop, _ = max(components(mask), key=lambda c: int(c[0].sum()))
    return crop, medial_axis(crop, squared_distance(crop))


def test_clean_silhouettes_keep_about_the_base_threshold():
    """Most clean shapes stay under the floor; the roughest (a fork's tines, an
    aircraft's many corners) get at most a pixel or two more."""
    rough = np.array([boundary_roughness(load(p)) for p in SHAPES])
    assert np.median(rough) < ROUGHNESS_FLOOR / 1.5
    assert np.mean(rough < ROUGHNESS_FLOOR) >= 0.85
    assert max(coarse_threshold(load(p)) for p in SHAPES) <= COARSE_PIXEL_THRESHOLD + 2.0


@pytest.mark.parametrize("kind,scale", [("gaussian", 1.0), ("gaussian", 1.5), ("uniform", 1.0)])
def test_boundary_noise_raises_roughness_and_threshold(kind, scale):
    clean = [load(p) for p in SHAPES[::4]]
    noisy = [boundary_noise(m, kind, scale, rng=k, margin=2) for k, m in enumerate(clean)]
    for c, n in zip(clean, noisy, strict=True):
        assert boundary_roughness(n) > max(boundary_roughness(c), ROUGHNESS_FLOOR)
        assert coarse_threshold(n) > coarse_threshold(c)
    assert np.median([coarse_threshold(n) for n in noisy]) > 2 * COARSE_PIXEL_THRESHOLD


def test_the_vertex_budget_bounds_every_polygon():
    """A large boundary with many relevant bumps keeps at most the budget; a clean shape
    with few relevant vertices keeps few (the budget is a cap, not a target)."""
    from evaluation.perturb import resampled_noise

    rr, cc = np.mgrid[:400, :400]
    radius = np.hypot(rr - 200, cc - 200)
    wavy = radius < 170 + 6 * np.sin(np.arctan2(rr - 200, cc - 200) * 40)
    for mask in (wavy, resampled_noise(wavy, 1.5, rng=0)):
        unbounded = boundary_partition(mask, pixel_threshold=coarse_threshold(mask))
        assert max(len(v) for v in unbounded.vertices) > COARSE_VERTICES
        assert max(len(v) for v in coarse_partition(mask).vertices) <= COARSE_VERTICES
    square = np.zeros((60, 60), bool)
    square[10:50, 10:50] = True
    assert [len(v) for v in coarse_partition(square).vertices] == [4]


def test_shapes_with_few_convex_vertices_are_pruned_without_error():
    """A round hole has no vertex convex towards the shape (one segment), and pruning
    goes on; a small disk and a thin ellipse get their one or two ends."""
    import skelprune

    rr, cc = np.mgrid[:80, :120]
    dist = np.hypot(rr - 40, cc - 60)
    ring = (dist < 30) & (dist >= 12)
    part = coarse_partition(ring)
    assert [int(c.sum()) for c in part.convex][1] == 0  # the hole: one segment
    disk = np.hypot(rr - 40, cc - 60) < 5
    ellipse = ((rr - 40) / 4.0) ** 2 + ((cc - 60) / 20.0) ** 2 < 1
    for mask, most in ((ring, 0), (disk, 1), (ellipse, 2)):
        comp = skelprune.prune(mask).components[0]
        assert comp.graph.n_endpoints() <= most
        assert comp.rer < 0.05


def test_roughness_of_degenerate_masks():
    assert boundary_roughness(np.zeros((5, 5), bool)) == 0.0
    one = np.zeros((5, 5), bool)
    one[2, 2] = True
    assert boundary_roughness(one) == 1.0  # the opening removes the single pixel


def test_generating_segments_agrees_with_the_support_test():
    crop, ma = _axis(load(SHAPES[3], factor=2))
    part = boundary_partition(crop, pixel_threshold=COARSE_PIXEL_THRESHOLD)
    pts = np.stack([ma.rows, ma.cols], axis=1)
    labels = generating_segments(pts, ma.r2, part)
    assert labels.shape == (len(pts), 3)
    np.testing.assert_array_equal(
        labels[:, 1] != -1, generated_in_several_segments(pts, ma.r2, part)
    )
    assert ((labels >= -1) & (labels < part.n_segments)).all()
    assert (labels[:, 0] >= 0).all()  # every disk touches the boundary somewhere
    # ids are distinct within a row
    for a, b in ((0, 1), (0, 2), (1, 2)):
        both = (labels[:, a] >= 0) & (labels[:, b] >= 0)
        assert (labels[both, a] != labels[both, b]).all()


@pytest.mark.parametrize("kind,scale", [("gaussian", 1.0), ("gaussian", 1.5), ("uniform", 1.5)])
@pytest.mark.parametrize("seed", range(3))
def test_noisy_rectangle_gets_one_branch_per_corner(kind, scale, seed):
    """The paper's Table 2 setting: 4 endpoints, one at each corner, after both stages
    (the coarse stage before the paper's argmin; the default gets 4 as well: test_margin)."""
    import skelprune

    mask, _ = noisy_rectangle(60, 160, kind, scale, rng=seed)
    comp = skelprune.prune(mask, coarse="dce", choice="argmin").components[0]
    ends = comp.to_dict()["skeleton"]["endpoints"]
    assert len(ends) == 4
    h, w = mask.shape
    corners = {
        (n["y"] > h / 2, n["x"] > w / 2)
        for n in comp.to_dict()["skeleton"]["nodes"]
        if n["id"] in ends
    }
    assert len(corners) == 4


def test_the_corner_rule_is_what_removes_forks():
    """Support alone leaves forks at the corners of these rectangles; the rule removes them."""
    forked = 0
    for seed in range(5):
        mask, _ = noisy_rectangle(60, 160, "gaussian", 1.5, rng=seed)
        crop, ma = _axis(mask)
        part = coarse_partition(crop)
        support_only = BranchGraph(ma.rows, ma.cols, crop.shape)
        labels = generating_segments(np.stack([ma.rows, ma.cols], axis=1), ma.r2, part)
        remove_unsupported(support_only, labels[:, 1] != -1)
        full = BranchGraph(ma.rows, ma.cols, crop.shape)
        coarse_removals(full, crop, ma.r2)
        assert full.n_endpoints() <= support_only.n_endpoints()
        forked += support_only.n_endpoints() > full.n_endpoints()
    assert forked >= 3


@pytest.mark.parametrize("path", SHAPES[::3], ids=lambda p: p.stem)
def test_coarse_removals_replay_and_keep_topology(path):
    mask = boundary_noise(load(path), "gaussian", 1.0, rng=1, margin=2)
    crop, ma = _axis(mask)
    graph = BranchGraph(ma.rows, ma.cols, crop.shape)
    before_ends = graph.n_endpoints()
    removed = coarse_removals(graph, crop, ma.r2)
    assert removed and graph.n_endpoints() < before_ends
    replay = BranchGraph(ma.rows, ma.cols, crop.shape)
    for b in removed:
        replay.remove_end_branch(b)
    np.testing.assert_array_equal(np.sort(graph.alive_points()), np.sort(replay.alive_points()))
    # a tree stays one tree: points alive form one 8-connected component
    from scipy import ndimage

    img = np.zeros(crop.shape, bool)
    alive = graph.alive_points()
    img[graph.rows[alive], graph.cols[alive]] = True
    assert ndimage.label(img, np.ones((3, 3), bool))[1] == 1


@pytest.mark.parametrize("seed", range(6))
def test_roughness_counts_equal_scipy_morphology(seed):
    from scipy import ndimage

    rng = np.random.default_rng(seed)
    if seed < 3:
        mask = boundary_noise(load(SHAPES[seed * 7]), "uniform", 1.5, rng=seed, margin=2)
    else:
        mask = ndimage.binary_opening(rng.random((40, 50)) < 0.6) | (rng.random((40, 50)) < 0.05)
    cross = ndimage.generate_binary_structure(2, 1)
    m = np.pad(mask, 2)
    perimeter = np.count_nonzero(m & ~ndimage.binary_erosion(m, cross))
    changed = np.count_nonzero(m & ~ndimage.binary_opening(m, cross)) + np.count_nonzero(
        ndimage.binary_closing(m, cross) & ~m
    )
    assert boundary_roughness(mask) == pytest.approx(changed / perimeter, abs=0)


def reference_coarse(graph: BranchGraph, crop: np.ndarray, r2: np.ndarray) -> list[int]:
    """The coarse stage as the module docstring states it, with every rim scanned up front.

    The library scans rims lazily and settles several branches per compiled call; this
    reads the generating segments of every point of ``M`` and applies the two rules
    branch by branch.
    """
    from skelprune.grid.coarse import _convex_vertices

    part = coarse_partition(crop)
    labels = generating_segments(np.stack([graph.rows, graph.cols], axis=1), r2, part)
    supported = labels[:, 1] != -1
    before, after, positions = _convex_vertices(part)
    meet = {}
    for v, (a, b) in enumerate(zip(before.tolist(), after.tolist(), strict=True)):
        meet[(a, b)] = meet[(b, a)] = v

    def claim(b: int) -> int:
        """The convex vertex whose two segments are all that generate branch ``b``."""
        segs = set()
        for p in graph.branches[b].points:
            segs.update(s for s in labels[p].tolist() if s >= 0)
            if labels[p, 2] != -1:
                return -1
        vertices = {
            meet.get((int(labels[p, 0]), int(labels[p, 1])), -2)
            for p in graph.branches[b].points
            if labels[p, 1] != -1
        }
        if len(vertices) != 1 or -2 in vertices:
            return -1
        v = vertices.pop()
        return v if segs <= {int(before[v]), int(after[v])} else -1

    removed = remove_unsupported(graph, supported)
    while True:
        by_vertex: dict[int, list[tuple[float, int]]] = {}
        for b in graph.end_branches():
            v = claim(b)
            if v >= 0:
                p = graph.endpoint(b)
                d2 = float(
                    (graph.rows[p] - positions[v, 0]) ** 2 + (graph.cols[p] - positions[v, 1]) ** 2
                )
                by_vertex.setdefault(v, []).append((d2, b))
        surplus = [b for c in by_vertex.values() if len(c) > 1 for _, b in sorted(c)[1:]]
        if not surplus:
            return removed
        merged = graph.remove_end_branch(surplus[0])
        removed.append(surplus[0])
        if merged is not None:
            removed += remove_unsupported(graph, supported, candidates=[merged[0]])


def _coarse_cases():
    from testkit.shapes import blobs, rectangle_with_holes, two_components

    out = [
        ("rect-holes", rectangle_with_holes()),
        ("two", two_components()),
        ("blobs", blobs(4, size=72, n=5, holes=2)),
    ]
    for k, path in enumerate(SHAPES[::2]):
        m = load(path)
        out.append((path.stem, m))
        out.append((path.stem + "-noisy", boundary_noise(m, "gaussian", 1.0, rng=k, margin=2)))
    for seed in range(3):
        out.append((f"rect-{seed}", noisy_rectangle(60, 160, "uniform", 1.5, rng=seed)[0]))
    return out


@pytest.mark.parametrize(
    ("name", "mask"), _coarse_cases(), ids=lambda x: x if isinstance(x, str) else ""
)
def test_lazy_coarse_stage_equals_the_eager_reference(name, mask):
    for crop, _ in components(mask):
        ma = medial_axis(crop, squared_distance(crop))
        fast = BranchGraph(ma.rows, ma.cols, crop.shape)
        if not fast.ends:
            continue
        slow = BranchGraph(ma.rows, ma.cols, crop.shape)
        assert coarse_removals(fast, crop, ma.r2) == reference_coarse(slow, crop, ma.r2)


def test_where_segments_meet_is_the_pair_table_without_the_table():
    """``_meeting_vertex`` answers what an m × m table of (before, after) pairs would,
    on a boundary with hundreds of segments (pixel noise inside a square)."""
    from skelprune.grid.coarse import _convex_vertices, _meeting_vertex

    rng = np.random.default_rng(3)
    mask = np.zeros((60, 60), bool)
    mask[5:55, 5:55] = rng.random((50, 50)) < 0.8
    partition = boundary_partition(mask, n_vertices=50, threshold=0.0)
    before, after, _ = _convex_vertices(partition)
    m = partition.n_segments
    assert m > 200
    table = np.full((m, m), -2, np.int64)
    table[before, after] = np.arange(len(after))
    table[after, before] = np.arange(len(after))
    starts_at = np.full(m, -1, np.int64)
    starts_at[after] = np.arange(len(after))
    got = np.array([[_meeting_vertex(starts_at, before, a, b) for b in range(m)] for a in range(m)])
    off_diagonal = ~np.eye(m, dtype=bool)  # a point's labels are distinct segments
    assert np.array_equal(got[off_diagonal], table[off_diagonal])


def test_the_coarse_stage_holds_no_table_quadratic_in_the_segments():
    """Pixel noise makes about as many boundary segments as boundary pixels: every
    array the stage keeps is linear in the skeleton points plus the segments."""
    from skelprune.grid.coarse import _convex_vertices, _EndBranches
    from testkit.adversarial import noise

    crop, ma = _axis(noise(48, 0.8, seed=1))
    graph = BranchGraph(ma.rows, ma.cols, crop.shape)
    partition = coarse_partition(crop)
    ends = _EndBranches(graph, ma.r2, partition, *_convex_vertices(partition))
    m, n = partition.n_segments, ma.rows.size
    assert m > 100
    sizes = {k: v.size for k, v in vars(ends).items() if isinstance(v, np.ndarray)}
    assert sizes and max(sizes.values()) <= 2 * (n + m), sizes


@numba.njit
def _label_sets(cells, raster_local, r2, tolerance, limit):
    """rim_label_set for every point (compiled here: the kernel is for compiled callers)."""
    out = np.full((r2.size, limit), -1, np.int64)
    for k in range(r2.size):
        rim_label_set(*cells, raster_local[k, 0], raster_local[k, 1], r2[k], tolerance, out[k])
    return out


@pytest.mark.parametrize(
    ("name", "mask"), _coarse_cases()[::2], ids=lambda x: x if isinstance(x, str) else ""
)
def test_rim_labels_from_cells_are_the_scanned_labels(name, mask):
    """The labels found from the boundary pixels by cells are those of the rim scan:
    all of them (a limit no rim reaches), and the same first three or fewer."""
    for crop, _ in components(mask):
        ma = medial_axis(crop, squared_distance(crop))
        part = coarse_partition(crop)
        pts = np.stack([ma.rows, ma.cols], axis=1)
        raster = SegmentRaster(part, pts, ma.r2)
        cells = tuple(raster.cells())
        every = np.arange(len(pts))
        for limit in (3, 64):
            scanned = raster.labels(every, limit)
            found = _label_sets(cells, raster.local, raster.r2, raster.tolerance, limit)
            for a, b in zip(scanned, found, strict=True):
                assert (b != -1).sum() == (a != -1).sum()
                if limit == 64 or (a != -1).sum() < 3:
                    assert set(a.tolist()) == set(b.tolist())
        assert (found[:, 1] != -1).any()
