"""A shape turned by 90° or mirrored gets exactly the turned or mirrored skeleton.

Before the canonical orientation (``skelprune.grid._orientation``), thinning and the
``(row, col)`` tie rules worked in raster order, and 24 % of the kimia216 shapes got
another endpoint count when merely turned by 90°.
"""

from __future__ import annotations

import numpy as np
import pytest

import skelprune
from evaluation.perturb import boundary_noise
from skelprune.api import components
from skelprune.errors import InvalidImageError
from skelprune.grid._orientation import Orientation, canonical_orientation
from skelprune.grid.medial_axis import medial_axis, squared_distance
from testkit.shapes import (
    blobs,
    dataset,
    load,
    rectangle_with_holes,
    touching_border,
    two_components,
)

#: The eight symmetries of the pixel grid, as functions of an array.
SYMMETRIES = {
    "identity": lambda a: a,
    "rot90": lambda a: np.rot90(a, 1),
    "rot180": lambda a: np.rot90(a, 2),
    "rot270": lambda a: np.rot90(a, 3),
    "transpose": lambda a: a.T,
    "flip-rows": lambda a: a[::-1],
    "flip-cols": lambda a: a[:, ::-1],
    "anti-transpose": lambda a: np.rot90(a, 2).T,
}


def turned(mask: np.ndarray, name: str) -> np.ndarray:
    return np.ascontiguousarray(SYMMETRIES[name](mask))


def kimia(step: int) -> list[np.ndarray]:
    return [load(p) for p in dataset("kimia216")[::step]]


def shapes() -> list[np.ndarray]:
    """Kimia shapes (several with exact moment ties), holes, two components, the border,
    boundary noise."""
    out = kimia(17) + [load(p) for p in dataset("kimia99")[::33]]
    out += [
        rectangle_with_holes(),
        two_components(),
        touching_border(),
        blobs(3, holes=2),
        boundary_noise(load(dataset("kimia216")[5]), "gaussian", 1.0, rng=1),
    ]
    square = np.zeros((30, 30), bool)
    square[5:25, 5:25] = True  # every symmetry maps it to itself
    return [*out, square]


def point_image(shape: tuple[int, int], rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    img = np.zeros(shape, bool)
    img[rows, cols] = True
    return img


@pytest.mark.parametrize("seed", range(20))
def test_every_turned_copy_picks_the_same_canonical_array(seed):
    rng = np.random.default_rng(seed)
    mask = rng.random((rng.integers(3, 12), rng.integers(3, 12))) < 0.5
    if seed % 4 == 0:  # symmetric masks: moment ties, settled by the bytes
        mask = mask | mask[::-1]
    if seed % 8 == 0:
        mask = mask | mask[:, ::-1]
    ref = canonical_orientation(mask).apply(mask)
    # idempotent: what lets prune() skip the search on its already oriented crop
    assert canonical_orientation(ref) == Orientation()
    for name in SYMMETRIES:
        t = turned(mask, name)
        np.testing.assert_array_equal(canonical_orientation(t).apply(t), ref, err_msg=name)


@pytest.mark.parametrize("swap", [False, True])
@pytest.mark.parametrize("flip_rows", [False, True])
@pytest.mark.parametrize("flip_cols", [False, True])
def test_points_back_inverts_apply(swap, flip_rows, flip_cols):
    o = Orientation(swap, flip_rows, flip_cols)
    a = np.arange(35).reshape(5, 7)
    seen = o.apply(a)
    rows, cols = np.nonzero(np.ones(seen.shape, bool))
    back_r, back_c = o.points_back(rows, cols, seen.shape)
    np.testing.assert_array_equal(a[back_r, back_c], seen[rows, cols])


@pytest.mark.parametrize("name", [n for n in SYMMETRIES if n != "identity"])
def test_medial_axis_follows_the_shape(name):
    for mask in [*kimia(23), rectangle_with_holes(), blobs(5, holes=1)]:
        padded = np.pad(mask, 1)
        ma = medial_axis(padded)
        t = medial_axis(turned(padded, name))
        np.testing.assert_array_equal(
            point_image(turned(padded, name).shape, t.rows, t.cols),
            turned(point_image(padded.shape, ma.rows, ma.cols), name),
        )


def symmetric(mask: np.ndarray) -> bool:
    """Whether a symmetry of the grid other than the identity maps ``mask`` to itself.

    Such a shape's skeleton cannot always share its symmetry (a one-pixel-thin axis
    through an even-sized square cannot), so a turned copy gets the skeleton only up to
    that symmetry: the same counts and errors, not always the same pixels.
    """
    return any(np.array_equal(turned(mask, n), mask) for n in SYMMETRIES if n != "identity")


def invariants(res: skelprune.PruneResult) -> list[tuple]:
    return sorted(
        (c.area, c.graph.n_endpoints(), c.chosen_step, c.rer, round(c.ss, 12))
        for c in res.components
    )


@pytest.mark.parametrize("kw", [{}, {"coarse": None}, {"method": "dce"}])
@pytest.mark.parametrize("name", [n for n in SYMMETRIES if n != "identity"])
def test_pruned_skeleton_follows_the_shape(name, kw):
    checked = 0
    for mask in shapes():
        res = skelprune.prune(mask, **kw)
        t = skelprune.prune(turned(mask, name), **kw)
        # components come in raster order, which a turn changes
        assert invariants(res) == invariants(t)
        if any(symmetric(crop) for crop, _ in components(mask)):
            continue
        rows, cols, r2 = res.skeleton_points()
        trows, tcols, tr2 = t.skeleton_points()
        np.testing.assert_array_equal(
            point_image(t.mask.shape, trows, tcols),
            turned(point_image(mask.shape, rows, cols), name),
        )
        assert sorted(r2.tolist()) == sorted(tr2.tolist())
        checked += 1
    assert checked >= 12


def test_document_points_are_in_the_image_frame():
    mask = np.zeros((40, 90), bool)
    mask[5:35, 10:80] = True
    mask[5:12, 10:30] = False  # no symmetry: the canonical orientation is not the identity
    assert canonical_orientation(np.pad(mask, 1)) != Orientation()
    r2 = squared_distance(np.pad(mask, 1))[1:-1, 1:-1]
    doc = skelprune.prune(mask).to_dict()["components"][0]["skeleton"]
    points = [p for b in doc["branches"] for p in b["points"] + b["off_path"]]
    points += [p for n in doc["nodes"] for p in n["points"]]
    points += [[n["x"], n["y"], n["radius"]] for n in doc["nodes"]]
    for x, y, radius in points:
        assert mask[int(y), int(x)]
        assert radius**2 == pytest.approx(r2[int(y), int(x)])


def test_medial_axis_refuses_a_shape_on_the_border():
    mask = np.zeros((10, 12), bool)
    mask[3:7, 0:5] = True
    with pytest.raises(InvalidImageError, match="border"):
        medial_axis(mask)
    assert len(medial_axis(np.pad(mask, 1))) > 0
