"""GeoJSON validation and rasterisation (skelprune.io.polygon)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from skelprune.errors import ImageTooLargeError, InvalidOptionError, InvalidPolygonError
from skelprune.io.polygon import DEFAULT_LONGEST_SIDE, parse_geojson, polygon_mask

SQUARE = [[0, 0], [10, 0], [10, 10], [0, 10], [0, 0]]
HOLE = [[3, 3], [3, 7], [7, 7], [7, 3], [3, 3]]


def poly(*rings: list) -> dict:
    return {"type": "Polygon", "coordinates": list(rings)}


def world_centres(mask: np.ndarray, frame) -> tuple[np.ndarray, np.ndarray]:
    """Exact pixel centres in polygon coordinates (``frame.point`` rounds what it reports,
    to a thousandth of a pixel; the rasteriser decides on the exact centres)."""
    rows, cols = np.indices(mask.shape)
    x = frame.x0 + cols.ravel() * frame.pixel_size
    y = frame.y0 + (-1 if frame.flip_y else 1) * rows.ravel() * frame.pixel_size
    return x, y


def test_square_pixel_size_exact_area_and_frame() -> None:
    mask, frame = polygon_mask(poly(SQUARE), pixel_size=0.5)
    assert mask.shape == (24, 24)  # 20 px across + a 2 px margin on each side
    assert int(mask.sum()) == 400
    assert frame.flip_y and frame.pixel_size == 0.5
    rows, cols = np.nonzero(mask)
    # Top-left shape pixel maps to the top-left of the square in world units (y up).
    x, y = frame.point(cols.min(), rows.min())
    assert (x, y) == (0.25, 9.75)
    x, y = frame.point(cols.max(), rows.max())
    assert (x, y) == (9.75, 0.25)
    assert not mask[0].any() and not mask[-1].any() and not mask[:, 0].any()
    assert frame.distance(4.0) == 2.0


def test_default_longest_side() -> None:
    mask, frame = polygon_mask(poly([[0, 0], [30, 0], [30, 10], [0, 10], [0, 0]]))
    assert mask.shape == (math.ceil(DEFAULT_LONGEST_SIDE / 3) + 4, DEFAULT_LONGEST_SIDE + 4)
    assert math.isclose(frame.pixel_size, 30 / DEFAULT_LONGEST_SIDE)
    mask, _ = polygon_mask(poly(SQUARE), longest_side=40, margin=1)
    assert mask.shape == (42, 42) and int(mask.sum()) == 1600


def test_hole_and_island() -> None:
    mask, frame = polygon_mask(poly(SQUARE, HOLE), pixel_size=1.0)
    assert int(mask.sum()) == 100 - 16
    # The pixel at the centre of the hole is background.
    col = round((5.0 - frame.x0) / frame.pixel_size)
    row = round((frame.y0 - 5.0) / frame.pixel_size)
    assert not mask[row, col] and mask[row, col - 3]
    # A MultiPolygon with an island inside the hole keeps the island.
    island = [[4, 4], [6, 4], [6, 6], [4, 6], [4, 4]]
    multi = {"type": "MultiPolygon", "coordinates": [[SQUARE, HOLE], [island]]}
    mask, _ = polygon_mask(multi, pixel_size=1.0)
    assert int(mask.sum()) == 100 - 16 + 4


def test_feature_and_collection_union() -> None:
    right = [[20, 0], [30, 0], [30, 10], [20, 10], [20, 0]]
    feature = {"type": "Feature", "properties": {"name": "a"}, "geometry": poly(SQUARE)}
    fc = {
        "type": "FeatureCollection",
        "features": [feature, {"type": "Feature", "properties": None, "geometry": poly(right)}],
    }
    assert int(polygon_mask(feature, pixel_size=1.0)[0].sum()) == 100
    mask, _ = polygon_mask(fc, pixel_size=1.0)
    assert int(mask.sum()) == 200 and mask.shape == (14, 34)


def test_altitude_is_ignored() -> None:
    ring3 = [[x, y, 99.0] for x, y in SQUARE]
    assert int(polygon_mask(poly(ring3), pixel_size=1.0)[0].sum()) == 100


@pytest.mark.parametrize(
    ("obj", "reason"),
    [
        (poly(SQUARE[:-1]), "ring is not closed, first position"),
        (poly([[0, 0], [1, 1], [0, 0]]), "at least 4 positions"),
        (poly([[0, 0], [1, 0], [1, math.nan], [0, 0]]), "not a finite number"),
        (poly([[0, 0], [1, 0], [1, math.inf], [0, 0]]), "not a finite number"),
        (poly([[0, 0], [1, 0], [1, "2"], [0, 0]]), "not a finite number"),
        (poly([[0, 0], [1, 0], [1, True], [0, 0]]), "not a finite number"),
        (poly([[0, 0], [1, 0], [1], [0, 0]]), r"\[x, y\]"),
        (poly([[0, 0], [1, 0], [0, 0], [0, 0]]), "zero area"),
        ({"type": "Polygon", "coordinates": []}, "non-empty array"),
        ({"type": "Point", "coordinates": [0, 0]}, "'Point' is not Polygon"),
        ({"type": "Feature", "geometry": None}, "no geometry"),
        ({"type": "FeatureCollection", "features": []}, "no features"),
        (
            {"type": "FeatureCollection", "features": [poly(SQUARE)]},
            r"features\[0\]: not a Feature",
        ),
        ([1, 2], "expected a GeoJSON object"),
    ],
)
def test_invalid_inputs_say_why(obj: object, reason: str) -> None:
    with pytest.raises(InvalidPolygonError, match=reason):
        polygon_mask(obj)  # type: ignore[arg-type]


def test_error_location_is_reported() -> None:
    multi = {"type": "MultiPolygon", "coordinates": [[SQUARE], [SQUARE, HOLE[:-1]]]}
    with pytest.raises(InvalidPolygonError, match=r"\$\.coordinates\[1\]\[1\]: ring is not closed"):
        polygon_mask(multi)


def test_vertex_limit() -> None:
    parse_geojson(poly(SQUARE, HOLE), max_vertices=10)
    with pytest.raises(InvalidPolygonError, match="10 positions, more than 9 allowed"):
        parse_geojson(poly(SQUARE, HOLE), max_vertices=9)


def test_bow_tie_is_repaired_or_refused() -> None:
    bow = poly([[0, 0], [10, 10], [10, 0], [0, 10], [0, 0]])
    geom = parse_geojson(bow)
    assert len(geom.geoms) == 2 and math.isclose(geom.area, 50.0)
    mask, frame = polygon_mask(bow, pixel_size=0.5)
    x, y = world_centres(mask, frame)
    assert np.array_equal(mask.ravel(), shapely.intersects_xy(geom, x, y))
    with pytest.raises(InvalidPolygonError, match="invalid polygon: Self-intersection"):
        parse_geojson(bow, repair=False)


def test_overlapping_parts_merge() -> None:
    shifted = [[5, 0], [15, 0], [15, 10], [5, 10], [5, 0]]
    multi = {"type": "MultiPolygon", "coordinates": [[SQUARE], [shifted]]}
    assert math.isclose(parse_geojson(multi).area, 150.0)
    assert int(polygon_mask(multi, pixel_size=1.0)[0].sum()) == 150


def test_option_and_size_errors() -> None:
    with pytest.raises(InvalidOptionError, match="not both"):
        polygon_mask(poly(SQUARE), pixel_size=1.0, longest_side=10)
    with pytest.raises(InvalidOptionError, match="finite number from 1e-12 to 1e"):
        polygon_mask(poly(SQUARE), pixel_size=-1.0)
    with pytest.raises(InvalidOptionError, match="integer from 8 to 16384"):
        polygon_mask(poly(SQUARE), longest_side=0)
    with pytest.raises(ImageTooLargeError, match="exceeds the limit of 1000"):
        polygon_mask(poly(SQUARE), pixel_size=0.01, max_pixels=1000)


@settings(max_examples=30, deadline=None)
@given(
    radii=st.lists(st.floats(0.3, 1.0), min_size=3, max_size=25),
    scale=st.floats(0.5, 500.0),
    offset=st.tuples(st.floats(-1e4, 1e4), st.floats(-1e4, 1e4)),
    side=st.integers(8, 120),
)
def test_pixels_are_exactly_the_centres_inside(
    radii: list[float], scale: float, offset: tuple[float, float], side: int
) -> None:
    """Star polygons anywhere at any scale: a pixel is shape iff its centre is in the polygon."""
    angles = np.linspace(0, 2 * np.pi, len(radii), endpoint=False)
    xs = offset[0] + scale * np.array(radii) * np.cos(angles)
    ys = offset[1] + scale * np.array(radii) * np.sin(angles)
    ring = [[float(x), float(y)] for x, y in zip(xs, ys, strict=True)]
    obj = poly([*ring, ring[0]])
    mask, frame = polygon_mask(obj, longest_side=side)
    assert max(mask.shape) == side + 4
    geom = shapely.Polygon(ring)
    x, y = world_centres(mask, frame)
    expected = shapely.intersects_xy(geom, x, y).reshape(mask.shape)
    assert np.array_equal(mask, expected)
    assert mask.any()


@pytest.mark.parametrize(
    ("obj", "kwargs", "error", "reason"),
    [
        (poly(SQUARE), {"pixel_size": 5e-324}, InvalidOptionError, "pixel_size must be"),
        (poly([[x * 1e-320, y * 1e-320] for x, y in SQUARE]), {}, InvalidPolygonError, "zero area"),
        (
            poly([[-1e308, 0], [1e308, 0], [1e308, 1], [-1e308, 1], [-1e308, 0]]),
            {},
            InvalidPolygonError,
            "too large a range",
        ),
    ],
)
def test_extreme_scales_are_refused_cleanly(
    obj: dict, kwargs: dict, error: type[Exception], reason: str
) -> None:
    with pytest.raises(error, match=reason):
        polygon_mask(obj, **kwargs)
