"""Centre lines of GIS data: GeoDataFrames, files of features, GeoTIFF masks.

:func:`centerlines` prunes **each feature on its own** (a table is never one raster),
in worker processes if asked, and returns a GeoDataFrame: one row per map line
(:mod:`skelprune.geo.carto`: short corner branches dropped, chains joined, simplified
by the local width), a Point where a polygon part is too small for a line, and a row
with the reason where a feature fails; the input row's index and attributes on every
row, the input's CRS. Geographic coordinates are pruned in a local equidistant
projection (:mod:`skelprune.io.crs`), so lengths and widths are in metres.

Needs the ``geo`` extra (geopandas, pyogrio, pyproj; rasterio for GeoTIFF masks).

From the command line: ``skelprune centerlines IN OUT [--jobs N] [--main-path]`` (the
formats by the file name's ending: ``.gpkg``, ``.shp``, ``.geojson``/``.json``,
``.parquet``/``.geoparquet``).
"""

from __future__ import annotations

import dataclasses
import logging
import os
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np
import shapely
from shapely.geometry import LineString, MultiPolygon, Point, Polygon

from ..errors import SkelpruneError
from ..io.crs import PLANAR, crs_name
from ..output.document import PruneResult
from ..output.finite import finite
from .answer import geojson_frame, geojson_lines, lines_geojson
from .carto import END_FACTOR, SHARE, cartographic_lines

__all__ = [
    "centerlines",
    "feature_lines",
    "geojson_frame",
    "geojson_lines",
    "lines_geojson",
    "read_frame",
    "write_frame",
]

log = logging.getLogger("skelprune.geo")

#: Columns every answer row has (besides the input's attributes and ``geometry``).
COLUMNS = ("feature", "part", "kind", "length", "width", "error")
#: File endings and the pyogrio driver (or parquet) that writes them.
DRIVERS = {
    ".gpkg": "GPKG",
    ".shp": "ESRI Shapefile",
    ".geojson": "GeoJSON",
    ".json": "GeoJSON",
    ".parquet": "parquet",
    ".geoparquet": "parquet",
}


def _polygonal(geom: Any) -> MultiPolygon | None:
    if geom is None or geom.is_empty:
        return None
    parts = [g for g in shapely.get_parts(geom) if isinstance(g, Polygon) and not g.is_empty]
    return MultiPolygon(parts) if parts else None


def feature_lines(
    geom: Any,
    crs: str | None = None,
    *,
    share: float = SHARE,
    end_factor: float = END_FACTOR,
    main_path: bool = False,
    **options: Any,
) -> tuple[list[dict[str, Any]], list[str]]:
    """The map lines of one polygon: rows ``{"geometry", "part", "kind", "length",
    "width"}`` in the polygon's CRS (lengths and widths in metres for a geographic CRS),
    and the warnings.

    Every part gets a row: its lines, or, for a part too small for a line (none, or
    lines shorter than the diameter of its largest inscribed circle: a blob), that
    circle's centre as a Point, with a warning.

    Examples
    --------
    >>> from shapely.geometry import box
    >>> lake = MultiPolygon([box(0, 0, 3000, 800), box(5000, 0, 5010, 10)])
    >>> rows, warnings = feature_lines(lake, pixel_size=20.0)
    >>> [(r["kind"], r["part"]) for r in rows], [r["geometry"].wkt for r in rows][1:]
    ([('line', 0), ('point', 1)], ['POINT (5005 5)'])
    """
    import skelprune

    from ..io.crs import local_projection
    from ..io.fit import RasterWarning
    from ..io.polygon import _guessed

    polygon = _polygonal(geom)
    if polygon is None:
        raise SkelpruneError("the feature has no polygon (null, empty, or not polygonal)")
    guessed: list[RasterWarning] = []
    if crs is None:  # as skelprune.prune reads a polygon without a CRS
        crs = _guessed(polygon, guessed)
    projection = None if crs in (None, PLANAR) else local_projection(polygon, crs)
    ground = polygon if projection is None else projection.forward(polygon)
    # the ground is planar (metres, or the projected CRS's units): never guessed again
    if options.get("raster") is not None:
        options = {**options, "raster": dataclasses.replace(options["raster"], crs=PLANAR)}
    else:
        options = {**options, "crs": PLANAR}
    res = skelprune.prune(ground, **options)
    assert isinstance(res, PruneResult)  # a polygon, never a volume
    warnings = [w.message for w in guessed]
    warnings += [w["message"] for w in res.to_dict().get("warnings", [])]
    lines = cartographic_lines(
        res.to_geojson(), ground, share=share, end_factor=end_factor, main_path=main_path
    )
    pixel = res.input.frame.pixel_size
    lines = [ln for ln in lines if ln.length >= pixel]  # a pixel's dot is no line
    parts = list(ground.geoms)
    tree = shapely.STRtree(parts)
    by_part: dict[int, list[Any]] = {}
    for ln in lines:
        geom_line = LineString(ln.xy)
        mid = geom_line.interpolate(0.5, normalized=True)
        hit = tree.query(mid, predicate="intersects")
        part = int(hit[0]) if len(hit) else int(tree.query_nearest(mid)[0])
        by_part.setdefault(part, []).append((geom_line, ln))
    rows = []
    for i, part in enumerate(parts):
        centre, radius = _centre(part)
        found = by_part.get(i, [])
        # a part whose lines are shorter than its inscribed circle is a blob: a point
        if found and sum(ln.length for _, ln in found) >= 2 * radius:
            rows += [{"geometry": g, "part": i, "kind": "line", **_numbers(ln)} for g, ln in found]
            continue
        rows.append(
            {
                "geometry": centre,
                "part": i,
                "kind": "point",
                "length": 0.0,
                "width": finite(2 * radius),
            }
        )
        if len(parts) > 1 or not found:
            warnings.append(
                f"part #{i} is too small for a line at pixel size {pixel:.4g}: its centre, a Point"
            )
    if projection is not None:
        for row in rows:
            row["geometry"] = shapely.transform(
                row["geometry"], lambda xy: np.column_stack(projection.back(*xy.T))
            )
    return rows, warnings


