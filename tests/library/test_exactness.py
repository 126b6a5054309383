"""The fast pruning equals the naive from-scratch oracle (docs/algorithm.md)."""

from __future__ import annotations

import numpy as np
import pytest

from skelprune.api import components
from skelprune.pruning.bayesian import pruning_sequence
from skelprune.skeleton import Skeleton
from testkit.oracle import naive_sequence
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

CASES = (
    [pytest.param(("k216", i), id=f"kimia216-{K216[i].stem}") for i in range(0, 204, 17)]
    + [pytest.param(("k99", i), id=f"kimia99-{K99[i].stem}") for i in range(0, 99, 11)]
    + [pytest.param(("blobs", s), id=f"blobs-{s}") for s in range(4)]
    + [pytest.param(("holes", s), id=f"blobs-holes-{s}") for s in range(4)]
    + [
        pytest.param(("rect-holes", 0), id="rectangle-two-holes"),
        pytest.param(("border", 0), id="touching-border"),
        pytest.param(("two", 0), id="two-components"),
    ]
)


def make(case: tuple[str, int]) -> np.ndarray:
    kind, i = case
    if kind == "k216":
        return load(K216[i], factor=2)
    if kind == "k99":
        return load(K99[i], factor=2)
    if kind == "blobs":
        return blobs(100 + i, size=56, n=5)
    if kind == "holes":
        return blobs(200 + i, size=56, n=4, holes=2)
    return {"rect-holes": rectangle_with_holes, "border": touching_border, "two": two_components}[
        kind
    ]()


def test_at_least_thirty_shapes():
    assert len(CASES) >= 30


@pytest.mark.parametrize("case", CASES)
def test_fast_equals_naive(case):
    mask = make(case)
    crops = components(mask)
    assert crops
    steps = 0
    for crop, _ in crops:
        medial = Skeleton.medial_axis(crop)  # the canonical frame prune() works in
        norm = medial.normalisation(9.0)
        if norm.alpha is None:
            continue
        fast = pruning_sequence(medial, norm.alpha, norm.lbar)
        removed, lams = naive_sequence(
            medial.working_graph(), medial.mask, medial.r2, norm.alpha, norm.lbar
        )
        assert fast.removed == removed
        np.testing.assert_allclose(fast.objective, lams, rtol=0, atol=1e-9)
        steps += len(removed)
    assert steps > 0  # the case really exercised pruning


NOISY = [
    pytest.param(("k216", i, s), id=f"noisy-kimia216-{K216[i].stem}-{s}")
    for i, s in ((5, 1.0), (60, 1.5), (150, 1.0))
]


def make_noisy(case: tuple[str, int, float]) -> np.ndarray:
    from evaluation.perturb import boundary_noise

    _, i, scale = case
    return boundary_noise(load(K216[i], factor=2), "gaussian", scale, rng=i, margin=2)


@pytest.mark.parametrize("case", CASES[::3] + NOISY)
def test_fast_equals_naive_from_the_coarse_dce_skeleton(case):
    """``coarse="dce"``: the Bayesian stage, started from the coarse skeleton.

    The noisy shapes make the coarse stage's roughness-raised threshold and its
    one-branch-per-convex-vertex rule act.
    """
    from skelprune.grid.coarse import coarse_dce

    mask = make_noisy(case) if len(case) == 3 else make(case)
    steps = 0
    for crop, _ in components(mask):
        medial = Skeleton.medial_axis(crop)
        if medial.normalisation(9.0).alpha is None:
            continue
        start = coarse_dce(medial)
        norm = start.normalisation(9.0)
        if norm.alpha is None:
            continue
        fast = pruning_sequence(start, norm.alpha, norm.lbar)
        removed, lams = naive_sequence(
            start.working_graph(), start.mask, start.r2, norm.alpha, norm.lbar
        )
        assert fast.removed == removed
        np.testing.assert_allclose(fast.objective, lams, rtol=0, atol=1e-9)
        steps += len(removed) + (medial.n_points - start.n_points)
    assert steps > 0


@pytest.mark.parametrize("kw", [{"coarse": "dce"}, {"method": "dce"}])
@pytest.mark.parametrize("case", CASES[1::4])
def test_dce_pruning_never_changes_topology(case, kw):
    from skimage.measure import euler_number, label

    import skelprune

    mask = make(case)
    res = skelprune.prune(mask, **kw)
    rows, cols, _ = res.skeleton_points()
    skel = np.zeros(mask.shape, bool)
    skel[rows, cols] = True
    assert label(skel, connectivity=2).max() == label(mask, connectivity=2).max()
    assert euler_number(skel, connectivity=2) == euler_number(mask, connectivity=2)
