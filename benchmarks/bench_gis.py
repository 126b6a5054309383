"""Centre lines for GIS users: skelprune against pygeoops.centerline and centerline.

``python -m benchmarks gis`` prunes real polygons (Natural Earth countries in
``data/gis``, see its README) and generated rivers with a known centre line
(``testkit.rivers``, a 50 km one 20–200 m wide among them) at default options, and the
same with ``pygeoops.centerline`` and ``centerline.geometry.Centerline`` (the ``bench``
extra; a tool missing or over its time cap is shown as such). Per tool and polygon:

- pieces/part: connected line networks per polygon part (1 is right);
- inside: share of the line length inside the polygon;
- cover: share of the true centre line within a quarter of the local width of the lines
  (rivers only); off: median distance of the lines from the true centre line over the
  local width (rivers) — for real polygons, the median distance of the lines' vertices
  from the polygon's medial axis is not known, so it is left out;
- ends: line ends (degree-1 nodes); vert/width: vertices per mean width of line length;
- s, MB: wall time and peak memory (tracemalloc: Python and numpy allocations).

First, where the answer stops changing: the rivers at 1.5 to 8 pixels across their
narrowest width (``pixels_per_width``), median time of three runs (prune and GeoJSON).

``SKELPRUNE_BENCH_QUICK=1``: the generated rivers only. A reference tool that takes more
than ``SKELPRUNE_BENCH_GIS_CAP`` seconds (default 60) on a polygon is skipped for the rest.
"""

from __future__ import annotations

import json
import os
import time
import tracemalloc
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import shapely
from shapely.geometry import LineString, MultiLineString, MultiPolygon

import skelprune
from benchmarks.common import table
from skelprune.io.polygon import parse_geojson
from testkit import DATA
from testkit.rivers import River, river, vertices_per_width

GIS = DATA / "gis"
#: Seconds a reference tool may take on one polygon before it is skipped for the rest.
CAP = float(os.environ.get("SKELPRUNE_BENCH_GIS_CAP", "60"))


def _skelprune(geom: MultiPolygon) -> list[LineString]:
    geo = skelprune.prune(geom).to_geojson()
    return [
        LineString(f["geometry"]["coordinates"])
        for f in geo["features"]
        if f["geometry"]["type"] == "LineString" and len(f["geometry"]["coordinates"]) >= 2
    ]


def _skelprune_cut(geom: MultiPolygon) -> list[LineString]:
    geo = skelprune.prune(geom).to_geojson(cut_ends=True)
    return [
        LineString(f["geometry"]["coordinates"])
        for f in geo["features"]
        if f["geometry"]["type"] == "LineString" and len(f["geometry"]["coordinates"]) >= 2
    ]


def _pygeoops(geom: MultiPolygon) -> list[LineString]:
    import pygeoops

    out = pygeoops.centerline(geom)
    return [g for g in shapely.get_parts(out) if isinstance(g, LineString) and not g.is_empty]


def _centerline(geom: MultiPolygon) -> list[LineString]:
    from centerline.geometry import Centerline

    lines = []
    for part in geom.geoms:
        step = max(2 * part.area / part.length / 4, part.length / 20_000)
        c = Centerline(part, interpolation_distance=step)
        lines += [g for g in shapely.get_parts(c.geometry) if isinstance(g, LineString)]
    return lines


TOOLS: dict[str, Callable[[MultiPolygon], list[LineString]]] = {
    "skelprune": _skelprune,
    "skelprune cut_ends": _skelprune_cut,
    "pygeoops": _pygeoops,
    "centerline": _centerline,
}


def _measure(fn: Callable[[], Any]) -> tuple[Any, float, float]:
    """The answer, its wall time, and (in a second run, as tracemalloc slows numpy's
    allocations down) its peak memory."""
    t = time.perf_counter()
    out = fn()
    elapsed = time.perf_counter() - t
    tracemalloc.start()
    try:
        fn()
        peak = tracemalloc.get_traced_memory()[1] / 2**20
    finally:
        tracemalloc.stop()
    return out, elapsed, peak