def _numbers(ln: Any) -> dict[str, float | None]:
    # the one rule of every answer: a number that is not finite is null
    return {"length": finite(ln.length), "width": finite(ln.width)}


def _centre(part: Polygon) -> tuple[Point, float]:
    """The centre of a part's largest inscribed circle, and its radius."""
    tolerance = max(part.length / 1000, 1e-9)
    segment = shapely.maximum_inscribed_circle(part, tolerance)
    centre = Point(shapely.get_coordinates(segment)[0])
    return centre, float(segment.length)


def _one(args: tuple[Any, bytes | None, str | None, dict[str, Any]]) -> tuple[Any, Any, Any]:
    """One feature in a worker: (index, rows, warnings) or (index, None, error)."""
    index, wkb, crs, options = args
    try:
        geom = None if wkb is None else shapely.from_wkb(wkb)
        rows, warnings = feature_lines(geom, crs, **options)
        for row in rows:
            row["geometry"] = shapely.to_wkb(row["geometry"])
        return index, rows, warnings
    except SkelpruneError as exc:
        return index, None, str(exc)


def centerlines(
    source: Any,
    *,
    jobs: int = 1,
    progress: bool = False,
    main_path: bool = False,
    crs: str | None = None,
    share: float = SHARE,
    end_factor: float = END_FACTOR,
    on_feature: Callable[[Any, str | None], None] | None = None,
    **options: Any,
) -> Any:
    """Map centre lines of every polygon feature: a GeoDataFrame.

    Parameters
    ----------
    source : GeoDataFrame, GeoSeries or path
        The features; a path is read with :func:`read_frame` (GeoPackage, Shapefile,
        GeoJSON, GeoParquet, anything GDAL reads).
    jobs : int
        Worker processes (1: in this process).
    progress : bool
        A progress bar on stderr.
    main_path : bool
        One line per connected network: its longest path (for label placement).
    crs : str, optional
        The features' CRS (an authority code, or ``"planar"``), where the frame has none
        or says wrong; default: the frame's CRS, and for a frame without one what
        :func:`skelprune.prune` does (longitude/latitude if every coordinate lies within
        its bounds and a feature is at most a degree across, with a warning in the log;
        planar otherwise).
    share, end_factor : float
        How far a simplified line may move (a share of its local half-width) and how
        long an end branch must be to stay (in junction radii): :mod:`.carto`.
    on_feature : callable, optional
        Called as ``on_feature(index, error)`` after each feature (error None: done).
    **options
        Pruning and raster options of :func:`skelprune.prune` (``pixel_size`` in the
        ground's units: metres for geographic data).

    Returns
    -------
    geopandas.GeoDataFrame
        One row per line or point: ``feature`` (the input row's index), ``part`` (the
        part of its polygon), ``kind`` (``line`` or ``point``), ``length`` and ``width``
        (mean, along the line; a point's: its inscribed circle's diameter), ``error``
        (null, or why the feature has no row of lines: a row with no geometry), then the
        input's attributes; the input's CRS.

    Examples
    --------
    >>> import geopandas as gpd
    >>> from shapely.geometry import box
    >>> lakes = gpd.GeoDataFrame({"name": ["long", "none"]},
    ...                          geometry=[box(0, 0, 3000, 800), None], crs="EPSG:32633")
    >>> out = centerlines(lakes)
    >>> out["feature"].tolist(), out["kind"].tolist(), out["name"].tolist()
    ([0, 1], ['line', None], ['long', 'none'])
    >>> out["error"][1]
    'the feature has no polygon (null, empty, or not polygonal)'
    >>> round(out["length"][0])  # metres
    3000
    """
    import geopandas as gpd

    frame = read_frame(source) if isinstance(source, str | os.PathLike) else source
    if isinstance(frame, gpd.GeoSeries):
        frame = gpd.GeoDataFrame(geometry=frame)
    if crs is not None:
        from ..options import RasterOptions

        RasterOptions(crs=crs)  # checked once, here, not in every worker
    else:
        crs = crs_name(frame.crs)
    settings = {"share": share, "end_factor": end_factor, "main_path": main_path, **options}
    tasks = [
        (index, None if g is None else shapely.to_wkb(g), crs, settings)
        for index, g in zip(frame.index, frame.geometry, strict=True)
    ]
    results = _run(tasks, jobs, progress, on_feature)
    attributes = frame.drop(columns=frame.geometry.name)
    records: list[dict[str, Any]] = []
    geoms: list[Any] = []
    for index, rows, outcome in results:
        extra = attributes.loc[index].to_dict() if len(attributes.columns) else {}
        if rows is None:
            log.warning("feature %s: %s", index, outcome)
            records.append({"feature": index, "part": None, "kind": None, "length": None,
                            "width": None, "error": outcome, **extra})  # fmt: skip
            geoms.append(None)
            continue
        for message in outcome:
            log.info("feature %s: %s", index, message)
        for row in rows:
            geoms.append(shapely.from_wkb(row.pop("geometry")))
            records.append({"feature": index, **row, "error": None, **extra})
    columns = [*COLUMNS, *[c for c in attributes.columns if c not in COLUMNS]]
    import pandas as pd

    table = pd.DataFrame.from_records(records, columns=columns).astype(
        {"kind": object, "error": object}
    )
    table = table.where(table.notna(), None) if len(table) else table
    out_crs = frame.crs if frame.crs is not None or crs == PLANAR else crs
    return gpd.GeoDataFrame(table, geometry=gpd.GeoSeries(geoms, crs=out_crs), crs=out_crs)


