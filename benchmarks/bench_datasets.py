"""Whole data sets on Dask: :func:`skelprune.parallel.prune_many` against a plain loop.

Two data sets:

- 2,000 masks: kimia216's PNG files, each written ten times under its own name (the
  shapes of a segmentation's output: a few hundred pixels across), pruned into one
  ``NAME.json`` each;
- 10,000 small polygons (GeoDataFrame rows: noisy ellipses 40–120 m long, rasterised at
  ``longest_side=64``), into one table of JSON lines.

Each is run three ways, the rounds interleaved so that a slow spell of the shared machine
hits every row alike:

- the plain library loop a user writes (read, prune, serialise, write: one process);
- ``prune_many`` on a local cluster of 1 worker process, and of 2; each cluster is
  started and warmed once (its start is reported apart), and every round writes into a
  fresh folder.

Reported: inputs per second (median of the rounds), the 1-worker run's overhead against
the loop, the 2-worker speed-up against 1 worker, and each worker's peak resident memory.
The machine's bound: 2 cores, shared with the client process (which receives and writes
every result) and with whatever else runs.

A third, the table at scale: a GeoParquet of :data:`TABLE_ROWS` polygons (the same noisy
ellipses, with attributes) through dask-geopandas partitions on a local cluster of 2
workers, into a GeoParquet of map lines (``prune_geoparquet(..., lines="map")``): rows
per second, partitions, output rows, and that every input row is in the output with its
attributes.

``python -m benchmarks datasets`` (about half an hour on 2 cores, most of it the
100,000-row table); ``python -m benchmarks.bench_datasets --rows 2000 --only table`` runs
the table alone at a smaller size (``SKELPRUNE_BENCH_ROWS`` sets the size for the first
form).
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from testkit import DATA

from .common import table

ROUNDS = 3
MASKS = 2000
POLYGONS = 10_000
RASTER = {"longest_side": 64}
#: Rows of the GeoParquet table: the issue's 100,000 unless the environment says.
TABLE_ROWS = int(os.environ.get("SKELPRUNE_BENCH_ROWS", "100000"))


def write_masks(folder: Path) -> list[Path]:
    sources = sorted((DATA / "kimia216").glob("*.png"))
    folder.mkdir()
    paths = []
    for i in range(MASKS):
        path = folder / f"m{i:05d}-{sources[i % len(sources)].name}"
        shutil.copyfile(sources[i % len(sources)], path)
        paths.append(path)
    return paths


def polygons(n: int = POLYGONS):
    """A GeoDataFrame of ``n`` small noisy ellipses, fixed seed."""
    import geopandas
    from shapely.geometry import Polygon

    rng = np.random.default_rng(0)
    t = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    shapes = []
    for _ in range(n):
        a, b = rng.uniform(20, 60), rng.uniform(8, 25)
        r = 1 + 0.15 * rng.standard_normal(t.size)
        x0, y0 = rng.uniform(0, 1e5, 2)
        shapes.append(Polygon(np.c_[x0 + a * r * np.cos(t), y0 + b * r * np.sin(t)]))
    return geopandas.GeoDataFrame({"id": np.arange(n)}, geometry=shapes)


def loop_masks(paths: list[Path], out: Path) -> None:
    """The plain loop: what prune_many does for each file, in one process."""
    import skelprune
    from skelprune.parallel import document_bytes

    out.mkdir()
    for path in paths:
        (out / f"{path.stem}.json").write_bytes(document_bytes(skelprune.prune(path).to_dict()))


def loop_polygons(frame, out: Path) -> None:
    import skelprune
    from skelprune.parallel import document_bytes

    out.mkdir()
    with open(out / "table.jsonl", "wb") as f:
        for row, (index, geom) in enumerate(zip(frame.index, frame.geometry, strict=True)):
            res = skelprune.prune(geom, **RASTER)
            line = {"row": row, "index": int(index), "result": res.to_geojson()}
            f.write(document_bytes(line))


def _warm(path: str, polygon) -> None:
    """Load the library and its kernels in a worker, as the runs will use them."""
    import skelprune

    skelprune.prune(path).to_dict()
    skelprune.prune(polygon, **RASTER).to_geojson()


def _peak_rss() -> int:
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def table_run(rows: int, workers: int = 2) -> None:
    """The GeoParquet table at scale: write it, prune it partition by partition, check
    and print the figures."""
    import geopandas

    from skelprune.parallel.geoparquet import prune_geoparquet

    work = Path(tempfile.mkdtemp(prefix="bench-table-"))
    try:
        frame = polygons(rows)
        frame["name"] = [f"lake {i}" for i in range(rows)]
        frame["area"] = frame.geometry.area
        frame = frame.set_crs("EPSG:32633")
        source = work / "lakes.parquet"
        frame.to_parquet(source)
        t = time.perf_counter()
        out = prune_geoparquet(source, work / "lines", jobs=workers, lines="map", **RASTER)
        seconds = time.perf_counter() - t
        lines = geopandas.read_parquet(out)
        parts = len(list(out.glob("*.parquet")))
        failed = int(lines["error"].notna().sum())
        missing = set(range(rows)) - set(lines["feature"])
        joined = lines.merge(frame[["id", "name"]], left_on="feature", right_index=True)
        attributes_kept = bool((joined["name_x"] == joined["name_y"]).all())
        size = source.stat().st_size
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print(
        table(
            [
                "rows",
                "workers",
                "partitions",
                "seconds",
                "rows/s",
                "output rows",
                "lines",
                "points",
                "failed",
                "rows missing",
                "attributes kept",
            ],
            [
                [
                    f"{rows:,}",
                    workers,
                    parts,
                    f"{seconds:.0f}",
                    f"{rows / seconds:.0f}",
                    f"{len(lines):,}",
                    int((lines["kind"] == "line").sum()),
                    int((lines["kind"] == "point").sum()),
                    failed,
                    len(missing),
                    "yes" if attributes_kept else "NO",
                ]
            ],
        )
    )
    print(f"input GeoParquet {size / 2**20:.1f} MiB; cluster start included in the seconds")


def main(rows: int = TABLE_ROWS, only: str | None = None) -> None:
    if only in (None, "table"):
        table_run(rows)
        print()
    if only == "table":
        return
    from distributed import Client, LocalCluster

    from skelprune.parallel import prune_many

    work = Path(tempfile.mkdtemp(prefix="bench-datasets-"))
    try:
        paths = write_masks(work / "masks")
        frame = polygons()
        clusters, started = {}, {}
        for n in (1, 2):
            t = time.perf_counter()
            cluster = LocalCluster(
                n_workers=n,
                threads_per_worker=1,
                processes=True,
                dashboard_address=":0",
                silence_logs=logging.ERROR,
            )
            client = Client(cluster)
            client.run(_warm, str(paths[0]), frame.geometry.iloc[0])  # every worker
            started[n] = time.perf_counter() - t
            clusters[n] = (cluster, client)
        runs = {
            ("masks", "loop"): lambda out: loop_masks(paths, out),
            ("polygons", "loop"): lambda out: loop_polygons(frame, out),
        }
        for n, (_, client) in clusters.items():
            runs["masks", f"prune_many, {n} worker"] = lambda out, c=client: prune_many(
                paths, client=c, out=out
            )
            runs["polygons", f"prune_many, {n} worker"] = lambda out, c=client: prune_many(
                {"table": frame}, client=c, out=out, **RASTER
            )
        seconds: dict[tuple[str, str], list[float]] = {k: [] for k in runs}
        for r in range(ROUNDS):
            for key, run in runs.items():
                out = work / f"out-{r}-{key[0]}-{key[1].replace(' ', '_').replace(',', '')}"
                t = time.perf_counter()
                run(out)
                seconds[key].append(time.perf_counter() - t)
                shutil.rmtree(out)
        memory = {n: client.run(_peak_rss) for n, (_, client) in clusters.items()}
        for cluster, client in clusters.values():
            client.close()
            cluster.close()
    finally:
        shutil.rmtree(work, ignore_errors=True)
    rows = []
    summary = {}
    for (data, how), values in seconds.items():
        count = MASKS if data == "masks" else POLYGONS
        med = statistics.median(values)
        summary[data, how] = med
        rows.append([data, how, f"{med:.1f}", f"{count / med:.0f}", _spread(values)])
    print(table(["data set", "run", "seconds, median", "inputs/s", f"range of {ROUNDS}"], rows))
    print()
    ratios = []
    for data in ("masks", "polygons"):
        loop = summary[data, "loop"]
        one, two = summary[data, "prune_many, 1 worker"], summary[data, "prune_many, 2 worker"]
        ratios.append(
            [data, f"{100 * (one / loop - 1):+.1f} %", f"{one / two:.2f}x", f"{loop / two:.2f}x"]
        )
    print(
        table(
            ["data set", "1 worker vs loop (overhead)", "2 workers vs 1", "2 workers vs loop"],
            ratios,
        )
    )
    print()
    for n, per_worker in memory.items():
        peaks = ", ".join(f"{v / 2**20:.0f} MiB" for v in per_worker.values())
        print(f"{n} worker(s): cluster start and warm-up {started[n]:.1f} s; peak RSS {peaks}")
    print(f"cores: {len(os.sched_getaffinity(0))} usable, {os.cpu_count()} in the machine")
    print(json.dumps({f"{d}/{h}": round(v, 2) for (d, h), v in summary.items()}))


def _spread(values: list[float]) -> str:
    return f"{min(values):.1f}–{max(values):.1f}"


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rows", type=int, default=TABLE_ROWS, help="rows of the table")
    parser.add_argument(
        "--only",
        choices=["table", "compare"],
        help="the table alone, or the comparison with the loop alone",
    )
    args = parser.parse_args(sys.argv[1:])
    main(args.rows, args.only)
