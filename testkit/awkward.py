"""Awkward shapes for the answers' one rule (no NaN or infinity in any answer): cycles,
lakes with islands, one-pixel components, straight lines, loops, shapes touching the
border, noise; as masks, polygons and volumes; and the checks that find a number that
is not finite in an answer's text.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from typing import Any

import numpy as np
from shapely.geometry import MultiPolygon, Point, box, mapping

from testkit.shapes import rectangle_with_holes, touching_border

__all__ = [
    "CRS",
    "NOT_FINITE",
    "assert_finite_json",
    "assert_finite_text",
    "lake_with_islands",
    "masks",
    "noise",
    "polygons",
    "volumes",
]

#: A projected CRS in metres: map lines and branches agree on the ground.
CRS = {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::32633"}}
#: A number that is not finite as Python, numpy, C or JSON writers spell it.
NOT_FINITE = re.compile(r"(?<![\w.])[-+]?(nan|inf|infinity)(?![\w.])", re.IGNORECASE)


def _refuse(token: str) -> Any:
    raise AssertionError(f"a number that is not finite in the answer: {token}")


def assert_finite_json(body: str | bytes) -> Any:
    """The JSON document, parsed; an assertion error at a NaN or an Infinity."""
    return json.loads(body, parse_constant=_refuse)


def assert_finite_text(text: str) -> None:
    """An assertion error at a word of ``text`` that spells a number not finite."""
    found = NOT_FINITE.search(text)
    assert found is None, f"a number that is not finite in the answer: {found.group(0)!r}"


def noise(seed: int = 3) -> np.ndarray:
    """Salt-and-pepper foreground: junctions so close that a branch has no direction
    (its junction angles are not defined)."""
    rng = np.random.default_rng(seed)
    h, w = rng.integers(20, 90, 2)
    return rng.random((h, w)) < rng.uniform(0.5, 0.8)


def _disc_mask(shape: tuple[int, int], discs: list[tuple[float, float, float]]) -> np.ndarray:
    yy, xx = np.mgrid[: shape[0], : shape[1]]
    out = np.zeros(shape, bool)
    for cy, cx, r in discs:
        out ^= (yy - cy) ** 2 + (xx - cx) ** 2 <= r * r
    return out


def masks() -> dict[str, np.ndarray]:
    """Image masks, by name."""
    ring = _disc_mask((48, 48), [(24, 24, 16), (24, 24, 8)])
    lake = _disc_mask((80, 80), [(40, 40, 36), (28, 50, 7), (50, 28, 9), (55, 52, 5)])
    specks = np.zeros((30, 40), bool)
    specks[10:20, 10:30] = True
    specks[2, 2] = specks[27, 37] = specks[5, 35] = True  # one-pixel components
    pixel = np.zeros((5, 5), bool)
    pixel[2, 2] = True
    line = np.zeros((9, 40), bool)
    line[4, 3:37] = True
    diagonal = np.eye(30, dtype=bool)
    loop = np.zeros((20, 20), bool)
    loop[4, 4:16] = loop[15, 4:16] = loop[4:16, 4] = loop[4:16, 15] = True
    return {
        "ring": ring,
        "figure-eight": rectangle_with_holes(),
        "lake": lake,
        "specks": specks,
        "pixel": pixel,
        "line": line,
        "diagonal": diagonal,
        "loop": loop,
        "full": np.ones((12, 20), bool),
        "border": touching_border(),
        "noise": noise(),
    }


def lake_with_islands() -> dict[str, Any]:
    """A lake with three islands (a polygon with holes), in metres (EPSG:32633)."""
    lake = Point(500_000, 5_000_000).buffer(1000, 64)
    for (x, y), r in (((300, 200), 150), ((-350, -100), 200), ((100, -450), 120)):
        lake = lake.difference(Point(500_000 + x, 5_000_000 + y).buffer(r, 32))
    return {**mapping(lake), "crs": CRS}


def _geojson(geom: Any) -> dict[str, Any]:
    return {**json.loads(json.dumps(mapping(geom))), "crs": CRS}


def polygons() -> dict[str, dict[str, Any]]:
    """GeoJSON polygons, by name (planar, EPSG:32633)."""
    x, y = 500_000, 5_000_000
    ring = Point(x, y).buffer(400, 32).difference(Point(x, y).buffer(250, 32))
    speck = MultiPolygon([box(x, y, x + 3000, y + 800), box(x + 5000, y, x + 5010, y + 10)])
    return {
        "lake-with-islands": json.loads(json.dumps(lake_with_islands())),
        "ring": _geojson(ring),
        "reach": _geojson(box(x, y, x + 4000, y + 60)),
        "speck": _geojson(speck),
        "square": _geojson(box(x, y, x + 500, y + 500)),
    }


def _volume(build: Callable[[np.ndarray], None], shape: tuple[int, int, int]) -> np.ndarray:
    v = np.zeros(shape, bool)
    build(v)
    return v


def volumes() -> dict[str, np.ndarray]:
    """Volumes (z, y, x), by name."""

    def ring(v: np.ndarray) -> None:  # a square ring of bars: a cycle
        v[3:7, 3:7, 3:27] = v[3:7, 23:27, 3:27] = True
        v[3:7, 3:27, 3:7] = v[3:7, 3:27, 23:27] = True

    def border(v: np.ndarray) -> None:  # a bar through the whole volume
        v[:, 3:7, 3:7] = True

    def specks(v: np.ndarray) -> None:  # a bar and single voxels
        v[3:7, 4:8, 2:22] = True
        v[1, 1, 1] = v[8, 10, 20] = True

    return {
        "ring": _volume(ring, (10, 30, 30)),
        "border": _volume(border, (16, 10, 10)),
        "specks": _volume(specks, (10, 12, 24)),
    }
