"""Map lines on real-like polygons: skelprune's map lines beside its skeleton GeoJSON,
pygeoops.centerline and centerline.

``python -m benchmarks maps`` (the ``bench`` extra installs the reference tools, the
``geo`` extra rasterio). Polygons: ragged lakes (one alone, one with islands, one with
islets off its shore), a coastal strip, a generated river, three Natural Earth countries
(real coastlines: ``data/gis``), and staircase polygons as a segmentation gives them (a
lake, a river and a T burnt into a pixel mask and traced back with
``rasterio.features.shapes``). No real polygon can be downloaded here; the generators
are ``testkit.rivers``. Per polygon and tool: pieces per part (connected networks, 1 is
right), the share of line length inside, lines (between junctions and ends), ends,
vertices per width three ways (whole: the polygon's area over the lines' length as the
mean width; part: each part's own; local: each line's own width along it:
``testkit.rivers.vertices_per_width``), wall time.

``python -m benchmarks.bench_maps FOLDER`` draws the pictures of ``docs/gis.md``.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import shapely
from shapely import affinity
from shapely.geometry import LineString, MultiPolygon, box, shape

from benchmarks.bench_gis import GIS, _centerline, _network, _pygeoops, _skelprune
from benchmarks.common import table
from skelprune.geo import feature_lines
from skelprune.io.polygon import parse_geojson
from testkit.rivers import lake, river


def _maps(geom: MultiPolygon) -> list[LineString]:
    rows, _ = feature_lines(geom)
    return [r["geometry"] for r in rows if r["kind"] == "line"]


def _maps_main(geom: MultiPolygon) -> list[LineString]:
    rows, _ = feature_lines(geom, main_path=True)
    return [r["geometry"] for r in rows if r["kind"] == "line"]


TOOLS: dict[str, Callable[[MultiPolygon], list[LineString]]] = {
    "skelprune map lines": _maps,
    "skelprune main_path": _maps_main,
    "skelprune skeleton": _skelprune,
    "pygeoops": _pygeoops,
    "centerline": _centerline,
}


def traced(geom: Any, px: float) -> MultiPolygon:
    """A polygon burnt into a mask of ``px`` pixels and traced back: a staircase outline,
    as a segmentation model's polygons are."""
    from rasterio import features
    from rasterio.transform import from_origin

    minx, miny, maxx, maxy = geom.bounds
    transform = from_origin(minx - 2 * px, maxy + 2 * px, px, px)
    width, height = int((maxx - minx) / px) + 4, int((maxy - miny) / px) + 4
    mask = features.rasterize([geom], out_shape=(height, width), transform=transform)
    mask = mask.astype(np.uint8)
    polys = [shape(g) for g, v in features.shapes(mask, mask=mask > 0, transform=transform)]
    return MultiPolygon([p for p in polys if p.area > 0])


def _multi(geom: Any) -> MultiPolygon:
    return geom if isinstance(geom, MultiPolygon) else MultiPolygon([geom])


def polygons() -> list[tuple[str, MultiPolygon]]:
    tee = shapely.union_all([box(0, 0, 400, 40), box(180, -300, 220, 0)])
    tee = affinity.rotate(tee, 30, origin=(200, 0))
    reach = river(5_000, 40, 120, seed=4).polygon
    out = [
        ("ragged lake", lake(seed=1, stretch=1.6, roughness=0.2)),
        ("lake with 3 islands", lake(seed=2, islands=3, stretch=1.5, roughness=0.2)),
        ("lake with 4 islets", lake(seed=4, islets=4, stretch=1.5, roughness=0.2)),
        ("coastal strip", lake(seed=3, stretch=4, roughness=0.2)),
        ("river 10 km, 30-90 m", river(10_000, 30, 90, seed=3).polygon),
        ("staircase lake (20 m px)", traced(lake(seed=2, islands=3, stretch=1.5), 20.0)),
        ("staircase river (10 m px)", traced(reach, 10.0)),
        ("staircase T (10 m px)", traced(tee, 10.0)),
    ]
    for name in ("croatia", "gambia", "italy"):
        out.append((name, parse_geojson(json.loads((GIS / f"{name}.geojson").read_text()))))
    return [(name, _multi(g)) for name, g in out]


def many_parts() -> None:
    """Parse, fit and rasterise MultiPolygons of many unit squares (the raster and its
    topology check included): about linear in the parts."""
    from skelprune.io.polygon import read_polygon

    rows = []
    for n in (5_000, 20_000, 80_000):
        side = int(n**0.5) + 1
        squares = [
            [
                [
                    [2 * i, 2 * j],
                    [2 * i + 1, 2 * j],
                    [2 * i + 1, 2 * j + 1],
                    [2 * i, 2 * j + 1],
                    [2 * i, 2 * j],
                ]
            ]
            for i, j in (divmod(k, side) for k in range(n))
        ]
        obj = {"type": "MultiPolygon", "coordinates": squares}
        t = time.perf_counter()
        raster = read_polygon(obj)
        secs = time.perf_counter() - t
        rows.append([n, f"{len(json.dumps(obj)) / 1e6:.1f}", raster.mask.size, f"{secs:.1f}"])
        print(" | ".join(str(c) for c in rows[-1]), flush=True)
    print(table(["squares", "MB of GeoJSON", "raster pixels", "s"], rows))


