"""A GeoParquet of polygons to a GeoParquet of their skeleton lines, partition by
partition on dask-geopandas: :func:`prune_geoparquet`.

Each partition is a GeoDataFrame; each of its rows is pruned on its own (never the table
as one raster) under the budget of :func:`~skelprune.parallel.prune_many`, and gives one
row a skeleton branch, with the input row's attributes. Needs ``dask-geopandas`` (and
so ``pyarrow``) besides the ``parallel`` extra.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import SkelpruneError
from ..limits import DATASET_LIMITS, Limits
from ..options import (
    OutputOptions,
    PruneOptions,
    RasterOptions,
    resolve_options,
)
from .items import Feature, Item
from .work import Job, feature_lines, run_item

if TYPE_CHECKING:
    from distributed import Client

__all__ = ["LINE_COLUMNS", "branch_lines", "map_lines", "prune_geoparquet"]

#: The columns each output row adds to its input row's attributes (``problem`` and
#: ``detail``: the problem kind and its detail, on the one row of a feature that failed,
#: whose geometry is empty).
LINE_COLUMNS = {
    "source_row": "int64",
    "component": "Int64",
    "branch": "Int64",
    "length": "float64",
    "margin": "float64",
    "problem": "string",
    "detail": "string",
}


def branch_lines(part: Any, job: Job) -> Any:
    """One partition's skeleton branches: a GeoDataFrame of one row a branch (a
    LineString), the input row's attributes and :data:`LINE_COLUMNS`, in the partition's
    CRS. A feature that fails gives one row with no geometry and its problem."""
    import geopandas
    import pandas as pd
    from shapely.geometry import shape

    attributes = part.drop(columns=part.geometry.name)
    rows: list[dict[str, Any]] = []
    geometries: list[Any] = []
    sources: list[Any] = []
    for position, (index, geom) in enumerate(zip(part.index, part.geometry, strict=True)):
        lines, problem = run_item(Item("", Feature(position, index, geom)), job, feature_lines)
        if problem is not None:
            rows.append({"problem": problem[0], "detail": problem[1]})
            geometries.append(None)
            sources.append(index)
            continue
        assert lines is not None
        for feature in lines["features"]:
            if feature["geometry"]["type"] != "LineString":
                continue  # the nodes: their places are the lines' ends
            props = feature["properties"]
            rows.append(
                {
                    "component": props["component"],
                    "branch": props["id"],
                    "length": props["length"],
                    "margin": props["margin"],
                }
            )
            geometries.append(shape(feature["geometry"]))
            sources.append(index)
    lines = pd.DataFrame(rows, columns=list(LINE_COLUMNS)[1:]).astype(
        {k: v for k, v in LINE_COLUMNS.items() if k != "source_row"}
    )
    lines.insert(0, "source_row", pd.array(sources, dtype="int64") if sources else [])
    table = attributes.loc[sources].reset_index(drop=True)
    out = pd.concat([table, lines.reset_index(drop=True)], axis=1)
    out["source_row"] = out["source_row"].astype("int64")
    return geopandas.GeoDataFrame(out, geometry=geometries, crs=part.crs)


def map_lines(part: Any, job: Job) -> Any:
    """One partition's map lines (:func:`skelprune.geo.centerlines`: corner branches
    dropped, chains joined, simplified by the local width, a Point for a part too small
    for a line): one row a line or point with ``feature`` (the input row's index),
    ``part``, ``kind``, ``length``, ``width`` and ``error``, then the input row's
    attributes, in the partition's CRS. A geographic CRS is pruned on the ground (lengths
    and widths in metres). A feature that fails gives one row with no geometry and its
    reason in ``error``. Each feature is rasterised within the raster options' pixel
    budget; the memory estimate of :func:`branch_lines` does not apply."""
    from ..geo import centerlines

    options: dict[str, Any] = {"options": job.options, "output": job.output}
    if job.raster is not None:
        options["raster"] = job.raster
    out = centerlines(part, **options)
    # the same column types in every partition (and the empty meta), so the parts
    # share one schema: a partition without a failure has no string in `error`, and
    # the attributes come back from records as objects
    types = {"feature": part.index.dtype, "part": "Int64", "kind": "string"}
    types |= {"length": "float64", "width": "float64", "error": "string"}
    types |= {c: part[c].dtype for c in part.columns if c != part.geometry.name and c in out}
    return out.astype(types)


#: What a partition becomes, by name: :func:`branch_lines` or :func:`map_lines`.
#: The per-partition functions ``prune_geoparquet(lines=...)`` names.
LINES: dict[str, Callable[[Any, Job], Any]] = {"branches": branch_lines, "map": map_lines}


def prune_geoparquet(
    source: str | os.PathLike[str],
    destination: str | os.PathLike[str],
    options: PruneOptions | None = None,
    *,
    raster: RasterOptions | None = None,
    output: OutputOptions | None = None,
    client: Client | str | None = None,
    jobs: int | None = None,
    limits: Limits | None = None,
    npartitions: int | None = None,
    lines: str | Callable[[Any, Job], Any] = "branches",
    **keywords: Any,
) -> Path:
    """Prune every polygon of a GeoParquet and write their skeleton lines as GeoParquet.

    Parameters
    ----------
    source : path
        A GeoParquet file or folder of parts (what ``dask_geopandas.read_parquet``
        reads); its index labels the rows (``source_row`` in the output).
    destination : path
        The folder of GeoParquet parts to write (one a partition): one row a branch, with
        the input row's attributes, ``source_row``, ``component``, ``branch``,
        ``length`` and ``margin`` (the GeoJSON lines' numbers), in the input's CRS; a row
        that failed gives one row with no geometry, its ``problem`` (the service's
        problem kind) and ``detail``.
    options, raster, output, **keywords
        As for :func:`skelprune.prune` (``pixel_size``, ``simplify``, ...).
    client, jobs, limits
        As for :func:`~skelprune.parallel.prune_many`.
    npartitions : int, optional
        Split the table into this many partitions at least (default: some four a worker).
    lines : {"branches", "map"} or callable
        What a partition becomes: ``"branches"`` (:func:`branch_lines`, the skeleton's
        branches, the default), ``"map"`` (:func:`map_lines`, the map lines of
        :func:`skelprune.geo.centerlines`), or ``lines(partition, job) -> GeoDataFrame``,
        another per-feature function.

    Returns
    -------
    Path
        The destination folder.
    """
    import dask_geopandas

    from .run import _client, _workers

    options, read, raster, output = resolve_options(options, None, raster, output, keywords)
    if read is not None:
        raise SkelpruneError("a GeoParquet holds polygons: read options do not apply")
    job = Job(options, None, raster, output, limits=limits or DATASET_LIMITS)
    fn: Callable[[Any, Job], Any]
    if isinstance(lines, str):
        if lines not in LINES:
            raise SkelpruneError(f"lines: {lines!r} is not one of {', '.join(LINES)}")
        fn = LINES[lines]
    else:
        fn = lines
    with _client(client, jobs, job.limits) as c:
        table = dask_geopandas.read_parquet(source)
        wanted = npartitions or 4 * _workers(c)
        if table.npartitions < wanted:
            table = table.repartition(npartitions=wanted)
        meta = fn(table._meta, job)
        result = table.map_partitions(fn, job, meta=meta)
        c.compute(result.to_parquet(destination, write_index=False, compute=False)).result()
    return Path(destination)
