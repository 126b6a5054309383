"""Path similarity matching (skelprune.matching): identity, invariances, symmetry, classes."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from PIL import Image

import skelprune
from evaluation.perturb import rotate
from skelprune.matching import describe, distance_matrix
from testkit import DATA


def kimia(name: str) -> np.ndarray:
    return np.asarray(Image.open(DATA / "kimia216" / f"{name}.png")) != 0


def figure(
    arms: list[tuple[float, float, float]], degrees: float = 0.0, size: int = 200
) -> np.ndarray:
    """Elliptic arms (length, width, angle) from the centre, turned by ``degrees``: the
    same figure at any angle, up to pixels (rounded ends: one endpoint an arm)."""
    m = np.zeros((size, size), np.uint8)
    for length, width, angle in arms:
        t = np.deg2rad(angle + degrees)
        centre = (size / 2 + length / 2 * np.cos(t), size / 2 - length / 2 * np.sin(t))
        cv2.ellipse(
            m,
            (round(centre[0] * 16), round(centre[1] * 16)),
            (round(length / 2 * 16), round(width / 2 * 16)),
            -float(np.rad2deg(t)),
            0,
            360,
            1,
            -1,
            cv2.LINE_8,
            4,
        )
    return m.astype(bool)


T_SHAPE = [(80, 16, 0), (40, 24, 90), (60, 12, 200)]
CROSS = [(70, 30, 0), (70, 30, 90), (70, 30, 180), (70, 30, 270)]
SHAPES = ["bird-2", "hammer-1", "bone-1", "fork-1", "elephant-1", "key-1"]


@pytest.mark.parametrize("name", SHAPES)
def test_self_match_is_zero_with_identity_correspondence(name):
    m = kimia(name)
    res = skelprune.match(m, m)
    assert res.distance == 0.0
    assert res.pairs == [(i, i) for i in range(res.a.n_endpoints)]
    assert not res.mirrored


@pytest.mark.parametrize("name", SHAPES)
def test_turned_by_90_and_mirrored_copies_match_at_zero(name):
    m = kimia(name)
    for copy in (np.rot90(m), np.rot90(m, 3), m[:, ::-1], m[::-1]):
        res = skelprune.match(m, copy)
        assert res.distance < 1e-9
        # the correspondence pairs the same endpoints: compare positions mapped back
        assert len(res.pairs) == res.a.n_endpoints == res.b.n_endpoints
    assert skelprune.match(m, m[:, ::-1]).mirrored


def test_mirror_correspondence_maps_positions():
    m = kimia("hammer-1")
    res = skelprune.match(m, m[:, ::-1])
    w = m.shape[1] - 1
    for i, j in res.pairs:
        xa, ya = res.a.positions[i]
        xb, yb = res.b.positions[j]
        assert (w - xa, ya) == (xb, yb)


def test_turned_by_30_degrees_is_close():
    a = figure(T_SHAPE)
    turned = figure(T_SHAPE, 30.0)
    other = figure(CROSS)
    d_turn = skelprune.match(a, turned).distance
    d_other = skelprune.match(a, other).distance
    assert skelprune.describe(turned).n_endpoints == skelprune.describe(a).n_endpoints
    assert d_turn < 0.1 * d_other
    # on dataset shapes (their skeletons change a little when turned) still nearer
    # than a shape of another class
    for name, other_name in (
        ("hammer-1", "bird-2"),
        ("bone-1", "children-1"),
        ("bird-2", "hammer-1"),
    ):
        m = kimia(name)
        assert (
            skelprune.match(m, rotate(m, 30.0)).distance
            < skelprune.match(m, kimia(other_name)).distance
        )


def test_scale_invariance():
    a = figure(T_SHAPE, size=200)
    big = cv2.resize(a.astype(np.uint8), (400, 400), interpolation=cv2.INTER_NEAREST) > 0
    assert skelprune.match(a, big).distance < 0.1 * skelprune.match(a, figure(CROSS)).distance


def test_symmetric():
    names = ["bird-2", "hammer-1", "fork-1", "camel-12", "heart-1"]
    descs = [describe(kimia(n)) for n in names]
    for i, a in enumerate(descs):
        for b in descs[i + 1 :]:
            ab, ba = skelprune.match(a, b), skelprune.match(b, a)
            assert ab.distance == pytest.approx(ba.distance, rel=1e-12, abs=1e-12)
            assert ab.distance > 0
            assert sorted(ab.pairs) == sorted((j, i) for i, j in ba.pairs)
    mat = distance_matrix(descs)
    assert np.allclose(mat, mat.T) and np.all(np.diag(mat) == 0)
    assert mat[0, 1] == pytest.approx(skelprune.match(descs[0], descs[1]).distance)


@pytest.mark.parametrize(
    ("query", "same", "other"),
    [
        ("hammer-1", "hammer-2", "bird-2"),
        ("fork-1", "fork-2", "heart-1"),
        ("elephant-1", "elephant-2", "fork-1"),
        ("bone-1", "bone-2", "children-1"),
    ],
)
def test_same_class_is_closer_than_another_class(query, same, other):
    q = describe(kimia(query))
    assert skelprune.match(q, kimia(same)).distance < skelprune.match(q, kimia(other)).distance


def test_results_and_masks_give_the_same_answer():
    m = kimia("key-1")
    assert skelprune.match(skelprune.prune(m), m).distance == 0.0
    d = skelprune.match(skelprune.prune(m, coarse=None), skelprune.prune(m)).distance
    assert d >= 0.0


def test_correspondence_document():
    m, t = kimia("hammer-1"), kimia("hammer-2")
    res = skelprune.match(m, t)
    doc = res.to_dict()
    assert doc["distance"] == res.distance
    nodes_a = skelprune.prune(m).to_dict()["components"][0]["skeleton"]["nodes"]
    for pair in doc["correspondence"]:
        node = nodes_a[pair["a"]["node"]]
        assert node["kind"] == "endpoint"
        assert (node["x"], node["y"]) == (pair["a"]["x"], pair["a"]["y"])


def test_skeleton_without_two_endpoints_is_refused():
    ring = np.zeros((60, 60), bool)
    cv2.circle(ring.view(np.uint8), (30, 30), 25, 1, -1)
    cv2.circle(ring.view(np.uint8), (30, 30), 12, 0, -1)
    with pytest.raises(skelprune.matching.UnmatchableShapeError, match="endpoint"):
        skelprune.match(ring, kimia("bird-2"))


def test_skeleton_with_too_many_endpoints_is_refused():
    # a comb: one long bar with many teeth, each tooth an endpoint of the skeleton
    m = np.zeros((60, 20 + 8 * 45), bool)
    m[40:52, 5:-5] = True
    for k in range(45):
        m[8:40, 10 + 8 * k : 14 + 8 * k] = True
    res = skelprune.prune(m, coarse=None)
    ends = len(res.to_dict()["components"][0]["skeleton"]["endpoints"])
    assert ends > skelprune.matching.MAX_ENDPOINTS
    with pytest.raises(skelprune.matching.UnmatchableShapeError, match="more than"):
        skelprune.match(res, res)


def test_a_label_is_described_by_its_own_boundary():
    """Two touching labels: the larger one's endpoints are ordered along its own outline,
    as for the label alone, not along the outline of both together."""
    labels = np.zeros((90, 150), np.uint8)
    labels[20:70, 10:100] = 1  # the larger label, touching the next one
    labels[5:85, 100:112] = 2
    labels[40:50, 112:140] = 2
    alone = describe(skelprune.prune(labels == 1))
    within = describe(skelprune.prune(labels, labels=True))
    np.testing.assert_array_equal(within.positions, alone.positions)
    np.testing.assert_array_equal(within.radii, alone.radii)
