"""Discrete Curve Evolution and the contour partition (skelprune.grid.dce, docs/algorithm.md)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage as ndi
from skimage.draw import polygon as fill_polygon

from evaluation.perturb import boundary_noise, rescale
from skelprune.grid.dce import (
    BoundaryPartition,
    boundary_partition,
    evolve_polygon,
    generated_in_several_segments,
)


def densify(corners: np.ndarray, step: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """Closed polygon through ``corners`` with points every ``step``; corner indices."""
    pts, idx = [], []
    for a, b in zip(corners, np.roll(corners, -1, axis=0), strict=True):
        k = max(1, int(np.ceil(np.linalg.norm(b - a) / step)))
        idx.append(len(pts))
        pts.extend(a + (b - a) * t for t in np.arange(k) / k)
    return np.array(pts), np.array(idx)


def star(n_tips: int = 5, r_out: float = 40.0, r_in: float = 16.0, centre=(50.0, 50.0)):
    ang = np.pi / 2 + np.arange(2 * n_tips) * np.pi / n_tips
    rad = np.where(np.arange(2 * n_tips) % 2 == 0, r_out, r_in)
    return np.c_[centre[0] - rad * np.sin(ang), centre[1] + rad * np.cos(ang)]


def relevances(v: np.ndarray, perimeter: float) -> np.ndarray:
    a = v - np.roll(v, 1, axis=0)
    b = np.roll(v, -1, axis=0) - v
    l1, l2 = np.linalg.norm(a, axis=1), np.linalg.norm(b, axis=1)
    beta = np.arctan2(np.abs(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]), np.sum(a * b, axis=1))
    return beta * l1 * l2 / ((l1 + l2) * perimeter)


def rect_mask(h: int, w: int, pad: int = 5) -> np.ndarray:
    m = np.zeros((h + 2 * pad, w + 2 * pad), bool)
    m[pad : pad + h, pad : pad + w] = True
    return m


def exact_r2(mask: np.ndarray) -> np.ndarray:
    """Squared distance to the nearest background pixel, the shape padded by one pixel."""
    d = ndi.distance_transform_edt(np.pad(mask, 1))[1:-1, 1:-1]
    return np.rint(d * d).astype(np.int64)


# --- evolve_polygon ---------------------------------------------------------------


def test_noisy_square_evolves_to_its_corners():
    corners = np.array([[0.0, 0.0], [0.0, 40.0], [40.0, 40.0], [40.0, 0.0]])
    pts, idx = densify(corners, 0.5)
    rng = np.random.default_rng(3)
    noisy = pts + rng.uniform(-0.05, 0.05, pts.shape)
    noisy[idx] = corners
    kept = evolve_polygon(noisy, n_vertices=4)
    assert kept.tolist() == idx.tolist()
    # the threshold rule finds the same four: every other vertex is nearly collinear
    assert evolve_polygon(noisy, threshold=0.01).tolist() == idx.tolist()


def test_star_keeps_its_ten_vertices():
    pts, idx = densify(star(), 0.5)
    kept = evolve_polygon(pts, threshold=0.01)
    assert kept.tolist() == idx.tolist()
    assert evolve_polygon(pts, n_vertices=10).tolist() == idx.tolist()


def test_vertex_count_stop_is_exact_and_never_below_three():
    pts, _ = densify(star(), 0.5)
    for n in (3, 7, 10, 25, 100):
        kept = evolve_polygon(pts, n_vertices=n)
        assert len(kept) == n
        assert np.all(np.diff(kept) > 0)
    assert len(evolve_polygon(pts, n_vertices=1)) == 3
    assert len(evolve_polygon(pts, threshold=np.inf)) == 3


def test_threshold_stop_leaves_only_relevant_vertices():
    pts, _ = densify(star(), 0.5)
    perimeter = float(np.sum(np.linalg.norm(np.roll(pts, -1, axis=0) - pts, axis=1)))
    rng = np.random.default_rng(0)
    pts = pts + rng.normal(0.0, 0.3, pts.shape)
    counts = []
    for t in (1e-4, 1e-3, 1e-2, 0.1):
        kept = evolve_polygon(pts, threshold=t)
        counts.append(len(kept))
        if len(kept) > 3:
            assert relevances(pts[kept], perimeter).min() > t
    assert counts == sorted(counts, reverse=True)
    assert counts[0] > 10 * counts[2]
    # both rules: n_vertices is a cap, the threshold a floor
    assert counts[0] > 40 > counts[3]
    assert len(evolve_polygon(pts, n_vertices=40, threshold=1e-4)) == 40
    assert len(evolve_polygon(pts, n_vertices=40, threshold=0.1)) == counts[3]


def test_evolution_is_deterministic_and_breaks_ties_by_index():
    ang = np.arange(12) * 2 * np.pi / 12  # a regular polygon: all relevances equal
    poly = np.c_[np.sin(ang), np.cos(ang)] * 10
    kept = evolve_polygon(poly, n_vertices=6)
    assert kept.tolist() == evolve_polygon(poly.copy(), n_vertices=6).tolist()
    assert kept[0] != 0  # the first removal is vertex 0, the smallest index
    pts, _ = densify(star(), 0.5)
    pts = pts + np.random.default_rng(1).normal(0, 0.4, pts.shape)
    runs = [evolve_polygon(pts, n_vertices=20) for _ in range(3)]
    assert all(np.array_equal(runs[0], r) for r in runs)


def test_rejects_bad_input():
    with pytest.raises(ValueError):
        evolve_polygon(np.zeros((5, 3)))


# --- boundary_partition ------------------------------------------------------------


def test_rectangle_has_four_segments_one_per_side():
    m = rect_mask(20, 40)
    part = boundary_partition(m)
    assert isinstance(part, BoundaryPartition)
    assert part.n_segments == 4
    # boundary points are the background pixels 4-adjacent to the shape
    assert len(part.points) == 2 * (20 + 40)
    assert not m[part.points[:, 0], part.points[:, 1]].any()
    # each side lies (apart from the cut at the corner) in a single segment
    sides = [
        part.points[:, 0] == 4,
        part.points[:, 0] == 25,
        part.points[:, 1] == 4,
        part.points[:, 1] == 45,
    ]
    for side in sides:
        _, counts = np.unique(part.segment[side], return_counts=True)
        assert counts.max() >= side.sum() - 1
    assert len(set(part.segment.tolist())) == 4


def test_star_mask_is_cut_at_its_five_tips():
    v = star(r_out=40, r_in=16)
    m = np.zeros((100, 100), bool)
    m[fill_polygon(v[:, 0], v[:, 1], m.shape)] = True
    part = boundary_partition(m, threshold=0.01)
    assert part.n_segments == 5
    tips = part.vertices[0][part.convex[0]]
    d = np.linalg.norm(tips[:, None, :] - v[None, ::2, :], axis=2)
    assert np.all(d.min(axis=1) < 2.5)  # every convex vertex is a tip
    # scale-free: the same shape twice as large is cut the same way
    assert boundary_partition(rescale(m, 2.0), threshold=0.01).n_segments == 5


def test_holes_get_their_own_segments():
    m = rect_mask(40, 60)
    m[15:30, 20:45] = False  # a rectangular hole: all its corners are concave for D
    part = boundary_partition(m)
    assert len(part.vertices) == 2
    outer, hole = (part.segment[part.polygon_id == k] for k in (0, 1))
    assert set(outer.tolist()).isdisjoint(hole.tolist())
    assert len(set(hole.tolist())) == 1
    assert part.n_segments == 5
    # a plus-shaped hole has four corners that are convex for the shape
    m = rect_mask(60, 60)
    m[25:40, 15:50] = False
    m[15:50, 25:40] = False
    part = boundary_partition(m)
    hole = part.segment[part.polygon_id == 1]
    assert len(set(hole.tolist())) == 4
    assert part.n_segments == 8


def test_partition_is_deterministic():
    m = boundary_noise(rect_mask(30, 50), "gaussian", 1.0, rng=5)
    a, b = boundary_partition(m), boundary_partition(m.copy())
    assert np.array_equal(a.points, b.points)
    assert np.array_equal(a.segment, b.segment)


# --- generated_in_several_segments ------------------------------------------------


@pytest.mark.parametrize("h", [20, 21])
def test_rectangle_centre_line_is_generated_by_two_segments(h):
    m = rect_mask(h, 60)
    part = boundary_partition(m)
    r2 = exact_r2(m)
    top = 5
    rows = [top + (h - 1) // 2, top + h // 2]  # the centre pixel row(s)
    pts = np.array([[r, c] for r in rows for c in (30, 35, 40)])
    assert generated_in_several_segments(pts, r2[pts[:, 0], pts[:, 1]], part).all()
    # off the centre line a disk touches only its nearest side
    off = np.array([[top + 3, 35], [top + h - 4, 30]])
    assert not generated_in_several_segments(off, r2[off[:, 0], off[:, 1]], part).any()


def test_corner_diagonal_kept_noise_bump_spur_not():
    m = rect_mask(40, 80)
    m[4, 40:43] = True  # a one-pixel bump on the top side (row 4, above row 5)
    part = boundary_partition(m)
    assert part.n_segments == 4
    r2 = exact_r2(m)
    diag = np.array([[5 + k, 5 + k] for k in (2, 4, 8)])  # on the diagonal of a corner
    spur = np.array([[4, 41], [5, 41]])  # the tip of the bump's spur
    res_d = generated_in_several_segments(diag, r2[diag[:, 0], diag[:, 1]], part)
    res_s = generated_in_several_segments(spur, r2[spur[:, 0], spur[:, 1]], part)
    assert res_d.all()
    assert not res_s.any()


def test_generated_handles_edge_cases():
    m = rect_mask(20, 40)
    part = boundary_partition(m)
    none = generated_in_several_segments(np.zeros((0, 2), int), np.zeros(0, int), part)
    assert none.shape == (0,)
    # an inconsistent radius (no boundary point that close) is never "several segments"
    assert not generated_in_several_segments(np.array([[15, 25]]), np.array([1]), part)[0]
    # the tolerance widens the touching band
    pt, r2 = np.array([[12, 25]]), np.array([8 * 8])  # 8 px from the top, 13 px from the bottom
    assert not generated_in_several_segments(pt, r2, part, tolerance=1.0)[0]
    assert generated_in_several_segments(pt, r2, part, tolerance=5.5)[0]
