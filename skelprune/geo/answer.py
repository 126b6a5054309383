"""Map lines as GeoJSON text: what ``skelprune centerlines IN OUT.geojson`` writes, and
what the service answers with ``lines=map`` (docs/gis.md).

Both go through :func:`lines_geojson`, so the same polygon and options give the same
bytes: GDAL's GeoJSON (through pyogrio), one feature a line. A GeoJSON object posted as
it is (:func:`geojson_frame`) becomes the table ``skelprune centerlines`` reads from a
file of the same features: one row per Feature, its properties as columns, the CRS of
its ``crs`` member.
"""

from __future__ import annotations

import io
from collections.abc import Mapping
from typing import Any

import shapely.geometry

from ..errors import InvalidPolygonError
from ..io.parse import geojson_crs

__all__ = ["LAYER", "geojson_frame", "geojson_lines", "lines_geojson"]

#: The collection's ``name`` where no file names it (``skelprune centerlines`` writes
#: its OUT file's name without the ending, as GDAL does).
LAYER = "centerlines"


def geojson_frame(obj: Mapping[str, Any]) -> Any:
    """A GeoJSON object as a GeoDataFrame of its features.

    A ``Polygon`` or ``MultiPolygon`` is one row without attributes, a ``Feature`` one
    row, a ``FeatureCollection`` a row per Feature (a null geometry stays, as a row
    without geometry); the Features' properties are the columns. The CRS is the one its
    ``crs`` member names, else none (then :func:`~skelprune.geo.centerlines` decides as
    :func:`skelprune.prune` does).

    Examples
    --------
    >>> fc = {"type": "FeatureCollection", "features": [{"type": "Feature",
    ...       "properties": {"name": "pond"}, "geometry": {"type": "Polygon",
    ...       "coordinates": [[[0, 0], [40, 0], [40, 20], [0, 0]]]}}],
    ...       "crs": {"type": "name", "properties": {"name": "EPSG:32633"}}}
    >>> frame = geojson_frame(fc)
    >>> frame["name"].tolist(), frame.crs.to_epsg(), frame.geometry[0].area
    (['pond'], 32633, 400.0)
    """
    import geopandas as gpd

    kind = obj.get("type")
    if kind == "FeatureCollection":
        features = list(obj.get("features") or [])
    elif kind == "Feature":
        features = [obj]
    elif kind in ("Polygon", "MultiPolygon"):
        features = [{"type": "Feature", "properties": {}, "geometry": obj}]
    else:
        raise InvalidPolygonError(
            f"$: type {kind!r} is not Polygon, MultiPolygon, Feature or FeatureCollection"
        )
    rows = [dict(f.get("properties") or {}) for f in features]
    geoms = [
        None if f.get("geometry") is None else shapely.geometry.shape(f["geometry"])
        for f in features
    ]
    columns = list(dict.fromkeys(k for row in rows for k in row))
    return gpd.GeoDataFrame(
        {c: [row.get(c) for row in rows] for c in columns},
        geometry=gpd.GeoSeries(geoms),
        crs=geojson_crs(obj),
    )


def lines_geojson(lines: Any, name: str = LAYER) -> bytes:
    """A GeoDataFrame of map lines (:func:`~skelprune.geo.centerlines`) as GeoJSON
    bytes, as GDAL writes a ``.geojson`` file named ``name`` (its ``name`` member)."""
    buf = io.BytesIO()
    lines.to_file(buf, driver="GeoJSON", engine="pyogrio", layer=name)
    return buf.getvalue()


def geojson_lines(
    obj: Mapping[str, Any],
    *,
    main_path: bool = False,
    crs: str | None = None,
    name: str = LAYER,
    **options: Any,
) -> bytes:
    """The map lines of a GeoJSON object's polygons as GeoJSON bytes: each Feature pruned
    on its own by :func:`~skelprune.geo.centerlines` (``main_path``, ``crs`` and the
    pruning and raster ``options`` as it takes them), written by :func:`lines_geojson`;
    the features ``skelprune centerlines`` writes for a file of the same features.

    Examples
    --------
    >>> import json
    >>> reach = {"type": "Polygon", "coordinates": [[[0, 0], [3000, 0], [3000, 800],
    ...          [0, 800], [0, 0]]], "crs": {"type": "name",
    ...          "properties": {"name": "EPSG:32633"}}}
    >>> doc = json.loads(geojson_lines(reach))
    >>> [f["geometry"]["type"] for f in doc["features"]], round(doc["features"][0]
    ...     ["properties"]["length"])
    (['LineString'], 3000)
    """
    from . import centerlines

    return lines_geojson(
        centerlines(geojson_frame(obj), main_path=main_path, crs=crs, **options), name
    )
