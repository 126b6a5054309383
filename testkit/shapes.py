"""Test shapes: dataset silhouettes and synthetic shapes with holes and components."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image

from testkit import DATA


def dataset(name: str) -> list[Path]:
    return sorted((DATA / name).glob("*.png"))


def load(path: Path, factor: int = 1) -> np.ndarray:
    """A dataset mask, optionally reduced by an integer factor (majority of blocks)."""
    m = np.asarray(Image.open(path)) > 0
    if factor > 1:
        h, w = (m.shape[0] // factor) * factor, (m.shape[1] // factor) * factor
        m = m[:h, :w].reshape(h // factor, factor, w // factor, factor).mean((1, 3)) >= 0.5
    return m


def blobs(seed: int, size: int = 64, n: int = 4, holes: int = 0) -> np.ndarray:
    """Union of random ellipses, with ``holes`` small elliptic holes cut out."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[:size, :size]
    m = np.zeros((size, size), bool)
    for _ in range(n):
        cy, cx = rng.uniform(0.2, 0.8, 2) * size
        a, b = rng.uniform(0.08, 0.3, 2) * size
        t = rng.uniform(0, np.pi)
        u = (xx - cx) * np.cos(t) + (yy - cy) * np.sin(t)
        v = -(xx - cx) * np.sin(t) + (yy - cy) * np.cos(t)
        m |= (u / a) ** 2 + (v / b) ** 2 <= 1
    for _ in range(holes):
        ys, xs = np.nonzero(m)
        if not len(ys):
            break  # the holes have eaten the shape
        k = rng.integers(len(ys))
        r = rng.uniform(1.5, 4)
        m &= (yy - ys[k]) ** 2 + (xx - xs[k]) ** 2 > r * r
    return m


def rectangle_with_holes(h: int = 40, w: int = 70) -> np.ndarray:
    m = np.zeros((h, w), bool)
    m[3:-3, 3:-3] = True
    m[12:20, 14:24] = False
    m[10:30, 40:46] = False
    return m


def touching_border() -> np.ndarray:
    m = np.zeros((40, 50), bool)
    m[:, 10:30] = True  # touches top and bottom
    m[15:25, 30:] = True  # touches the right border
    return m


def two_components() -> np.ndarray:
    m = np.zeros((50, 80), bool)
    m[5:25, 5:40] = True
    yy, xx = np.mgrid[:50, :80]
    m |= (yy - 35) ** 2 + (xx - 60) ** 2 < 120
    m[33:37, 58:62] = False  # a hole in the second component
    return m