def _network(lines: list[LineString], geom: MultiPolygon) -> dict[str, float]:
    """Pieces per part, share inside, ends, vertices per mean width."""
    if not lines:
        return dict.fromkeys(("pieces", "inside", "ends", "vpw", "vpw_part", "vpw_local"), 0)
    # noded: lines that cross or touch share an end here
    segments = shapely.get_parts(shapely.union_all(lines))
    parent: dict[tuple[float, float], tuple[float, float]] = {}

    def find(k: tuple[float, float]) -> tuple[float, float]:
        while parent.setdefault(k, k) != k:
            parent[k] = parent[parent[k]]
            k = parent[k]
        return k

    degree: dict[tuple[float, float], int] = {}
    for seg in segments:
        cs = seg.coords
        a, b = ((round(p[0], 3), round(p[1], 3)) for p in (cs[0], cs[-1]))
        parent[find(a)] = find(b)
        for k in (a, b):
            degree[k] = degree.get(k, 0) + 1
    pieces = len({find(k) for k in degree})
    grown = geom.buffer(1e-6 * max(1.0, geom.length / 1e6))
    total = sum(ln.length for ln in lines)
    inside = shapely.intersection(MultiLineString(lines), grown).length / total if total else 0
    mean_width = geom.area / total if total else 0.0
    vertices = sum(len(ln.coords) for ln in lines)
    per_part, local = vertices_per_width(lines, geom)
    return {
        "pieces": pieces / len(geom.geoms),
        "inside": inside,
        "ends": sum(1 for d in degree.values() if d == 1),
        "vpw": vertices / (total / mean_width) if mean_width else 0.0,
        "vpw_part": per_part,
        "vpw_local": local,
    }


def _centred(lines: list[LineString], r: River) -> tuple[float, float]:
    """Share of the true centre line within a quarter width of the lines; median offset
    of the lines (sampled evenly along them) from the true centre line over the local
    width."""
    if not lines:
        return 0.0, float("nan")
    ml = MultiLineString(lines)
    s = np.linspace(0, r.centre.length, 2000)
    true_pts = shapely.line_interpolate_point(r.centre, s)
    # local width at the true centre line: twice the distance to the banks
    local = 2 * shapely.distance(true_pts, r.polygon.exterior)
    near = shapely.distance(true_pts, ml) <= local / 4
    # along the lines, evenly: a simplified line's straight stretches count, not only
    # its vertices
    pts = shapely.line_interpolate_point(ml, np.linspace(0, 1, 4000), normalized=True)
    offset = shapely.distance(pts, r.centre)
    width_there = 2 * shapely.distance(pts, r.polygon.exterior) + offset * 2
    return float(near.mean()), float(np.median(offset / np.maximum(width_there, 1e-9)))


def _polygons(quick: bool) -> list[tuple[str, MultiPolygon, River | None]]:
    out: list[tuple[str, MultiPolygon, River | None]] = []
    rivers = [("river 50 km, 20-200 m", river(50_000, 20, 200, seed=0))]
    rivers += [
        ("river 10 km, 50 m", river(10_000, 50, 50, seed=1)),
        ("river 10 km, 30-90 m", river(10_000, 30, 90, wavelength=1_500, amplitude=150, seed=2)),
    ]
    out += [(name, MultiPolygon([r.polygon]), r) for name, r in rivers]
    if not quick:
        for path in sorted(GIS.glob("*.geojson")):
            geom = parse_geojson(json.loads(path.read_text()))
            out.append((path.stem, geom, None))
    return out


def sweep() -> None:
    """Where the answer stops changing: the rivers at 2 to 8 pixels per narrowest width."""
    rows = []
    rivers = [
        ("river 50 km, 20-200 m", river(50_000, 20, 200, seed=0)),
        ("river 10 km, 50 m", river(10_000, 50, 50, seed=1)),
        ("river 10 km, 30-90 m", river(10_000, 30, 90, wavelength=1_500, amplitude=150, seed=2)),
    ]
    for name, r in rivers:
        geom = MultiPolygon([r.polygon])
        for k in (1.5, 2, 3, 4, 6, 8):
            times = []
            for _ in range(3):
                t = time.perf_counter()
                res = skelprune.prune(geom, pixels_per_width=k)
                geo = res.to_geojson()
                times.append(time.perf_counter() - t)
            lines = [
                LineString(f["geometry"]["coordinates"])
                for f in geo["features"]
                if f["geometry"]["type"] == "LineString"
            ]
            m = _network(lines, geom)
            cover, off = _centred(lines, r)
            rows.append(
                [
                    name,
                    k,
                    f"{res.frame.pixel_size:.2f}",
                    res.mask.size,
                    len(res.warnings),
                    f"{m['pieces']:.0f}",
                    m["ends"],
                    f"{100 * cover:.0f} %",
                    f"{off:.3f}",
                    f"{m['vpw']:.1f}",
                    f"{float(np.median(times)):.2f}",
                ]
            )
            print(" | ".join(str(c) for c in rows[-1]), flush=True)
    header = ["river", "px/width", "pixel m", "pixels", "warnings", "pieces", "ends"]
    print()
    print(table([*header, "cover", "off", "vert/width", "s (median of 3)"], rows))