def _run(
    tasks: list[Any],
    jobs: int,
    progress: bool,
    on_feature: Callable[[Any, str | None], None] | None,
) -> list[Any]:
    from tqdm import tqdm

    bar = tqdm(total=len(tasks), disable=not progress, unit="feature", file=None)
    out = []

    def done(result: Any) -> None:
        out.append(result)
        bar.update(1)
        if on_feature is not None:
            on_feature(result[0], None if result[1] is not None else result[2])

    try:
        if jobs <= 1 or len(tasks) <= 1:
            for task in tasks:
                done(_one(task))
        else:
            with ProcessPoolExecutor(max_workers=jobs) as pool:
                for result in pool.map(_one, tasks, chunksize=max(1, len(tasks) // (jobs * 8))):
                    done(result)
    finally:
        bar.close()
    return out


def read_frame(path: str | os.PathLike[str], layer: str | None = None) -> Any:
    """A file of features as a GeoDataFrame (pyogrio: GeoPackage, Shapefile, GeoJSON,
    …; GeoParquet by its ending)."""
    import geopandas as gpd

    path = Path(path)
    if path.suffix.lower() in (".parquet", ".geoparquet"):
        return gpd.read_parquet(path)
    return gpd.read_file(path, layer=layer, engine="pyogrio")


def write_frame(frame: Any, path: str | os.PathLike[str]) -> None:
    """Write a GeoDataFrame in the format its file name's ending names (:data:`DRIVERS`)."""
    path = Path(path)
    driver = DRIVERS.get(path.suffix.lower())
    if driver is None:
        raise SkelpruneError(
            f"{path.name}: unknown ending; write one of {', '.join(sorted(DRIVERS))}"
        )
    if driver == "parquet":
        frame.to_parquet(path)
    elif driver == "GeoJSON":  # the bytes the service answers with lines=map
        path.write_bytes(lines_geojson(frame, path.stem))
    else:
        if path.exists():
            path.unlink()
        frame.to_file(path, driver=driver, engine="pyogrio")
