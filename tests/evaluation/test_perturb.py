"""Shape perturbations and the rectangle ground truth (evaluation.perturb)."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image
from scipy import ndimage as ndi
from skimage.morphology import medial_axis

from evaluation.perturb import (
    PERTURBATIONS,
    Perturbation,
    boundary_flips,
    boundary_noise,
    noisy_rectangle,
    rectangle_medial_axis,
    resampled_noise,
    rescale,
    rotate,
    skeleton_distance,
    skeleton_error,
)
from testkit import DATA


def crop(m: np.ndarray) -> np.ndarray:
    rows, cols = np.nonzero(m)
    return m[rows.min() : rows.max() + 1, cols.min() : cols.max() + 1]


def n_holes(m: np.ndarray) -> int:
    return ndi.label(~np.pad(m, 1))[1] - 1


def n_components(m: np.ndarray) -> int:
    return ndi.label(m, structure=np.ones((3, 3)))[1]


def iou(a: np.ndarray, b: np.ndarray) -> float:
    """Best IoU over small integer shifts of two masks in their own frames."""
    h, w = max(a.shape[0], b.shape[0]) + 4, max(a.shape[1], b.shape[1]) + 4
    big = np.zeros((h, w), bool)
    big[2 : 2 + b.shape[0], 2 : 2 + b.shape[1]] = b
    best = 0.0
    for i in range(h - a.shape[0] + 1):
        for j in range(w - a.shape[1] + 1):
            sa = np.zeros((h, w), bool)
            sa[i : i + a.shape[0], j : j + a.shape[1]] = a
            best = max(best, float((sa & big).sum() / (sa | big).sum()))
    return best


@pytest.fixture(scope="module")
def shape_with_hole() -> np.ndarray:
    m = np.zeros((70, 90), bool)
    rr, cc = np.mgrid[:70, :90]
    m[((rr - 35) / 28) ** 2 + ((cc - 45) / 38) ** 2 <= 1] = True
    m[25:45, 30:50] = False  # a 20 × 20 hole
    m[30:40, 80:88] = True  # an appendage
    return m


@pytest.fixture(scope="module")
def kimia() -> np.ndarray:
    return np.array(Image.open(DATA / "kimia216" / "bird-4.png")) > 0


def test_identity_transforms_reproduce_the_shape(shape_with_hole, kimia):
    for m in (shape_with_hole, kimia):
        assert np.array_equal(crop(rotate(m, 0)), crop(m))
        assert np.array_equal(crop(rescale(m, 1.0)), crop(m))
        assert np.array_equal(boundary_noise(m, "gaussian", 0.0, rng=0), m)


def test_output_has_the_requested_margin(shape_with_hole):
    for margin in (0, 3):
        r = rotate(shape_with_hole, 30, margin=margin)
        rows, cols = np.nonzero(r)
        assert rows.min() == margin and cols.min() == margin
        assert r.shape[0] - 1 - rows.max() == margin and r.shape[1] - 1 - cols.max() == margin


@pytest.mark.parametrize("k", [1, 2, 3])
def test_quarter_turns_equal_rot90(shape_with_hole, kimia, k):
    for m in (shape_with_hole, kimia):
        assert np.array_equal(rotate(m, 90 * k, margin=0), np.rot90(crop(m), k))


def test_rotation_keeps_area_topology_and_inverts(shape_with_hole):
    m = shape_with_hole
    for deg in (15, 30, 45):
        r = rotate(m, deg)
        assert abs(int(r.sum()) - int(m.sum())) / m.sum() < 0.01
        assert n_holes(r) == 1 and n_components(r) == 1
        assert iou(crop(rotate(r, -deg)), crop(m)) > 0.97


def test_rescale_scales_area_and_bounding_box(shape_with_hole, kimia):
    m = shape_with_hole
    up = rescale(m, 2.0, margin=0)
    assert int(up.sum()) == 4 * int(m.sum())  # exact for an integer factor
    assert up.shape == tuple(2 * s for s in crop(m).shape)
    for f in (0.5, 1.5):
        s = rescale(kimia, f)
        assert abs(s.sum() / (f * f * kimia.sum()) - 1) < 0.05
        assert n_components(s) == 1
    down = rescale(up, 0.5, margin=0)
    assert iou(crop(down), crop(m)) > 0.98
    with pytest.raises(ValueError):
        rescale(m, 0.0)


@pytest.mark.parametrize(
    "kind, scale", [("gaussian", 1.0), ("gaussian", 1.5), ("uniform", 1.0), ("uniform", 1.5)]
)
def test_noise_keeps_area_holes_and_one_component(shape_with_hole, kind, scale):
    m = shape_with_hole
    n = boundary_noise(m, kind, scale, rng=11)
    assert n.shape == m.shape
    assert abs(int(n.sum()) - int(m.sum())) / m.sum() < 0.04
    assert n_holes(n) == 1 and n_components(n) == 1
    changed = n ^ m
    assert changed.sum() > 0.3 * (m ^ ndi.binary_erosion(m)).sum()  # it does move the boundary
    # uniform noise never moves the boundary by more than the scale (plus the pixel grid)
    if kind == "uniform":
        near = ndi.distance_transform_edt(~(m ^ ndi.binary_erosion(m)))
        assert near[changed].max() <= scale + 1.5


def test_noise_is_deterministic_for_a_seed(kimia):
    a = boundary_noise(kimia, "gaussian", 1.0, rng=42)
    b = boundary_noise(kimia, "gaussian", 1.0, rng=np.random.default_rng(42))
    c = boundary_noise(kimia, "gaussian", 1.0, rng=43)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)
    with pytest.raises(ValueError):
        boundary_noise(kimia, "cauchy", 1.0, rng=0)  # type: ignore[arg-type]


def test_noise_never_creates_holes_and_keeps_one_component():
    m = np.zeros((40, 120), bool)
    m[10:30, 5:115] = True
    m[18:22, 40:80] = False  # a thin slot hole
    for seed in range(8):
        n = boundary_noise(m, "gaussian", 1.5, rng=seed, margin=3)
        assert n_components(n) == 1
        assert n_holes(n) == 1


def test_perturbations_table():
    assert list(PERTURBATIONS) == [
        "gaussian-1",
        "gaussian-1.5",
        "uniform-1",
        "uniform-1.2",
        "uniform-1.5",
        "resampled-1",
        "flips-0.5",
        "rotate-15",
        "rotate-30",
        "rotate-45",
        "scale-0.5",
        "scale-1.5",
        "scale-2",
    ]
    assert PERTURBATIONS["uniform-1.2"] == Perturbation("uniform-1.2", "uniform", 1.2)


def test_every_perturbation_applies(kimia):
    for p in PERTURBATIONS.values():
        out = p.apply(kimia, rng=0)
        assert out.dtype == bool and n_components(out) == 1
        factor = p.param**2 if p.kind == "scale" else 1.0
        assert abs(out.sum() / (factor * kimia.sum()) - 1) < 0.06, p.name
    same = PERTURBATIONS["gaussian-1"]
    assert np.array_equal(same.apply(kimia, rng=3), same.apply(kimia, rng=3))


@pytest.mark.parametrize("noise", [resampled_noise, boundary_flips])
def test_independent_noise_models_keep_topology_and_area(noise, shape_with_hole):
    m = shape_with_hole
    for seed in range(4):
        n = noise(m, 1.0 if noise is resampled_noise else 0.5, rng=seed)
        assert n.shape == (m.shape[0] + 4, m.shape[1] + 4)
        assert n_components(n) == 1 and n_holes(n) == 1
        assert abs(int(n.sum()) / int(m.sum()) - 1) < 0.06
        assert not np.array_equal(n[2:-2, 2:-2], m)
    again = noise(m, 0.5, rng=1)
    assert np.array_equal(again, noise(m, 0.5, rng=1))


def test_resampled_contour_without_noise_is_the_shape(kimia):
    """Resampling moves the polygon by well under a pixel, so the fill is the shape
    up to a few corner pixels."""
    out = resampled_noise(kimia, 0.0, rng=0)[2:-2, 2:-2]
    assert (out ^ kimia).sum() <= 0.02 * kimia.sum()


@pytest.mark.parametrize("name", ["rotate-30", "scale-0.5", "scale-2", "gaussian-1", "resampled-1"])
def test_the_map_takes_perturbed_points_back(shape_with_hole, name):
    """The perturbed shape's pixels, mapped back, land on the clean shape."""
    kimia = shape_with_hole  # no thin part the noise could cut off and move the centroid
    out, back = PERTURBATIONS[name].apply_mapped(kimia, rng=0)
    pts = back(np.argwhere(out))
    p = PERTURBATIONS[name]
    # half an output pixel of fill rounding, in input pixels
    tol = 0.3 / min(1.0, p.param) if p.kind == "scale" else 0.3
    assert np.allclose(pts.mean(axis=0), np.argwhere(kimia).mean(axis=0), atol=tol)
    r = np.clip(np.rint(pts).astype(int), 0, np.array(kimia.shape) - 1)
    inside = ndi.binary_dilation(kimia, iterations=2)[r[:, 0], r[:, 1]]
    assert inside.mean() > 0.99
    assert np.array_equal(out, PERTURBATIONS[name].apply(kimia, rng=0))


