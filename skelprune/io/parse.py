"""GeoJSON polygons to one valid shapely geometry: the validation, the repair and the union.

Accepted: a ``Polygon`` or ``MultiPolygon`` geometry, a ``Feature`` holding one, or a
``FeatureCollection`` of such features (their union is one shape). Foreign members
(``bbox``, ``name``, ``crs``, anything else: RFC 7946 §6.1) are allowed and ignored, but
for ``crs``, which names the coordinates' reference system (:func:`geojson_crs`). A
Feature whose ``geometry`` is null is skipped, with a warning (RFC 7946 allows it).

Validation, with the reason and the JSON location in the error:

- every coordinate a finite number, positions of 2 or 3 numbers (a third, the altitude,
  is ignored);
- every ring closed (first position equal to the last) with at least 4 positions;
- at most ``max_vertices`` positions in all;
- invalid geometry (a self-intersecting ring, overlapping parts of one MultiPolygon) is
  **repaired** by default: each ring with shapely's ``make_valid`` (a bow-tie becomes two
  triangles), then a polygon's holes cut out of its shell (a hole equal to its shell
  leaves nothing); ``repair=False`` refuses it instead, with shapely's reason.

The union costs about linear time in the parts: only parts whose boxes meet are merged.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import shapely
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from shapely.geometry import GeometryCollection, MultiPolygon, Polygon

from ..errors import InvalidPolygonError, shown
from .crs import CRS_NAME
from .fit import RasterWarning

__all__ = ["MAX_COORDINATE", "ParsedPolygon", "geojson_crs", "parse_geojson", "parse_polygon"]

#: Largest coordinate magnitude accepted: its square (an area) is still a finite float.
MAX_COORDINATE = 1e150
#: Feature locations named in the warning about skipped null geometries.
NAMED_SKIPPED = 5


@dataclass
class ParsedPolygon:
    """A GeoJSON polygon, parsed: the valid geometry, the CRS its ``crs`` member names
    (None: none given), and what was skipped on the way (``warnings``)."""

    geometry: MultiPolygon
    crs: str | None = None
    warnings: list[RasterWarning] = field(default_factory=list)


def geojson_crs(obj: Mapping[str, Any]) -> str | None:
    """The CRS a GeoJSON object's ``crs`` member names (the 2008 GeoJSON form that GDAL
    and geopandas write: ``{"type": "name", "properties": {"name": "EPSG:32633"}}``), or
    None. RFC 7946 dropped the member: without it, coordinates are what the caller says.

    >>> geojson_crs({"type": "Polygon", "crs": {"type": "name",
    ...              "properties": {"name": "urn:ogc:def:crs:EPSG::32633"}}})
    'urn:ogc:def:crs:EPSG::32633'
    """
    crs = obj.get("crs")
    if crs is None:
        return None
    name = crs.get("properties", {}).get("name") if isinstance(crs, Mapping) else None
    if not isinstance(name, str) or not CRS_NAME.fullmatch(name):
        raise InvalidPolygonError(
            '$.crs: expected {"type": "name", "properties": {"name": "EPSG:…"}} (an '
            f"authority code or its URN), got {shown(crs)}"
        )
    return name


def _geometries(
    obj: Any, where: str, skipped: list[str]
) -> Iterator[tuple[str, Mapping[str, Any]]]:
    if not isinstance(obj, Mapping):
        raise InvalidPolygonError(f"{where}: expected a GeoJSON object, got {type(obj).__name__}")
    kind = obj.get("type")
    if kind in ("Polygon", "MultiPolygon"):
        yield where, obj
    elif kind == "Feature":
        geometry = obj.get("geometry")
        if geometry is None:
            skipped.append(where)
            return
        yield from _geometries(geometry, f"{where}.geometry", skipped)
    elif kind == "FeatureCollection":
        features = obj.get("features")
        if not isinstance(features, list) or not features:
            raise InvalidPolygonError(f"{where}: FeatureCollection has no features")
        for i, feature in enumerate(features):
            if not isinstance(feature, Mapping) or feature.get("type") != "Feature":
                raise InvalidPolygonError(f"{where}.features[{i}]: not a Feature")
            yield from _geometries(feature, f"{where}.features[{i}]", skipped)
    else:
        raise InvalidPolygonError(
            f"{where}: type {shown(kind)} is not Polygon, MultiPolygon, Feature or "
            "FeatureCollection"
        )


def _finite(v: int | float) -> bool:
    """True for a number that converts to a finite float (a huge int overflows)."""
    try:
        return math.isfinite(v)
    except OverflowError:
        return False


def _areas(geom: Any) -> list[Polygon]:
    """The non-empty polygons of any geometry (collections flattened)."""
    return [g for g in shapely.get_parts(geom) if isinstance(g, Polygon) and not g.is_empty] + [
        p
        for g in shapely.get_parts(geom)
        if isinstance(g, MultiPolygon | GeometryCollection)
        for p in _areas(g)
    ]


def _bounds(geom: Any) -> tuple[float, float, float, float]:
    minx, miny, maxx, maxy = shapely.bounds(geom).tolist()
    return minx, miny, maxx, maxy


def _ring(ring: Any, where: str) -> np.ndarray:
    if not isinstance(ring, list | tuple):
        raise InvalidPolygonError(f"{where}: a ring must be an array of positions")
    if len(ring) < 4:
        raise InvalidPolygonError(
            f"{where}: a ring needs at least 4 positions (closed triangle), got {len(ring)}"
        )
    out = np.empty((len(ring), 2), dtype=np.float64)
    for i, pos in enumerate(ring):
        if not isinstance(pos, list | tuple) or not 2 <= len(pos) <= 3:
            raise InvalidPolygonError(f"{where}[{i}]: a position must be [x, y] or [x, y, z]")
        for v in pos:
            if isinstance(v, bool) or not isinstance(v, int | float) or not _finite(v):
                raise InvalidPolygonError(
                    f"{where}[{i}]: coordinate {shown(v)} is not a finite number"
                )
        out[i] = pos[0], pos[1]
    if not np.array_equal(out[0], out[-1]):
        raise InvalidPolygonError(
            f"{where}: ring is not closed, first position {out[0].tolist()} "
            f"differs from last {out[-1].tolist()}"
        )
    return out


def _count(coords: Any, multi: bool) -> int:
    """Positions in a (Multi)Polygon's coordinates; malformed parts count as 0 here."""
    if not isinstance(coords, list | tuple):
        return 0
    polys = coords if multi else [coords]
    return sum(
        len(r)
        for p in polys
        if isinstance(p, list | tuple)
        for r in p
        if isinstance(r, list | tuple)
    )