def lonlat() -> None:
    """The 10 km, 30–90 m river in metres and the same river on the Earth at 0°, 45°,
    60° and 70° N, given in longitude/latitude: pruned on the ground (``crs`` given, and
    without one: guessed), and in degrees taken as planar (``crs="planar"``). Distances
    over the local width: between each answer's lines and those in metres, and of each
    from the true centre line (median, 95 %, worst point)."""
    import pyproj
    from shapely.geometry import MultiLineString

    import skelprune
    from testkit.rivers import on_earth

    reach = river(10_000, 30, 90, seed=3)

    def lines(geo: dict[str, Any]) -> MultiLineString:
        return MultiLineString(
            [
                f["geometry"]["coordinates"]
                for f in geo["features"]
                if f["properties"]["kind"] == "branch"
            ]
        )

    def apart(a: Any, b: Any) -> np.ndarray:
        pts = shapely.points(shapely.get_coordinates(shapely.segmentize(a, 5.0)))
        return shapely.distance(b, pts) / (2 * shapely.distance(reach.polygon.exterior, pts))

    def q(d: np.ndarray) -> str:
        return (
            f"{100 * np.median(d):.2f} / {100 * np.quantile(d, 0.95):.1f} / {100 * d.max():.0f} %"
        )

    metres = lines(skelprune.prune(reach.polygon).to_geojson())
    true = MultiLineString([reach.centre])
    rows = [["metres", "-", "-", q(apart(metres, true))]]
    for lat in (0.0, 45.0, 60.0, 70.0):
        local = pyproj.CRS.from_proj4(f"+proj=aeqd +lat_0={lat} +lon_0=10 +datum=WGS84 +units=m")
        to = pyproj.Transformer.from_crs("EPSG:4326", local, always_xy=True)
        g = on_earth(reach.polygon, 10.0, lat)
        for how, kw in (
            ("on the ground (crs)", {"crs": "EPSG:4326"}),
            ("no crs: guessed", {}),
            ("degrees as planar", {"crs": "planar"}),
        ):
            geo = skelprune.prune(g, **kw).to_geojson()
            ground = shapely.transform(
                lines(geo), lambda xy, to=to: np.column_stack(to.transform(*xy.T))
            )
            d = np.concatenate([apart(ground, metres), apart(metres, ground)])
            rows.append([f"{lat:.0f}° N", how, q(d), q(apart(ground, true))])
            print(" | ".join(rows[-1]), flush=True)
    header = ["river", "pruned", "from the line in metres", "from the true centre line"]
    print(table(header, rows))


def main(parts: bool = True) -> None:
    lonlat()
    if parts:
        many_parts()
    rows = []
    for name, geom in polygons():
        for tool, fn in TOOLS.items():
            try:
                t = time.perf_counter()
                lines = fn(geom)
                secs = time.perf_counter() - t
            except ImportError:
                rows.append([name, tool, "-", "-", "-", "-", "-", "-", "-", "not installed"])
                continue
            except Exception as exc:  # a reference tool failing on a polygon
                rows.append([name, tool, "-", "-", "-", "-", "-", "-", "-", type(exc).__name__])
                continue
            m = _network(lines, geom)
            rows.append(
                [
                    name,
                    tool,
                    f"{m['pieces']:.2f}",
                    f"{100 * m['inside']:.1f} %",
                    len(lines),
                    m["ends"],
                    f"{m['vpw']:.1f}",
                    f"{m['vpw_part']:.1f}",
                    f"{m['vpw_local']:.1f}",
                    f"{secs:.2f}",
                ]
            )
            print(" | ".join(str(c) for c in rows[-1]), flush=True)
    header = ["polygon", "tool", "pieces/part", "inside", "lines", "ends"]
    header += ["vert/width whole", "part", "local", "s"]
    print()
    print(table(header, rows))


def figures(out: Path) -> list[Path]:
    """Each tool's lines over four of the polygons (docs/figures/gis-maps-*.png)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out.mkdir(parents=True, exist_ok=True)
    chosen = dict(polygons())
    shown = {
        "lakes": ["lake with 3 islands", "staircase lake (20 m px)"],
        "shapes": ["staircase T (10 m px)", "coastal strip"],
    }
    tools = ["skelprune map lines", "skelprune skeleton", "pygeoops"]
    written = []
    for figure, names in shown.items():
        fig, axes = plt.subplots(len(names), len(tools), figsize=(4.2 * len(tools), 4 * len(names)))
        for row, name in enumerate(names):
            geom = chosen[name]
            for col, tool in enumerate(tools):
                ax = axes[row, col]
                for part in geom.geoms:
                    ax.fill(*part.exterior.xy, color="#cfe3f5", lw=0)
                    for hole in part.interiors:
                        ax.fill(*hole.xy, color="white", lw=0)
                lines = TOOLS[tool](geom)
                for ln in lines:
                    ax.plot(*ln.xy, color="#c0392b", lw=1)
                    ax.plot(*ln.xy, ".", color="#c0392b", ms=3)
                if tool == "skelprune map lines":
                    rows, _ = feature_lines(geom)
                    for r in rows:
                        if r["kind"] == "point":
                            ax.plot(*r["geometry"].xy, "o", color="#c0392b", ms=4)
                ax.set_aspect("equal", adjustable="datalim")
                ax.set_xticks([])
                ax.set_yticks([])
                vertices = sum(len(ln.coords) for ln in lines)
                ax.set_title(f"{name}\n{tool}: {len(lines)} lines, {vertices} vertices", fontsize=9)
        fig.tight_layout()
        path = out / f"gis-maps-{figure}.png"
        fig.savefig(path, dpi=100)
        plt.close(fig)
        written.append(path)
    return written


if __name__ == "__main__":
    import sys

    for p in figures(Path(sys.argv[1] if len(sys.argv) > 1 else "docs/figures")):
        print(p)
