"""Generated rivers with a known centre line, for the polygon tests and the GIS benchmark.

A river is a meandering centre line (a sum of sines along x, resampled to even steps)
widened on both sides by a width that varies smoothly between ``width_min`` and
``width_max``; its ends are cut straight across, as a reach cut out of a longer river is.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import shapely
from shapely.geometry import LineString, Polygon


@dataclass(frozen=True)
class River:
    polygon: Polygon
    centre: LineString  # the true centre line, end to end
    width_min: float
    width_max: float

    def geojson(self) -> dict[str, Any]:
        return shapely.geometry.mapping(self.polygon)  # type: ignore[no-any-return]


def river(
    length: float = 50_000.0,
    width_min: float = 20.0,
    width_max: float = 200.0,
    wavelength: float = 3_000.0,
    amplitude: float = 300.0,
    step: float | None = None,
    seed: int = 0,
) -> River:
    """A meandering river about ``length`` long (along its centre line).

    The meander's smallest radius of curvature stays above half the widest width, so
    the two banks never cross.

    >>> r = river(5_000, 20, 60, seed=1)
    >>> r.polygon.is_valid, round(r.centre.length / 1000)
    (True, 5)
    """
    rng = np.random.default_rng(seed)
    step = step or width_min / 2
    # a dense centre line, then resampled by arc length
    x = np.linspace(0, length, int(length / step) * 4 + 2)
    phases = rng.uniform(0, 2 * np.pi, 3)
    y = amplitude * (
        np.sin(2 * np.pi * x / wavelength + phases[0])
        + 0.3 * np.sin(2 * np.pi * x / (wavelength * 2.7) + phases[1])
    )
    for _ in range(3):  # shrink x until the centre line is ``length`` long
        seg = np.hypot(np.diff(x), np.diff(y))
        x = x * length / seg.sum()
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])
    s = np.linspace(0, arc[-1], int(arc[-1] / step) + 1)
    pts = np.stack([np.interp(s, arc, x), np.interp(s, arc, y)], 1)
    t = s / arc[-1]
    # width: a slow wave between the bounds
    k = rng.uniform(0, 2 * np.pi, 2)
    mix = 0.5 + 0.5 * np.sin(2 * np.pi * 3.3 * t + k[0]) * np.cos(2 * np.pi * 1.1 * t + k[1])
    mix = (mix - mix.min()) / max(float(np.ptp(mix)), 1e-12)  # both bounds reached
    width = width_min + (width_max - width_min) * mix
    d = np.gradient(pts, axis=0)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    normal = np.stack([-d[:, 1], d[:, 0]], 1)
    left = pts + normal * (width[:, None] / 2)
    right = pts - normal * (width[:, None] / 2)
    ring = np.concatenate([left, right[::-1], left[:1]])
    poly = shapely.make_valid(Polygon(ring))
    if not isinstance(poly, Polygon):  # never expected: the banks do not cross
        poly = max(shapely.get_parts(poly), key=lambda g: g.area)
    return River(poly, LineString(pts), width_min, width_max)


def on_earth(shape: Any, lon0: float, lat0: float) -> Any:
    """A shape in metres placed on the Earth: longitude/latitude (WGS 84) of the points
    whose local azimuthal equidistant coordinates about ``(lon0, lat0)`` are the shape's,
    so that it keeps its ground size and shape there (the ``geo`` extra's pyproj).

    >>> from shapely.geometry import box
    >>> g = on_earth(box(0, 0, 1000, 1000), 10.0, 70.0)
    >>> round(g.bounds[2] - g.bounds[0], 4), round(g.bounds[3] - g.bounds[1], 4)  # degrees
    (0.0262, 0.009)
    """
    import pyproj

    local = pyproj.CRS.from_proj4(f"+proj=aeqd +lat_0={lat0} +lon_0={lon0} +datum=WGS84 +units=m")
    back = pyproj.Transformer.from_crs(local, "EPSG:4326", always_xy=True)
    return shapely.transform(shape, lambda xy: np.column_stack(back.transform(*xy.T)))


def ragged_ring(
    radius: float,
    roughness: float,
    rng: np.random.Generator,
    centre: tuple[float, float] = (0.0, 0.0),
    stretch: float = 1.0,
    n: int = 2000,
) -> np.ndarray:
    """A closed ragged outline: a circle whose radius carries noise at every scale
    (harmonics 2–300, amplitudes falling as ``k^-1.6``, as natural shores do), stretched
    ``stretch`` times along x."""
    theta = np.linspace(0, 2 * np.pi, n, endpoint=False)
    k = np.arange(2, 301)
    amp = rng.standard_normal(len(k)) * k**-1.6
    amp *= roughness / np.sqrt((amp**2).sum() / 2)
    phase = rng.uniform(0, 2 * np.pi, len(k))
    r = radius * (1 + (amp[:, None] * np.sin(k[:, None] * theta + phase[:, None])).sum(0))
    r = np.maximum(r, 0.25 * radius)
    x = centre[0] + stretch * r * np.cos(theta)
    y = centre[1] + r * np.sin(theta)
    return np.column_stack([x, y])


def lake(
    radius: float = 1000.0,
    roughness: float = 0.15,
    islands: int = 0,
    islets: int = 0,
    stretch: float = 1.0,
    seed: int = 0,
) -> Any:
    """A ragged lake (or, stretched, a bay or a coastal strip): ``islands`` ragged holes
    inside, ``islets`` small separate parts off its shore (a MultiPolygon then).

    >>> g = lake(islands=2, islets=3, seed=1)
    >>> g.is_valid, g.geom_type, len(g.geoms), len(g.geoms[0].interiors)
    (True, 'MultiPolygon', 4, 2)
    """
    rng = np.random.default_rng(seed)
    shore = Polygon(ragged_ring(radius, roughness, rng, stretch=stretch))
    shore = max(shapely.get_parts(shapely.make_valid(shore)), key=lambda g: g.area)
    holes: list[Polygon] = []
    tries = 0
    while len(holes) < islands and tries < 200:
        tries += 1
        r = radius * rng.uniform(0.05, 0.15)
        c = (rng.uniform(-0.6, 0.6) * radius * stretch, rng.uniform(-0.6, 0.6) * radius)
        isle = Polygon(ragged_ring(r, roughness, rng, centre=c, n=400)).buffer(0)
        inner = shore.buffer(-0.08 * radius)
        if inner.contains(isle) and all(isle.distance(h) > 0.08 * radius for h in holes):
            holes.append(isle)
    body = shore.difference(shapely.union_all(holes)) if holes else shore
    parts = [body]
    tries = 0
    while len(parts) - 1 < islets and tries < 200:
        tries += 1
        a = rng.uniform(0, 2 * np.pi)
        r = radius * rng.uniform(0.02, 0.06)
        d = radius * stretch * 1.35 + r * 3
        c = (d * np.cos(a), radius * 1.35 * np.sin(a))
        islet = Polygon(ragged_ring(r, roughness / 2, rng, centre=c, n=200)).buffer(0)
        if all(islet.distance(p) > r for p in parts):
            parts.append(islet)
    return shapely.MultiPolygon(parts) if len(parts) > 1 else body


def vertices_per_width(lines: list[LineString], geom: Any) -> tuple[float, float]:
    """Vertices per width of map lines, two ways: ``(per part, local)``.

    - per part: each polygon part's lines measured in its own mean width (the part's area
      over the length of its lines), the vertices over the sum of those counts;
    - local: each line measured in its own width (twice the mean distance from points
      along it to the polygon's boundary), the vertices over the sum of its lengths in
      those widths: how many vertices a stretch of line as long as the shape is wide
      there carries.

    One mean width over a whole multi-part polygon (its area over all lines' length)
    mixes a country's mainland with its islets: it grows as lines are dropped.

    >>> from shapely.geometry import box
    >>> line = LineString([(5, 5), (95, 5)])  # 9 widths of 10 long: 2 vertices
    >>> part, local = vertices_per_width([line], box(0, 0, 100, 10))
    >>> round(part, 3), round(local, 3)  # part: 1000 / 90 = 11.1 wide on average
    (0.247, 0.222)
    """
    parts = list(getattr(geom, "geoms", [geom]))
    tree = shapely.STRtree(parts)
    length: dict[int, float] = {}
    for ln in lines:
        mid = ln.interpolate(0.5, normalized=True)
        hit = tree.query(mid, predicate="intersects")
        i = int(hit[0]) if len(hit) else int(tree.query_nearest(mid)[0])
        length[i] = length.get(i, 0.0) + ln.length
    vertices = sum(len(ln.coords) for ln in lines)
    in_parts = sum(v**2 / parts[i].area for i, v in length.items())
    boundary = geom.boundary
    step = geom.length / 20_000  # the boundary's length in 20,000 samples, at most 200 a line
    in_local = 0.0
    for ln in lines:
        n = max(2, min(200, int(ln.length / step) + 2))
        pts = shapely.line_interpolate_point(ln, np.linspace(0, 1, n), normalized=True)
        width = 2 * float(np.mean(shapely.distance(boundary, pts)))
        in_local += ln.length / width if width > 0 else 0.0
    return (
        vertices / in_parts if in_parts else 0.0,
        vertices / in_local if in_local else 0.0,
    )
