"""The numba boundary tracer (``skelprune.grid._contours``) equals skimage's ``find_contours``.

``boundary_polygons`` replays marching squares without skimage; DCE breaks ties by vertex
index, so the polygons must be the same arrays (same start vertex, orientation and polygon
order), not only the same cyclic sequences. The reference below is the implementation the
tracer replaced.
"""

from __future__ import annotations

import numpy as np
import pytest
from skimage.measure import find_contours

from evaluation.perturb import boundary_noise, rotate
from skelprune.grid._contours import boundary_polygons as _boundary_polygons
from skelprune.grid.dce import boundary_partition, generated_in_several_segments
from testkit.shapes import (
    blobs,
    dataset,
    load,
    rectangle_with_holes,
    touching_border,
    two_components,
)

K216 = dataset("kimia216")
K99 = dataset("kimia99")


def reference_polygons(mask: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """The former ``_boundary_polygons``: skimage marching squares plus post-processing."""
    padded = np.pad(np.asarray(mask, dtype=bool), 1)
    out = []
    for c in find_contours(
        padded.astype(np.float64), 0.5, fully_connected="high", positive_orientation="high"
    ):
        if len(c) > 1 and np.array_equal(c[0], c[-1]):
            c = c[:-1]
        keep = np.ones(len(c), bool)
        keep[1:] = np.any(np.diff(c, axis=0) != 0, axis=1)
        c = c[keep]
        if len(c) < 3:
            continue
        lo = np.floor(c).astype(np.int64)
        hi = np.ceil(c).astype(np.int64)
        lo_bg = ~padded[lo[:, 0], lo[:, 1]]
        bg = np.where(lo_bg[:, None], lo, hi)
        out.append((c - 1.0, bg - 1))
    return out


def assert_same_polygons(mask: np.ndarray) -> None:
    got, ref = _boundary_polygons(mask), reference_polygons(mask)
    assert len(got) == len(ref)
    for (xy, bg), (rxy, rbg) in zip(got, ref, strict=True):
        assert xy.dtype == rxy.dtype and bg.dtype == rbg.dtype
        np.testing.assert_array_equal(xy, rxy)
        np.testing.assert_array_equal(bg, rbg)


def tiny_shapes() -> list[np.ndarray]:
    """Single pixels, lines, diagonal-only contacts and checkerboards, in and at the border."""
    out = []
    for h, w in [(1, 1), (1, 5), (5, 1), (3, 3)]:
        out.append(np.ones((h, w), bool))  # fills the whole image: touches every border
    m = np.zeros((5, 5), bool)
    m[2, 2] = True
    out.append(m)
    m = np.zeros((7, 9), bool)
    m[3, 1:8] = True  # horizontal line
    out.append(m)
    out.append(m.T.copy())  # vertical line
    out.append(np.eye(6, dtype=bool))  # diagonal line touching two corners of the image
    out.append(np.fliplr(np.eye(6, dtype=bool)).copy())  # anti-diagonal
    m = np.zeros((6, 6), bool)
    m[1:3, 1:3] = True
    m[3:5, 3:5] = True  # two squares meeting at a corner (case 9)
    out.append(m)
    out.append(np.fliplr(m).copy())  # the other diagonal (case 6)
    out.append(np.indices((8, 8)).sum(axis=0) % 2 == 0)  # checkerboard: all diagonal
    m = np.ones((7, 7), bool)
    m[2:5, 2:5] = False
    m[3, 3] = True  # a pixel island in a hole
    out.append(m)
    m = np.ones((5, 5), bool)
    m[1, 1] = m[2, 2] = m[3, 3] = False  # holes meeting at corners (background 4-connected)
    out.append(m)
    out.append(np.zeros((4, 4), bool))  # no shape: no polygon
    out.append(np.zeros((0, 3), bool))
    return out


@pytest.mark.parametrize("i", range(len(tiny_shapes())))
def test_tiny_and_degenerate_shapes(i):
    assert_same_polygons(tiny_shapes()[i])


def test_random_masks_with_many_holes_and_corner_contacts():
    rng = np.random.default_rng(0)
    for _ in range(200):
        h, w = rng.integers(1, 14, size=2)
        assert_same_polygons(rng.random((h, w)) < rng.uniform(0.2, 0.8))


@pytest.mark.parametrize("i", range(0, 204, 3))
def test_kimia216(i):
    assert_same_polygons(load(K216[i]))


@pytest.mark.parametrize("i", range(0, 99, 3))
def test_kimia99(i):
    assert_same_polygons(load(K99[i]))


@pytest.mark.parametrize("seed", range(6))
def test_perturbed_shapes(seed):
    m = load(K216[seed * 31])
    assert_same_polygons(boundary_noise(m, "gaussian", 1.0, rng=seed, margin=2))
    assert_same_polygons(boundary_noise(m, "uniform", 2.0, rng=seed))  # may touch the border
    assert_same_polygons(rotate(m, 17.0 + 29 * seed))


def test_holes_border_and_several_components():
    for m in [
        rectangle_with_holes(),
        touching_border(),
        two_components(),
        blobs(3, size=56, n=4, holes=2),
        blobs(7, size=64, n=5, holes=3),
    ]:
        assert_same_polygons(m)
    m = load(K216[0])
    assert_same_polygons(m[: m.shape[0] // 2])  # cut through the shape: touches the border
    assert_same_polygons(~m)  # the background as the shape: the image border is a boundary


# --- evolve_polygon: the heap (with straight runs dropped first) equals a plain DCE -----


def reference_evolution(xy: np.ndarray, n_keep: int, threshold: float) -> list[int]:
    """DCE as defined: rescan every live vertex, delete the least (relevance, index).

    Relevances come from the library's own kernel, so that this checks the evolution
    (deletion order, stop rules, the straight-run shortcut), not the float formula.
    """
    from skelprune.grid.dce import _relevance

    d = np.diff(xy, axis=0, append=xy[:1])
    perimeter = float(np.hypot(d[:, 0], d[:, 1]).sum()) or 1.0
    live = list(range(len(xy)))
    while len(live) > 3:
        m = len(live)
        keys = [
            (_relevance(xy, live[t - 1], live[t], live[(t + 1) % m], perimeter), live[t])
            for t in range(m)
        ]
        key, i = min(keys)
        if m <= n_keep and key > threshold:
            break
        live.remove(i)
    return live


EVOLUTION_CASES = [
    (None, 0.0),
    (None, 0.002),
    (None, 0.01),
    (16, 0.01),
    (16, None),
    (5, None),
    (40, 0.0),
]


@pytest.mark.parametrize(("n_vertices", "threshold"), EVOLUTION_CASES)
def test_evolution_equals_plain_dce(n_vertices, threshold):
    from skelprune.grid.dce import evolve_polygon

    masks = [
        load(K216[7]),
        load(K99[40]),
        blobs(5, size=40, n=3, holes=1),
        rectangle_with_holes(),
        np.ones((3, 9), bool),
    ]
    masks.append(np.zeros((9, 9), bool))
    masks[-1][4, 1:8] = masks[-1][1:8, 4] = True  # a plus: few vertices off straight runs
    for m in masks:
        for xy, _ in _boundary_polygons(m):
            n_keep = len(xy) if n_vertices is None else max(3, n_vertices)
            thr = -np.inf if threshold is None else threshold
            got = evolve_polygon(xy, n_vertices=n_vertices, threshold=threshold)
            assert got.tolist() == sorted(reference_evolution(xy, n_keep, thr))


# --- generated_in_several_segments: the annulus scan equals the full-square scan --------


def reference_generated(points, r2, part, tolerance=1.0):
    """Brute force over all boundary points, with the rim test of the raster scan.

    The points at squared distance ``r2 <= d2 <= (sqrt(r2) + tolerance)**2`` (the same
    float arithmetic, so the same answer when ``sqrt(r2)**2`` rounds below ``r2``; points
    nearer than ``r`` exist only when ``r2`` ignores background outside the image).
    """
    out = []
    for (r, c), q in zip(points, r2, strict=True):
        d2 = ((part.points - [r, c]) ** 2).sum(axis=1)
        outer = np.sqrt(float(q)) + tolerance
        segs = set(part.segment[(d2 >= q) & (d2 <= outer * outer)].tolist())
        out.append(len(segs) >= 2)
    return np.array(out, bool)


@pytest.mark.parametrize("tolerance", [0.0, 0.25, 0.5, 1.0, 2.5])
def test_generated_equals_brute_force(tolerance):
    from skelprune.grid.medial_axis import medial_axis, squared_distance

    for raw in [load(K216[40]), blobs(11, size=56, n=4, holes=2), rectangle_with_holes()]:
        m = np.pad(raw, 1)  # the blob touches the border
        part = boundary_partition(m, pixel_threshold=3.0)
        ma = medial_axis(m, squared_distance(m))
        pts = np.stack([ma.rows, ma.cols], axis=1)
        got = generated_in_several_segments(pts, ma.r2, part, tolerance=tolerance)
        np.testing.assert_array_equal(got, reference_generated(pts, ma.r2, part, tolerance))
