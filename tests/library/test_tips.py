"""Tips cut by the trade-off after the answer is chosen (the trimmed answer)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import skelprune
from skelprune.api import components
from skelprune.grid import tips
from skelprune.grid.coarse import coarse_dce
from skelprune.grid.tips import trim_tips
from skelprune.pruning.bayesian import pruning_sequence
from skelprune.pruning.choice import choose_step
from skelprune.skeleton import Skeleton
from testkit.limbs import limb_reach, limb_shape, limb_shapes
from testkit.oracle import disk_pixels, naive_trim, objective
from testkit.shapes import DRAWN, _bar, _disc, blobs, dataset, load, rectangle_with_holes

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
    cuts, lam = naive_trim(graph, answer.mask, answer.r2, alpha, lbar, tips.RULE)
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


# --- the remnant rule: tips lose remnants, never limbs -------------------------------


@pytest.fixture
def tip_rule():
    """Set :data:`skelprune.grid.tips.RULE` for one test, and put it back."""
    before = tips.RULE

    def use(rule: str) -> None:
        tips.RULE = rule

    yield use
    tips.RULE = before


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    seed=st.integers(0, 10_000),
    size=st.integers(24, 48),
    n=st.integers(1, 4),
    rule=st.sampled_from(tips.RULES),
)
def test_every_rule_equals_naive_on_random_shapes(seed, size, n, rule):
    before = tips.RULE
    tips.RULE = rule
    try:
        for crop, _ in components(blobs(seed, size=size, n=n)):
            start = Skeleton.medial_axis(crop)
            norm = start.normalisation(9.0)
            if norm.alpha is not None:
                fast_and_naive(start, norm.alpha, norm.lbar)
    finally:
        tips.RULE = before


@pytest.mark.parametrize("seed", range(0, 300, 25))
@pytest.mark.parametrize("rule", ["both", "reach", "area"])
def test_limb_blobs_equal_naive(seed, rule, tip_rule):
    tip_rule(rule)
    start = Skeleton.medial_axis(np.pad(limb_shape(seed).mask, 1))
    start = coarse_dce(start)
    norm = start.normalisation(9.0)
    assert norm.alpha is not None
    fast_and_naive(start, norm.alpha, norm.lbar)


def test_the_default_rule_cuts_no_limb_the_untrimmed_answer_keeps():
    # every 4th blob of the limbs benchmark: its limbs, kept whole without trimming,
    # stay kept (the skeleton reaches half their length beyond the body)
    shapes = limb_shapes(120)[::4]
    checked = 0
    for s in shapes:
        untrimmed = skelprune.prune(s.mask, trim=False).skeleton_points()
        trimmed = skelprune.prune(s.mask).skeleton_points()
        for lb in s.limbs:
            if limb_reach(lb, s.body, *untrimmed[:2]) >= 0.5 * lb.length:
                checked += 1
                assert limb_reach(lb, s.body, *trimmed[:2]) >= 0.5 * lb.length, s.name
    assert checked > 50


def _body_with_limbs(kind: str) -> tuple[np.ndarray, tuple[float, float], float, list[tuple]]:
    """A disc with one limb, with two limbs, or a fruit (dimpled disc) with its stem;
    each limb as (start inside the body, end, half-width)."""
    yy, xx = np.mgrid[:140, :200]
    centre, radius = (70.3, 90.6), 30.2
    limbs = {
        "one limb": [(centre, (78.3, 185.6), 3.1)],
        "two limbs": [(centre, (78.3, 185.6), 3.1), (centre, (10.2, 40.5), 2.6)],
        "stem": [(centre, (12.4, 96.1), 2.6)],
    }[kind]
    body = _disc(yy, xx, *centre, radius)
    if kind == "stem":
        body &= ~_disc(yy, xx, centre[0] - radius - 4, centre[1], 9.5)
    mask = body.copy()
    for p, q, half in limbs:
        mask |= _bar(yy, xx, p, q, half)
    return mask, centre, radius, limbs


@pytest.mark.parametrize("kind", ["one limb", "two limbs", "stem"])
def test_a_single_path_keeps_its_limbs_and_cuts_its_round_end(kind, tip_rule):
    mask, centre, radius, limbs = _body_with_limbs(kind)
    res = skelprune.prune(mask)
    comp = res.components[0]
    assert not comp.skeleton.graph.end_branches()  # the answer is a single path
    ends = np.asarray(tip_points(res))
    assert len(ends) == 2
    for _, q, half in limbs:
        # the path's end in the limb stops at most a little more than its end disk
        # short of the limb's end
        assert np.hypot(*(ends - q).T).min() < half + 2
    if len(limbs) == 1:
        # the path's other end is in the body: on a disc, its centre; in the fruit, cut
        # back from the dimple towards the centre
        near = np.hypot(*(ends - centre).T).min()
        whole = np.asarray(tip_points(skelprune.prune(mask, trim=False)))
        assert near < (0.3 if kind == "one limb" else 0.5) * radius
        assert near <= np.hypot(*(whole - centre).T).min()
    # the shape really tests the rule: the trade-off alone cuts the limb
    tip_rule("none")
    if kind != "two limbs":  # (there, λ alone keeps both limbs)
        cut = np.asarray(tip_points(skelprune.prune(mask)))
        assert all(np.hypot(*(cut - q).T).min() > 20 for _, q, _ in limbs)


def test_a_hair_one_pixel_wide_is_not_a_remnant(tip_rule):
    # a one-pixel slanted line off a disc keeps its length: each of its points covers
    # its own pixel only, and no other disk covers it
    yy, xx = np.mgrid[:70, :90]
    mask = _disc(yy, xx, 30.3, 30.2, 12.1)
    for t in range(42):
        mask[30 + t * 2 // 3, 30 + t] = True

    def reach() -> int:
        return int(skelprune.prune(mask).skeleton_points()[1].max())

    assert int(skelprune.prune(mask, trim=False).skeleton_points()[1].max()) == 71
    assert reach() >= 70
    tip_rule("area")  # the area rule alone takes it for a remnant: a pixel per point
    assert reach() < 40


@pytest.mark.parametrize("size", [(70, 170), (160, 300)])
def test_a_corner_loses_its_staircase_spur_and_no_more(size):
    # the corner branches' last pixels go (a spur the trade-off does not want), but
    # the cut stays at the pixel scale whatever the rectangle's size
    h, w = size
    mask = np.zeros((h + 10, w + 10), bool)
    mask[5 : h + 5, 5 : w + 5] = True
    corners = np.array([(y, x) for y in (4.5, h + 4.5) for x in (4.5, w + 4.5)])

    def from_corner(**options) -> list[float]:
        ends = tip_points(skelprune.prune(mask, min_margin=0, **options))
        return [float(np.hypot(*(corners - p).T).min()) for p in ends]

    assert len(from_corner()) == 4
    assert max(from_corner(trim=False)) < 3
    assert all(3 < d < 11 for d in from_corner())
