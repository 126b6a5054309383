"""The skeleton as GeoJSON for maps, a view of the components' branch tables
(:meth:`skelprune.output.document.PruneResult.to_geojson`)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import shapely

from ..io.frame import PixelFrame
from .lines import boundary_index, cut_end_forks, map_lines, mask_distance, recentre
from .table import frame_distances, frame_points

if TYPE_CHECKING:
    from ..io.crs import LocalProjection
    from ..io.polygon import PolygonRaster
    from .schema import ComponentSummaryDoc, SkeletonGeoJSON
    from .table import BranchTable

__all__ = ["raster_polygon", "skeleton_geojson"]


def raster_polygon(raster: PolygonRaster) -> Any:
    """The input polygon in its raster's pixel coordinates."""
    f = raster.frame
    sign = -1.0 if f.flip_y else 1.0
    return shapely.transform(
        raster.geometry,
        lambda xy: np.stack(
            [(xy[:, 0] - f.x0) / f.pixel_size, sign * (xy[:, 1] - f.y0) / f.pixel_size], axis=1
        ),
    )


def skeleton_geojson(
    tables: list[BranchTable],
    summaries: list[ComponentSummaryDoc],
    mask: np.ndarray,
    header: dict[str, Any],
    frame: PixelFrame,
    simplify: float = 0.5,
    cut_ends: bool = False,
    raster: PolygonRaster | None = None,
    crs: str | None = None,
) -> SkeletonGeoJSON:
    """Branches as LineStrings and nodes as Points, in ``frame``'s coordinates (the
    parameters and properties as :meth:`~skelprune.output.document.PruneResult.to_geojson`
    describes them): one table and one summary per component, the mask they came from,
    the collection's ``properties`` but its ``components``, a polygon's raster, and the
    CRS of the frame's coordinates where one is known (a GeoTIFF's; a polygon's raster
    has its own)."""
    polygon = None if raster is None or simplify <= 0 else raster_polygon(raster)
    projection = None if raster is None else raster.projection
    index = None if polygon is None else boundary_index(polygon)
    distance = mask_distance(mask)
    features: list[Any] = []
    for ci, (t, summary) in enumerate(zip(tables, summaries, strict=True)):
        # on every feature too: GIS tools show a feature's properties, not the collection's
        numbers = {"rer": summary["rer"], "ss": summary["ss"]}
        lines: list[Any] = t.lines()
        ends_at: dict[tuple[int, str], int] = {}
        moved: dict[int, tuple[float, float]] = {}
        if cut_ends:
            lines, ends_at, moved = cut_end_forks(t, lines, mask, distance)
        kept = [i for i, ln in enumerate(lines) if ln is not None]
        exact = [lines[i] for i in kept]
        # the exact polygon gives sub-pixel medial positions
        chosen = exact if index is None else recentre(exact, index)
        simple = map_lines(chosen, simplify, mask, polygon, exact)
        source, target = t.source.tolist(), t.target.tolist()
        length = frame_distances(frame, t.length).tolist()
        margin, removed = t.margins(), t.removal_steps()
        used: set[int] = set()
        for i, line in zip(kept, simple, strict=True):
            fx, fy = _placed(frame, projection, line[:, 0], line[:, 1])
            src = ends_at.get((i, "source"), source[i])
            dst = ends_at.get((i, "target"), target[i])
            used.update((src, dst))
            features.append(
                {
                    "type": "Feature",
                    "geometry": {
                        "type": "LineString",
                        "coordinates": np.column_stack([fx, fy]).tolist(),
                    },
                    "properties": {
                        "component": ci,
                        "kind": "branch",
                        "id": i,
                        "source": src,
                        "target": dst,
                        "length": length[i],
                        "radii": frame_distances(frame, line[:, 2]).tolist(),
                        "margin": margin[i],
                        "removed_at": removed[i],
                        **numbers,
                    },
                }
            )
        node_x = t.x[t.node_point].tolist()
        node_y = t.y[t.node_point].tolist()
        node_r = frame_distances(frame, t.radius[t.node_point]).tolist()
        for nid, kind in enumerate(t.kinds()):
            if cut_ends and nid not in used:
                continue  # a fork's junction and second tip, gone with the fork
            x, y = moved.get(nid, (node_x[nid], node_y[nid]))
            features.append(
                {
                    "type": "Feature",
                    "geometry": {"type": "Point", "coordinates": _point(frame, projection, x, y)},
                    "properties": {
                        "component": ci,
                        "kind": kind,
                        "id": nid,
                        "radius": 0.0 if nid in moved else node_r[nid],
                        **numbers,
                    },
                }
            )
    # A foreign member of the collection (RFC 7946 §6.1): the document's numbers.
    properties: Any = {**header, "components": summaries}
    if raster is not None:
        properties["warnings"] = [w.to_dict() for w in raster.warnings]
    out: Any = {"type": "FeatureCollection", "properties": properties, "features": features}
    crs = raster.crs if raster is not None and raster.crs is not None else crs
    if crs is not None:
        properties["crs"] = crs
        out["crs"] = {"type": "name", "properties": {"name": crs}}
    return out


def _placed(
    frame: PixelFrame, projection: LocalProjection | None, x: np.ndarray, y: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Pixel positions in the input's coordinates: the frame's, and back from the local
    projection for geographic input (rounded to a thousandth of a pixel, as the frame)."""
    fx, fy = frame_points(frame, x, y)
    if projection is None:
        return fx, fy
    lon, lat = projection.back(fx, fy)
    decimals = projection.decimals(frame.pixel_size)
    return np.round(lon, decimals), np.round(lat, decimals)


def _point(
    frame: PixelFrame, projection: LocalProjection | None, x: float, y: float
) -> list[float]:
    if projection is None:
        return list(frame.point(x, y))
    fx, fy = _placed(frame, projection, np.array([x], float), np.array([y], float))
    return [float(fx[0]), float(fy[0])]
