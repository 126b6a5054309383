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


def _disc(yy: np.ndarray, xx: np.ndarray, cy: float, cx: float, r: float) -> np.ndarray:
    return (yy - cy) ** 2 + (xx - cx) ** 2 < r * r


def _bar(yy: np.ndarray, xx: np.ndarray, p: tuple, q: tuple, half: float) -> np.ndarray:
    """Pixels within ``half`` of the segment ``p``–``q`` (row, col)."""
    (y0, x0), (y1, x1) = p, q
    dy, dx = y1 - y0, x1 - x0
    t = np.clip(((yy - y0) * dy + (xx - x0) * dx) / (dy * dy + dx * dx), 0, 1)
    return (yy - y0 - t * dy) ** 2 + (xx - x0 - t * dx) ** 2 <= half * half


def lollipop(scale: float = 1.0) -> np.ndarray:
    """A round disc on a slanted stick: one path whose round end must stop near the
    disc's centre (off the pixel grid, so that the digital axis is not symmetric)."""
    h, w = int(80 * scale), int(140 * scale)
    yy, xx = np.mgrid[:h, :w]
    s = scale
    centre = (30.4 * s, 104.7 * s)
    return _disc(yy, xx, *centre, 22.3 * s) | _bar(yy, xx, (70 * s, 8 * s), centre, 4.2 * s)


def dumbbell(scale: float = 1.0) -> np.ndarray:
    """Two discs joined by a bar."""
    h, w = int(70 * scale), int(170 * scale)
    yy, xx = np.mgrid[:h, :w]
    s = scale
    return (
        _disc(yy, xx, 35.3 * s, 32.6 * s, 25.2 * s)
        | _disc(yy, xx, 38.7 * s, 137.2 * s, 24.6 * s)
        | _bar(yy, xx, (35.3 * s, 32.6 * s), (38.7 * s, 137.2 * s), 6.3 * s)
    )


def stick_figure(scale: float = 1.0) -> np.ndarray:
    """A round head on a body with two arms and two legs."""
    h, w = int(200 * scale), int(140 * scale)
    yy, xx = np.mgrid[:h, :w]
    s = scale
    limbs = [
        ((50, 70), (120, 70), 7),  # body
        ((70, 70), (95, 25), 5),  # arms
        ((70, 70), (95, 115), 5),
        ((120, 70), (185, 35), 6),  # legs
        ((120, 70), (185, 105), 6),
    ]
    m = _disc(yy, xx, 32.3 * s, 70.6 * s, 22.4 * s)
    for p, q, half in limbs:
        m |= _bar(yy, xx, (p[0] * s, p[1] * s), (q[0] * s, q[1] * s), half * s)
    return m


#: Shapes drawn here, for tests and benchmarks of round ends.
DRAWN = {"lollipop": lollipop, "dumbbell": dumbbell, "stick_figure": stick_figure}