def forks() -> None:
    """How often a reach cut straight across ends in a fork, and what ``cut_ends`` does:
    twenty generated 5 km reaches (widths 20–200 m, meanders of 1–3 km), at default
    options."""
    rows = []
    total = {"doc": 0, "cut": 0, "reaches": 0}
    for seed in range(20):
        rng = np.random.default_rng(100 + seed)
        lo = float(rng.uniform(20, 80))
        hi = float(rng.uniform(lo, 200))
        wave = float(rng.uniform(1_000, 3_000))
        r = river(5_000, lo, hi, wavelength=wave, amplitude=wave / 10, seed=seed)
        res = skelprune.prune(r.polygon)
        ends = res.n_endpoints()
        geo = res.to_geojson(cut_ends=True)
        cut = sum(1 for f in geo["features"] if f["properties"]["kind"] == "endpoint")
        total["doc"] += ends
        total["cut"] += cut
        total["reaches"] += 1
        rows.append([seed, f"{lo:.0f}-{hi:.0f}", ends, cut, len(res.components)])
    print(table(["seed", "width m", "ends (document)", "ends (cut_ends)", "components"], rows))
    n = 2 * total["reaches"]
    print(
        f"\nreach ends: {n}; extra ends in the document {total['doc'] - n} "
        f"({100 * (total['doc'] - n) / n:.0f} % of ends fork), with cut_ends {total['cut'] - n}"
    )


TARGET = """
import resource, time, skelprune
from testkit.rivers import river
r = river(50_000, 20, 200, seed=0)
skelprune.prune(r.polygon)  # the kernels loaded
times = []
for _ in range(5):
    t = time.perf_counter()
    res = skelprune.prune(r.polygon)
    geo = res.to_geojson()
    times.append(time.perf_counter() - t)
lines = [f for f in geo["features"] if f["geometry"]["type"] == "LineString"]
rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(sorted(times)[2], len(res.components), len(lines), res.n_endpoints(), rss)
"""


def target() -> None:
    """The 50 km river at default options in a fresh process: prune and GeoJSON, median
    of five, and the process's peak resident memory (imports included)."""
    import subprocess
    import sys

    from testkit import REPO

    run = subprocess.run(
        [sys.executable, "-c", TARGET], capture_output=True, text=True, cwd=REPO, check=True
    )
    secs, comps, lines, ends, rss = run.stdout.split()
    ok = float(secs) <= 1 and float(rss) <= 500 and comps == "1" and lines == "1"
    print(
        f"50 km river, default options: {comps} component, {lines} line, {ends} ends, "
        f"{float(secs):.2f} s (median of 5), peak RSS {float(rss):.0f} MB; target "
        f"(one connected line, <= 1 s, <= 500 MB) {'met' if ok else 'MISSED'}"
    )


