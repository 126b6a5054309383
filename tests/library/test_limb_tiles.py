"""The limb test on the coverage's tiles equals the box test it replaced, call by call;
the noise floor's one-pass lost areas equal the removal-by-removal count."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import ndimage

import skelprune
from benchmarks.bench_large import blob
from skelprune.api import components
from skelprune.grid._rowcover import cover_counts, uncover_count
from skelprune.grid.limbs import LimbGuard
from skelprune.pruning.bayesian import pruning_sequence
from skelprune.skeleton import Skeleton, grown_r2
from testkit.limbs import box_limb_test, checked_limb_tests, limb_shapes
from testkit.shapes import blobs, dataset, load, stick_figure


def _shapes() -> list[np.ndarray]:
    out = [s.mask for s in limb_shapes(40)[::2]]
    out += [blobs(seed, 96, n=5, holes=seed % 3) for seed in range(8)]
    out += [load(p) for p in dataset("kimia216")[::17]]
    out += [blob(name, 256) for name in ("apple", "octopus", "cup", "heart")]
    out.append(stick_figure(1.5))
    return out


def test_every_limb_test_of_the_pipeline_equals_the_box_test() -> None:
    with checked_limb_tests() as calls:
        for mask in _shapes():
            for options in ({}, {"trim": False}, {"coarse": "dce"}):
                skelprune.prune(mask, **options)
    assert calls[0] > 300  # compared on this many end branches


def test_the_noisy_limbs_and_rough_blobs_equal_the_box_test() -> None:
    # boundary noise leaves many spurs with a few whole disks each: the rule's edge
    rng = np.random.default_rng(7)
    with checked_limb_tests() as calls:
        for mask in [s.mask for s in limb_shapes(16, seed=3)] + [blob("cup", 300)]:
            inner = mask & ~ndimage.binary_erosion(mask)
            outer = ndimage.binary_dilation(mask) & ~mask
            flip = (inner | outer) & (rng.random(mask.shape) < 0.3)
            skelprune.prune(mask ^ flip, coarse="none", trim=False)
    assert calls[0] > 20  # (most noise spurs alone cover too little to be tested)


def test_a_standalone_guard_keeps_its_own_coverage_up_to_date() -> None:
    # without a sequence's coverage to follow, the guard makes its own and follows the
    # removals itself: the same answers as the box test, end branch after end branch
    tested = 0
    for mask in [blob(name, 300) for name in ("octopus", "apple", "cup")] + [
        s.mask for s in limb_shapes(6)
    ]:
        ((crop, origin),) = components(mask)
        medial = Skeleton.medial_axis(crop, origin)
        graph = medial.working_graph()
        guard = LimbGuard(graph, medial.mask, medial.r2)
        while graph.ends:
            b = min(graph.ends)
            if not guard.limb[b]:  # (a limb found is remembered, merged on)
                found = guard.is_limb(b, 1 << 30)
                assert found == box_limb_test(graph, medial.mask, medial.r2, b)
                tested += 1
            guard.removed(b)
            merged = graph.remove_end_branch(b)
            if merged is not None:
                guard.merged(merged[0], merged[1])
    assert tested > 20


def _lost_one_by_one(sk: Skeleton, reach: float, removals: list[np.ndarray]) -> np.ndarray:
    pad = math.ceil(reach) + 1
    shape = np.pad(sk.mask, pad)
    rows, cols, r2 = sk.rows + pad, sk.cols + pad, grown_r2(sk.r2, reach)
    idx = sk.points()
    c = cover_counts(shape.shape[0], shape.shape[1], rows[idx], cols[idx], r2[idx])
    lost = [int(np.count_nonzero(shape & (c == 0)))]
    for pts in removals:
        lost.append(lost[-1] + uncover_count(c, shape, rows[pts], cols[pts], r2[pts]))
    return np.asarray(lost, np.int64)


@pytest.mark.parametrize("reach", [0.5 * 2**0.5, 2.2, 4.0])
def test_the_lost_areas_in_one_pass_equal_removal_by_removal(reach: float) -> None:
    for mask in [s.mask for s in limb_shapes(10)] + [blob("apple", 200)]:
        sk = Skeleton.medial_axis(np.pad(mask, 1))
        norm = sk.normalisation(9.0)
        seq = pruning_sequence(sk, norm.alpha, norm.lbar)
        removals = [seq.log.points(i) for i in range(len(seq.log))]
        assert len(removals) > 0
        np.testing.assert_array_equal(
            sk.lost_along(reach, removals), _lost_one_by_one(sk, reach, removals)
        )
