"""Ends where a shape runs off the image: kept whole, the axis running to the border."""

from __future__ import annotations

import numpy as np
from skimage.measure import euler_number, label

import skelprune
from skelprune.grid._open_edge import open_edge


def _ends(res: skelprune.PruneResult) -> list[tuple[float, float]]:
    nodes = res.to_dict()["components"][0]["skeleton"]["nodes"]
    return [(n["x"], n["y"]) for n in nodes if n["kind"] == "endpoint"]


def _bar_with_vessel(top: int) -> np.ndarray:
    """A bar with a 10-px vessel rising from it to row ``top`` (0: off the image)."""
    m = np.zeros((60, 80), bool)
    m[top:40, 30:40] = True
    m[30:40, 10:70] = True
    return m


def test_a_vessel_off_the_image_keeps_its_end_at_the_border() -> None:
    ends = _ends(skelprune.prune(_bar_with_vessel(0)))
    assert any(y == 0 and 33 <= x <= 36 for x, y in ends), ends  # at the border, centred
    # the same vessel ending inside the image is a tip: its axis stops short of its end
    inside = _ends(skelprune.prune(_bar_with_vessel(3)))
    assert all(y > 3 for _, y in inside), inside


def test_an_end_at_the_border_is_never_pruned() -> None:
    """A thin short stub off the image: the trade-off would prune it inside the image."""
    m = np.zeros((70, 120), bool)
    m[8:38, 10:110] = True
    m[0:8, 58:60] = True  # 2 px wide, off the top
    off = _ends(skelprune.prune(m))
    assert any(y == 0 for _, y in off), off
    inner = m.copy()
    inner[0:2] = False  # the same stub ending two pixels inside
    assert not any(y < 12 for _, y in _ends(skelprune.prune(inner)))


def test_a_shape_lying_along_the_border_is_as_if_padded() -> None:
    """A wide contact is no crossing: the answer equals that of the padded image."""
    m = np.zeros((50, 90), bool)
    m[30:50, 5:85] = True  # sits on the bottom row along 80 px
    m[10:30, 40:50] = True
    a = skelprune.prune(m).to_dict(curve=False)["components"][0]
    b = skelprune.prune(np.pad(m, ((0, 1), (0, 0)))).to_dict(curve=False)["components"][0]
    assert a == b


def test_open_edge_on_a_label_crop_and_nowhere_else() -> None:
    crop = np.zeros((6, 6), bool)
    crop[1:5, 1:5] = True
    assert open_edge(crop, (3, 3), (20, 20), 0.7) is None  # inside the image
    edge = open_edge(crop, (-1, 3), (20, 20), 0.7)  # cut by the top: a 4-px crossing
    assert edge is not None and edge[0, 1:5].all() and edge.sum() == 4


def test_a_hole_beside_the_border_keeps_its_cycle() -> None:
    """The shape gone on across the border must not open the axis round a hole that
    lies inside the image (found by test_library's property test): the axis keeps the
    shape's topology, or the plain axis is taken."""
    rows = [
        ".............########.",
        "....###.....#####...##",
        "...#####...######...##",
        "...#####...######...##",
        "...#####...###########",
        "...#####....##########",
        "...######....########.",
        "...#####.......####...",
        "...#####..............",
        "....####..............",
        "....###...............",
    ]
    m = np.zeros((22, 22), bool)  # the shape in the lower part, off the right border
    m[11:] = [[c == "#" for c in r] for r in rows]
    res = skelprune.prune(m)
    skeleton = np.zeros(m.shape, bool)
    r, c, _ = res.skeleton_points()
    skeleton[r, c] = True
    assert euler_number(skeleton, connectivity=2) == euler_number(m, connectivity=2) == 1
    assert label(skeleton, connectivity=2).max() == label(m, connectivity=2).max() == 2
