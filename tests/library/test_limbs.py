"""Limbs the greedy pruning never removes (docs/algorithm.md, "Limbs")."""

from __future__ import annotations

import numpy as np
import pytest

import skelprune
from skelprune.api import components
from skelprune.grid.coarse import coarse_dce
from skelprune.grid.limbs import LimbGuard
from skelprune.pruning.bayesian import pruning_sequence
from skelprune.skeleton import Skeleton
from testkit.limbs import limb_reach, limb_shape, limb_shapes
from testkit.oracle import naive_sequence


def test_the_blobs_keep_every_limb_trimmed_or_not() -> None:
    # every 4th of the first 120 blobs of the limbs benchmark, among them fruits whose
    # thin stem the trade-off alone removed whole (seeds 4, 64, 84, 104)
    checked = 0
    for s in limb_shapes(120)[::4]:
        for options in ({}, {"trim": False}):
            rows, cols, _ = skelprune.prune(s.mask, **options).skeleton_points()
            for lb in s.limbs:
                checked += 1
                assert limb_reach(lb, s.body, rows, cols) >= 0.5 * lb.length, (s.name, options)
    assert checked > 100


def _disc(stem_half: float | None, noise: float, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[:160, :160].astype(float)
    ang = np.arctan2(yy - 100.3, xx - 80.6)
    # boundary noise: the radius moved by up to `noise` px, changing every few degrees
    wobble = np.interp(ang, np.linspace(-np.pi, np.pi, 120), rng.uniform(-noise, noise, 120))
    mask = np.hypot(yy - 100.3, xx - 80.6) <= 45.2 + wobble
    if stem_half is not None:  # a round-ended stem straight up, 40 px beyond the disc
        mask |= (np.abs(xx - 80.6) <= stem_half) & (yy >= 15.0) & (yy <= 100.0)
        mask |= np.hypot(yy - 15.0, xx - 80.6) <= stem_half
    return mask


def _limb_flags(mask: np.ndarray) -> list[bool]:
    """Whether each end branch of the shape's medial axis is a limb, on the whole axis."""
    ((crop, origin),) = components(mask)
    medial = Skeleton.medial_axis(crop, origin)
    graph = medial.working_graph()
    guard = LimbGuard(graph, medial.mask, medial.r2)
    flags = []
    for b in graph.end_branches():
        flags.append(guard.is_limb(b, 1 << 30))  # (the area is not the test here)
    return flags


@pytest.mark.parametrize("half", [1.5, 2.5, 4.0])
def test_a_stem_is_a_limb_and_the_noise_spurs_are_not(half: float) -> None:
    flags = _limb_flags(_disc(half, 1.0))
    assert len(flags) > 3  # the noise leaves spurs on the medial axis
    assert sum(flags) == 1  # the stem, and none of them
    assert not any(_limb_flags(_disc(None, 1.0)))


@pytest.mark.parametrize("seed", [4, 64, 146, 196])
def test_blobs_whose_limbs_the_trade_off_alone_removes_equal_naive(seed: int) -> None:
    # the limbs benchmark's blobs on which the trade-off alone removed a limb whole: the
    # fast sequence, its limbs kept, equals the oracle's
    start = coarse_dce(Skeleton.medial_axis(np.pad(limb_shape(seed).mask, 1)))
    norm = start.normalisation(9.0)
    fast = pruning_sequence(start, norm.alpha, norm.lbar)
    removed, lams = naive_sequence(
        start.working_graph(), start.mask, start.r2, norm.alpha, norm.lbar
    )
    assert fast.removed == removed
    np.testing.assert_allclose(fast.objective, lams, rtol=0, atol=1e-9)