def test_skeleton_distance():
    a = np.array([[0, 0], [0, 10]])
    assert skeleton_distance(a, a, 25.0) == 0.0
    assert skeleton_distance(a, a + np.array([3, 0]), 9.0) == pytest.approx(1.0)
    assert skeleton_distance(a, np.array([[0, 0]]), 1.0) == pytest.approx(0.5 * (5 + 0))
    assert np.isnan(skeleton_distance(a, np.zeros((0, 2)), 1.0))


# --- rectangle ground truth and eq. 13 ---------------------------------------------


def sample(segments: np.ndarray, n: int = 50) -> np.ndarray:
    t = np.linspace(0, 1, n)[:, None]
    return np.concatenate([a + t * (b - a) for a, b in segments])


def test_rectangle_medial_axis_geometry():
    g = rectangle_medial_axis(0, 0, 20, 60)
    assert g.shape == (5, 2, 2)
    assert np.allclose(g[0], [[10, 10], [10, 50]])
    # every ground-truth point is equidistant from its two nearest sides
    pts = sample(g)
    d = np.sort(np.c_[pts[:, 0], 20 - pts[:, 0], pts[:, 1], 60 - pts[:, 1]], axis=1)
    assert np.allclose(d[:, 0], d[:, 1])
    tall = rectangle_medial_axis(0, 0, 60, 20)
    pts = sample(tall)
    d = np.sort(np.c_[pts[:, 0], 60 - pts[:, 0], pts[:, 1], 20 - pts[:, 1]], axis=1)
    assert np.allclose(d[:, 0], d[:, 1])
    assert np.allclose(rectangle_medial_axis(0, 0, 10, 10)[0], [[5, 5], [5, 5]])


def test_skeleton_error_is_zero_on_g_and_grows_with_offset():
    mask, g = noisy_rectangle(30, 80, "gaussian", 0.0, rng=0)
    assert mask.sum() == 30 * 80
    pts = sample(g)
    assert skeleton_error(pts, g) < 1e-20
    centre = sample(g[:1])[5:-5]
    errs = [skeleton_error(centre + np.array([d, 0.0]), g) for d in (0.5, 1, 2, 3)]
    assert np.allclose(errs, [0.25, 1, 4, 9])
    assert skeleton_error(np.zeros((0, 2)), g) == 0.0


def test_noisy_rectangle_matches_the_paper_setup():
    mask, g = noisy_rectangle(40, 100, "uniform", 1.5, rng=1)
    assert n_components(mask) == 1 and n_holes(mask) == 0
    assert abs(int(mask.sum()) - 4000) < 200
    clean, g0 = noisy_rectangle(40, 100, "uniform", 0.0, rng=1)
    assert np.array_equal(g, g0)
    # a plain medial axis of the clean rectangle lies on G (conventions agree)
    sk = medial_axis(np.pad(clean, 1))[1:-1, 1:-1]
    assert skeleton_error(np.argwhere(sk), g) < 0.5