def _polygons(coords: Any, where: str, multi: bool) -> Iterator[tuple[str, list[np.ndarray]]]:
    if not isinstance(coords, list | tuple) or not coords:
        raise InvalidPolygonError(f"{where}: coordinates must be a non-empty array")
    if multi:
        for i, poly in enumerate(coords):
            yield from _polygons(poly, f"{where}[{i}]", False)
    else:
        yield where, [_ring(r, f"{where}[{j}]") for j, r in enumerate(coords)]


def _make_valid(geom: Any, where: str) -> Any:
    try:
        return shapely.make_valid(geom)
    except shapely.errors.GEOSException:
        # The default ("linework") repair fails on some degenerate rings (e.g. an
        # exterior collapsed to a point); the "structure" one treats rings as areas.
        try:
            return shapely.make_valid(geom, method="structure", keep_collapsed=False)
        except shapely.errors.GEOSException as exc:
            raise InvalidPolygonError(f"{where}: cannot repair the polygon: {exc}") from None


def _repaired(poly: Polygon, where: str) -> list[Polygon]:
    """The areas of an invalid polygon: its shell repaired, less its holes repaired.

    Repairing the rings together would read a hole that coincides with its shell as a
    line on the boundary, and give back the whole shell; the polygon has no area."""
    if not poly.interiors:
        return _areas(_make_valid(poly, where))
    shell = _union(_areas(_make_valid(Polygon(poly.exterior), where)))
    holes = _union([a for r in poly.interiors for a in _areas(_make_valid(Polygon(r), where))])
    return _areas(shell if holes.is_empty else shapely.difference(shell, holes))


def _union(areas: list[Polygon]) -> Any:
    try:
        return shapely.union_all(areas)
    except shapely.errors.GEOSException:
        # Nearly coincident edges can defeat the floating-point overlay; the snap-rounding
        # one on a grid far below a pixel is robust.
        extent = max((max(b[2] - b[0], b[3] - b[1]) for b in map(_bounds, areas)), default=0.0)
        try:
            return shapely.union_all(areas, grid_size=extent * 1e-9 or None)
        except shapely.errors.GEOSException as exc:
            raise InvalidPolygonError(f"cannot combine the polygons: {exc}") from None


def _union_groups(areas: list[Polygon]) -> list[Polygon]:
    """The union of valid polygons, merging only those whose boxes meet (connected
    groups of them), so that many separate parts cost about linear time. Parts come out in
    the order of each group's first polygon."""
    if len(areas) <= 1:
        return areas
    tree = shapely.STRtree(areas)
    a, b = tree.query(areas)  # box against box: cheap, and a superset of what touches
    n = len(areas)
    graph = coo_matrix((np.ones(len(a), np.int8), (a, b)), shape=(n, n))
    n_groups, group = connected_components(graph, directed=False)
    if n_groups == n:
        return areas
    members: list[list[int]] = [[] for _ in range(n_groups)]
    for i, g in enumerate(group.tolist()):
        members[g].append(i)
    out: list[Polygon] = []
    for ids in sorted(members, key=lambda m: m[0]):
        if len(ids) == 1:
            out.append(areas[ids[0]])
        else:
            out += _areas(_union([areas[i] for i in ids]))
    return out