def main() -> None:
    quick = os.environ.get("SKELPRUNE_BENCH_QUICK") == "1"
    target()
    skelprune.prune(np.pad(np.ones((20, 40), bool), 5))  # kernels loaded before timing
    sweep()
    forks()
    rows = []
    skipped: set[str] = set()
    for name, geom, r in _polygons(quick):
        for tool, fn in TOOLS.items():
            if tool in skipped:
                rows.append([name, tool, "-", "-", "-", "-", "-", "-", "-", "skipped"])
                continue
            try:
                lines, secs, peak = _measure(lambda fn=fn, geom=geom: fn(geom))
            except ImportError:
                skipped.add(tool)
                rows.append([name, tool, "-", "-", "-", "-", "-", "-", "-", "not installed"])
                continue
            except Exception as exc:  # a reference tool failing on a polygon
                rows.append([name, tool, "-", "-", "-", "-", "-", "-", "-", type(exc).__name__])
                continue
            m = _network(lines, geom)
            cover, off = _centred(lines, r) if r is not None else (float("nan"), float("nan"))
            rows.append(
                [
                    name,
                    tool,
                    f"{m['pieces']:.2f}",
                    f"{100 * m['inside']:.1f} %",
                    "-" if r is None else f"{100 * cover:.0f} %",
                    "-" if r is None else f"{off:.3f}",
                    m["ends"],
                    f"{m['vpw']:.1f}",
                    f"{secs:.2f}",
                    f"{peak:.0f}",
                ]
            )
            if tool not in ("skelprune", "skelprune cut_ends") and secs > CAP:
                skipped.add(tool)  # too slow to run on every polygon
            print(" | ".join(str(c) for c in rows[-1]), flush=True)
    header = [
        "polygon",
        "tool",
        "pieces/part",
        "inside",
        "cover",
        "off",
        "ends",
        "vert/width",
        "s",
        "MB",
    ]
    print()
    print(table(header, rows))


def _ylim(geom: MultiPolygon, window: tuple[float, float]) -> tuple[float, float]:
    """The y range of a polygon inside an x window, with a margin."""
    _, miny, _, maxy = geom.bounds
    clip = shapely.clip_by_rect(geom, window[0], miny - 1, window[1], maxy + 1)
    lo, hi = clip.bounds[1], clip.bounds[3]
    pad = 0.1 * (hi - lo)
    return lo - pad, hi + pad


def figures(out: Path) -> list[Path]:
    """The pictures of docs/gis.md: a stretch of the 50 km river and two countries, each
    tool's lines over the polygon (``python -m benchmarks.bench_gis FOLDER``)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out.mkdir(parents=True, exist_ok=True)
    r = river(50_000, 20, 200, seed=0)
    cases = [
        ("river", MultiPolygon([r.polygon]), (20_000, 26_000)),
        ("gambia", parse_geojson(json.loads((GIS / "gambia.geojson").read_text())), None),
        ("croatia", parse_geojson(json.loads((GIS / "croatia.geojson").read_text())), None),
    ]
    written = []
    for name, geom, window in cases:
        tools = {"skelprune": _skelprune(geom), "pygeoops": _pygeoops(geom)}
        if name == "river":  # where the narrow river trips pygeoops: its longest stretch outside
            outside = shapely.difference(MultiLineString(tools["pygeoops"]), geom)
            pieces = shapely.get_parts(outside)
            if len(pieces):
                x = max(pieces, key=lambda g: g.length).centroid.x
                window = (x - 1_500, x + 1_500)
        height = 2.2 if name == "river" else 3.2
        fig, axes = plt.subplots(len(tools), 1, figsize=(10, height * len(tools)), squeeze=False)
        for ax, (tool, lines) in zip(axes[:, 0], tools.items(), strict=True):
            for part in geom.geoms:
                ax.fill(*part.exterior.xy, color="#cfe3f5", lw=0)
                for hole in part.interiors:
                    ax.fill(*hole.xy, color="white", lw=0)
            if name == "river":
                ax.plot(*r.centre.xy, color="#555", lw=1.2, ls="--", label="true centre line")
            for ln in lines:
                ax.plot(*ln.xy, color="#c0392b", lw=1)
                ax.plot(*ln.xy, ".", color="#c0392b", ms=2)
            if window is not None:
                ax.set_xlim(*window)
                ax.set_ylim(*_ylim(geom, window))
                ax.set_aspect("equal", adjustable="box")
            else:
                ax.set_aspect("equal", adjustable="datalim")
            ax.set_title(f"{name}: {tool} ({sum(len(ln.coords) for ln in lines)} vertices)")
            ax.set_xticks([])
            ax.set_yticks([])
        fig.tight_layout()
        path = out / f"gis-{name}.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        written.append(path)
    return written


if __name__ == "__main__":
    import sys

    for p in figures(Path(sys.argv[1] if len(sys.argv) > 1 else "docs/figures")):
        print(p)
