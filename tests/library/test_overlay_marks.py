"""The overlay's node marks scale to their object: a small object's axis stays in sight
(its end marks no wider than a share of its skeleton), a large one's marks stay as they
were, readable on the large picture."""

from __future__ import annotations

import numpy as np

import skelprune
from skelprune.output.render import COLOURS, MARK_SHARE, auto_scale


def _shown(mask: np.ndarray, **options) -> tuple[float, np.ndarray]:
    """The share of the skeleton's pixels drawn as skeleton (not hidden by a mark) in the
    default overlay, and the overlay."""
    res = skelprune.prune(mask, **options)
    scale = auto_scale(mask.shape)
    img = res.render_overlay(scale=scale)
    rows, cols, _ = res.skeleton_points()
    centre = img[rows * scale + scale // 2, cols * scale + scale // 2]
    return float((centre == COLOURS["skeleton"]).all(axis=1).mean()), img


def _ellipse(shape: tuple[int, int], a: float, b: float) -> np.ndarray:
    yy, xx = np.mgrid[: shape[0], : shape[1]]
    return ((yy - shape[0] / 2) / a) ** 2 + ((xx - shape[1] / 2) / b) ** 2 <= 1


def _marked(img: np.ndarray, kind: str) -> int:
    return int((img == COLOURS[kind]).all(axis=2).sum())


def test_a_small_nucleus_keeps_its_axis_in_sight() -> None:
    # a nucleus 21 × 13 px, and a tiny one 9 × 6 px: marks 1.5 px wide hid 36 % and 80 %
    share, img = _shown(_ellipse((24, 30), 6.5, 10.5))
    assert share >= 0.75
    assert _marked(img, "endpoint") > 0  # the ends are still marked
    share, img = _shown(_ellipse((20, 20), 3, 4.5))
    assert share >= 0.5 and _marked(img, "endpoint") > 0


def test_each_label_gets_marks_of_its_size() -> None:
    labels = np.zeros((60, 80), np.uint8)
    labels[_ellipse((60, 80), 25, 35)] = 1
    labels[5:11, 5:13] = 2  # a small object beside a large one
    res = skelprune.prune(labels, labels=True)
    scale = auto_scale(labels.shape)
    img = res.render_overlay(scale=scale)
    small = img[: 12 * scale, : 14 * scale]
    big = img[12 * scale :, 14 * scale :]
    skeleton_small = int((res.skeleton_mask()[:12, :14] == 2).sum())
    # the small object's end marks: at most MARK_SHARE of its skeleton in radius
    cap = max(skeleton_small * MARK_SHARE, 0.5) * scale
    assert _marked(small, "endpoint") <= 2 * np.pi * (cap + 1) ** 2
    assert _marked(big, "endpoint") > _marked(small, "endpoint")


def test_a_large_shapes_marks_are_unchanged() -> None:
    m = np.zeros((300, 400), bool)
    m[100:200, 50:350] = True
    share, img = _shown(m)
    scale = auto_scale(m.shape)
    assert share > 0.9
    # four ends, each a disc of radius 1.5 px at scale 2 (3 px): as before
    assert _marked(img, "endpoint") >= 4 * np.pi * (1.5 * scale - 1) ** 2