def parse_polygon(
    obj: Mapping[str, Any], *, max_vertices: int | None = None, repair: bool = True
) -> ParsedPolygon:
    """Validate a GeoJSON polygon object: one valid shapely geometry, its ``crs`` member
    and what was skipped (:func:`parse_geojson` gives the geometry alone).

    Examples
    --------
    >>> fc = {"type": "FeatureCollection", "name": "lakes", "bbox": [0, 0, 4, 4],
    ...       "features": [{"type": "Feature", "id": 1.5, "properties": None,
    ...                     "geometry": {"type": "Polygon",
    ...                                  "coordinates": [[[0, 0], [4, 0], [4, 4], [0, 0]]]}},
    ...                    {"type": "Feature", "properties": {}, "geometry": None}]}
    >>> parsed = parse_polygon(fc)
    >>> parsed.geometry.area, [w.kind for w in parsed.warnings]
    (8.0, ['skipped'])
    """
    skipped: list[str] = []
    geometries = list(_geometries(obj, "$", skipped))
    crs = geojson_crs(obj) if isinstance(obj, Mapping) else None
    if not geometries:
        raise InvalidPolygonError("no geometry: every Feature's geometry is null")
    if max_vertices is not None:
        # Counted before any position is looked at, so a huge input is refused cheaply.
        n_vertices = sum(
            _count(g.get("coordinates"), g["type"] == "MultiPolygon") for _, g in geometries
        )
        if n_vertices > max_vertices:
            raise InvalidPolygonError(
                f"too many vertices: {n_vertices} positions, more than {max_vertices} allowed"
            )
    areas: list[Polygon] = []
    for where, geometry in geometries:
        multi = geometry["type"] == "MultiPolygon"
        parts: list[Polygon] = []
        for pwhere, rings in _polygons(geometry.get("coordinates"), f"{where}.coordinates", multi):
            if max(float(np.abs(r).max()) for r in rings) > MAX_COORDINATE:
                # Beyond it GEOS overflows on areas, and lengths in the answer would not
                # be finite (JSON cannot write them).
                raise InvalidPolygonError(
                    "coordinates span too large a range to rasterise: every coordinate must "
                    f"lie within ±{MAX_COORDINATE:.0e}"
                )
            poly = Polygon(rings[0], rings[1:])
            if poly.is_valid:
                parts.append(poly)
            elif repair:
                parts += _repaired(poly, pwhere)
            else:
                reason = shapely.is_valid_reason(poly)
                raise InvalidPolygonError(f"{pwhere}: invalid polygon: {reason}")
        if multi and not repair and len(parts) > 1:
            # each part valid, but together? (overlapping parts, or parts sharing an edge)
            whole = MultiPolygon(parts)
            if not whole.is_valid:
                reason = shapely.is_valid_reason(whole)
                raise InvalidPolygonError(
                    f"{where}: invalid MultiPolygon (its parts overlap or share an edge): {reason}"
                )
        areas += parts
    polys = _union_groups(areas)
    result = MultiPolygon(polys) if polys else MultiPolygon()
    if result.is_empty or result.area <= 0:
        raise InvalidPolygonError("polygon has zero area")
    warnings = []
    if skipped:
        named = ", ".join(skipped[:NAMED_SKIPPED]) + (", …" if len(skipped) > NAMED_SKIPPED else "")
        warnings.append(
            RasterWarning(
                "skipped", f"{len(skipped)} Feature(s) with a null geometry skipped: {named}"
            )
        )
    return ParsedPolygon(result, crs, warnings)


def parse_geojson(
    obj: Mapping[str, Any], *, max_vertices: int | None = None, repair: bool = True
) -> MultiPolygon:
    """Validate a GeoJSON polygon object and return it as one valid shapely geometry.

    Parameters
    ----------
    obj : Mapping
        ``Polygon``, ``MultiPolygon``, ``Feature`` or ``FeatureCollection``.
    max_vertices : int, optional
        Refuse inputs with more positions than this, all rings together.
    repair : bool
        Repair invalid geometry (self-intersections, overlapping parts) with
        ``shapely.make_valid``; if False, refuse it.

    Returns
    -------
    shapely.geometry.MultiPolygon
        The union of all polygons, valid, with non-zero area.

    Raises
    ------
    InvalidPolygonError
        With the reason and the JSON location of the offending part.

    Examples
    --------
    >>> square = {"type": "Polygon",
    ...           "coordinates": [[[0, 0], [10, 0], [10, 10], [0, 10], [0, 0]]]}
    >>> parse_geojson(square).area
    100.0
    """
    return parse_polygon(obj, max_vertices=max_vertices, repair=repair).geometry
