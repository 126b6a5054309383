"""Inputs a hostile or careless client can send: tiny as PNGs or JSON, as hard as they
can be.

Each mask generator makes a square ``n``-pixel mask whose boundary, skeleton or
component count is as large as the pixel count allows; the polygon generators make
GeoJSON with many parts or many vertices. The tests run them small (fast);
``python -m benchmarks adversarial`` runs them at the service's limits against the real
server.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

__all__ = [
    "CORPUS",
    "checkerboard",
    "circle_polygon",
    "dots",
    "fractal",
    "lines",
    "noise",
    "unit_squares",
]


def noise(n: int, density: float, seed: int = 0) -> np.ndarray:
    """Each pixel foreground with probability ``density``, independently."""
    return np.random.default_rng(seed).random((n, n)) < density


def checkerboard(n: int, cell: int = 1) -> np.ndarray:
    """Squares of ``cell`` pixels, alternating: at ``cell=1`` every pixel is a corner."""
    idx = np.arange(n) // cell
    return (idx[:, None] + idx[None, :]) % 2 == 0


def lines(n: int, gap: int = 2) -> np.ndarray:
    """One-pixel horizontal lines every ``gap`` rows, joined by a one-pixel spine on the
    left: a comb, one component with ``n / gap`` end branches of the full width."""
    mask = np.zeros((n, n), bool)
    mask[1:-1:gap, 1:-1] = True
    mask[1:-1, 1] = True
    return mask


def dots(n: int, gap: int = 2) -> np.ndarray:
    """Isolated single pixels every ``gap`` pixels: ``(n / gap)²`` components."""
    mask = np.zeros((n, n), bool)
    mask[1:-1:gap, 1:-1:gap] = True
    return mask


def fractal(n: int, seed: int = 0) -> np.ndarray:
    """A disk whose radius wanders at every scale (1/f noise over 2 to n/4 wiggles per
    turn), on top of a Sierpinski-carpet of holes: a long, rough outer boundary and
    holes of every size."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[:n, :n].astype(np.float64)
    c = (n - 1) / 2
    angle = np.arctan2(yy - c, xx - c)
    radius = np.full_like(angle, 0.36 * n)
    k = 2
    while k <= max(2, n // 4):
        radius += 0.08 * n / k**0.7 * np.sin(k * angle + rng.uniform(0, 2 * np.pi))
        k *= 2
    mask = np.hypot(yy - c, xx - c) <= radius
    step = 3
    iy, ix = np.mgrid[:n, :n]
    while step <= n:
        third = step // 3
        mask &= ~(((iy % step) // third == 1) & ((ix % step) // third == 1))
        step *= 3
    return mask


#: Name -> generator of an ``n``-pixel square mask: the adversarial corpus.
CORPUS: dict[str, Callable[[int], np.ndarray]] = {
    "noise 10%": lambda n: noise(n, 0.1),
    "noise 50%": lambda n: noise(n, 0.5),
    "noise 90%": lambda n: noise(n, 0.9),
    "checkerboard 1 px": lambda n: checkerboard(n, 1),
    "checkerboard 3 px": lambda n: checkerboard(n, 3),
    "fractal": fractal,
    "1-px lines": lines,
    "tiny components": dots,
}


def unit_squares(n: int, gap: float = 2.0) -> dict[str, Any]:
    """A MultiPolygon of ``n`` unit squares on a grid, ``gap`` apart: many small parts
    (20,000 of them are a 1.2 MB body)."""
    side = math.ceil(math.sqrt(n))
    parts = []
    for i in range(n):
        x, y = gap * (i % side), gap * (i // side)
        parts.append([[[x, y], [x + 1, y], [x + 1, y + 1], [x, y + 1], [x, y]]])
    return {"type": "MultiPolygon", "coordinates": parts}


def circle_polygon(vertices: int, radius: float = 1000.0, digits: int = 6) -> dict[str, Any]:
    """A Polygon of ``vertices`` positions on a circle (coordinates rounded to
    ``digits``): one part, many vertices."""
    ring = [
        [
            round(radius * math.cos(2 * math.pi * k / vertices), digits),
            round(radius * math.sin(2 * math.pi * k / vertices), digits),
        ]
        for k in range(vertices)
    ]
    return {"type": "Polygon", "coordinates": [[*ring, ring[0]]]}
