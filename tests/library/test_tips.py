"""Tips cut by the trade-off after the answer is chosen (the trimmed answer)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import skelprune
from skelprune.api import components
from skelprune.pruning.bayesian import choose_step, pruning_sequence
from skelprune.pruning.coarse import coarse_dce
from skelprune.pruning.tips import trim_tips
from skelprune.skeleton import Skeleton
from testkit.oracle import disk_pixels, naive_trim, objective
from testkit.shapes import DRAWN, blobs, dataset, load, rectangle_with_holes

K216 = dataset("kimia216")
K99 = dataset("kimia99")

CASES = (
    [pytest.param(("k216", i), id=f"kimia216-{K216[i].stem}") for i in range(3, 204, 25)]
    + [pytest.param(("k99", i), id=f"kimia99-{K99[i].stem}") for i in range(5, 99, 24)]
    + [pytest.param(("drawn", name), id=f"drawn-{name}") for name in DRAWN]
    + [pytest.param(("holes", 0), id="rectangle-two-holes")]
)


def make(case: tuple[str, object]) -> np.ndarray:
    kind, key = case
    if kind == "k216":
        return load(K216[key])
    if kind == "k99":
        return load(K99[key])
    if kind == "drawn":
        return DRAWN[key]()
    return rectangle_with_holes()


def fast_and_naive(start: Skeleton, alpha: float, lbar: float) -> tuple[int, int]:
    """Trim the greedy's answer from ``start`` both ways; assert they agree exactly.

    Returns the number of ends and of points cut.
    """
    seq = pruning_sequence(start, alpha, lbar)
    chosen = choose_step(seq.objective)
    answer = seq.skeleton_at(chosen)
    fast = trim_tips(answer, seq.lost[chosen], alpha, lbar)
    graph = answer.working_graph()
    cuts, lam = naive_trim(graph, answer.mask, answer.r2, alpha, lbar)
    assert fast.cuts == cuts
    assert objective(fast.lost, answer.area, fast.na, fast.nd, alpha, lbar) == pytest.approx(
        lam, abs=1e-9
    )
    # the same points are left
    assert np.array_equal(fast.skeleton.points(), graph.alive_points())
    # λ can only fall, and the endpoints stay
    assert lam <= seq.objective[chosen] + 1e-12
    assert fast.skeleton.n_endpoints == answer.n_endpoints
    # each end branch's exclusive pixels: those only its kept points' disks cover
    disks = disk_pixels(graph.rows, graph.cols, answer.r2, answer.mask.shape)
    size = answer.mask.size
    flat = answer.mask.ravel()

    def count(points: list[int]) -> np.ndarray:
        hit = [disks[p] for p in points]
        return np.bincount(np.concatenate(hit), minlength=size) if hit else np.zeros(size, int)

    every = count(list(graph.alive_points()))
    assert set(fast.exclusive) == set(graph.end_branches())
    for b, n in fast.exclusive.items():
        own = count(graph.branches[b].points)
        assert n == int((flat & (own > 0) & (own == every)).sum())
    return len(cuts), sum(k for *_, k in cuts)


@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("coarse", [False, True], ids=["full", "coarse"])
def test_trim_equals_naive(case, coarse):
    ends = 0
    for crop, _ in components(make(case)):
        start = Skeleton.medial_axis(crop)
        if coarse and start.end_branches():
            start = coarse_dce(start)
        norm = start.normalisation(9.0)
        if norm.alpha is None:
            continue
        ends += fast_and_naive(start, norm.alpha, norm.lbar)[0]
    assert ends > 0  # the case really had tips to cut


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    seed=st.integers(0, 10_000),
    size=st.integers(24, 48),
    n=st.integers(1, 4),
    holes=st.integers(0, 1),
)
def test_trim_equals_naive_on_random_shapes(seed, size, n, holes):
    for crop, _ in components(blobs(seed, size=size, n=n, holes=holes)):
        start = Skeleton.medial_axis(crop)
        norm = start.normalisation(9.0)
        if norm.alpha is not None:
            fast_and_naive(start, norm.alpha, norm.lbar)


def tip_points(res: skelprune.PruneResult) -> list[tuple[float, float]]:
    doc = res.to_dict(curve=False)["components"][0]["skeleton"]
    return [(n["y"], n["x"]) for n in doc["nodes"] if n["kind"] == "endpoint"]


def test_a_round_head_ends_near_its_centre_not_on_the_boundary():
    # the stick figure's head: disc of radius 22.4 at (32.3, 70.6)
    mask = DRAWN["stick_figure"]()
    centre, radius = np.array([32.3, 70.6]), 22.4
    for coarse in ("dce", None):
        far = {
            trim: min(np.hypot(*(np.array(p) - centre)) for p in tip_points(res))
            for trim in (False, True)
            for res in [skelprune.prune(mask, coarse=coarse, trim=trim)]
        }
        assert far[False] > 0.8 * radius  # the hook: the greedy's tip runs to the boundary
        assert far[True] < 0.25 * radius


def test_a_single_path_is_trimmed_at_both_ends():
    # a dumbbell's axis is one path: both round ends come back to their centres
    mask = DRAWN["dumbbell"]()
    res = skelprune.prune(mask)
    comp = res.components[0]
    assert comp.alpha is not None  # defined for a single path
    assert comp.trim is not None and [k > 0 for *_, k in comp.trim.cuts] == [True, True]
    centres = np.array([[35.3, 32.6], [38.7, 137.2]])
    for p in tip_points(res):
        assert np.hypot(*(centres - p).T).min() < 3


def test_trim_false_is_the_untrimmed_answer_and_trim_only_lowers_the_target():
    for case in CASES[::3]:
        mask = make(case.values[0])
        whole = skelprune.prune(mask, trim=False)
        cut = skelprune.prune(mask)
        assert whole.to_dict()["trim"] is False and cut.to_dict()["trim"] is True
        for w, c in zip(whole.components, cut.components, strict=True):
            assert w.trim is None
            untrimmed = w.sequence.skeleton_at(w.chosen_step)
            assert np.array_equal(w.skeleton.points(), untrimmed.points())
            assert c.objective <= w.objective
            assert c.graph.n_endpoints() == w.graph.n_endpoints()
            assert set(c.skeleton.points().tolist()) <= set(w.skeleton.points().tolist())


def test_the_document_describes_the_trimmed_skeleton():
    from skelprune.grid.reconstruction import reconstruction

    res = skelprune.prune(DRAWN["stick_figure"]())
    comp = res.components[0]
    doc = res.to_dict()["components"][0]
    idx = comp.skeleton.points()
    sk = comp.skeleton
    rec = reconstruction(sk.mask.shape, sk.rows[idx], sk.cols[idx], sk.r2[idx])
    assert doc["rer"] == pytest.approx((sk.mask & ~rec).sum() / sk.area, abs=1e-15)
    point = doc["curve"][doc["chosen_step"]]
    assert (point["ar"], point["objective"]) == (doc["rer"], doc["objective"])
    assert point["length"] == doc["skeleton"]["length"]
    total = sum(b["length"] for b in doc["skeleton"]["branches"])
    assert doc["skeleton"]["length"] == pytest.approx(total, abs=1e-9)
    # the end branches' margins are measured from the trimmed skeleton
    ends = [b for b in doc["skeleton"]["branches"] if b["margin"] is not None]
    assert ends and all(b["margin"] > 0 for b in ends)
    geo = res.to_geojson()
    assert geo["properties"]["trim"] is True
    assert geo["properties"]["components"][0]["objective"] == doc["objective"]


def test_method_dce_is_not_trimmed():
    res = skelprune.prune(DRAWN["stick_figure"](), method="dce")
    assert res.to_dict()["trim"] is False
    assert res.components[0].trim is None


@pytest.mark.parametrize("value", ["yes", 1, None])
def test_trim_must_be_a_flag(value):
    with pytest.raises(skelprune.InvalidOptionError, match="trim must be true or false"):
        skelprune.prune(DRAWN["lollipop"](), trim=value)
