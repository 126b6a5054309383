"""GIS data as it comes: GeoDataFrames and files of features, GeoTIFF masks, staircase
outlines traced from pixels, lines a cartographer would draw."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import shapely
from shapely import affinity
from shapely.geometry import MultiPolygon, Point, box, shape

import skelprune

gpd = pytest.importorskip("geopandas", reason="the geo extra")  # make test installs it
rasterio = pytest.importorskip("rasterio", reason="the geo extra")
from rasterio import features  # noqa: E402
from rasterio.transform import from_origin  # noqa: E402

from skelprune.geo import centerlines, feature_lines  # noqa: E402
from testkit.rivers import lake, on_earth, river  # noqa: E402

CLI = [sys.executable, "-m", "skelprune.cli"]


def traced(geom: object, px: float) -> object:
    """A polygon burnt into a mask of ``px`` pixels and traced back (staircase outline),
    as a segmentation's polygons are made."""
    minx, miny, maxx, maxy = geom.bounds  # type: ignore[attr-defined]
    transform = from_origin(minx - 2 * px, maxy + 2 * px, px, px)
    width, height = int((maxx - minx) / px) + 4, int((maxy - miny) / px) + 4
    mask = features.rasterize([geom], out_shape=(height, width), transform=transform)
    mask = mask.astype(np.uint8)
    (poly,) = [
        shape(g) for g, v in features.shapes(mask, mask=mask > 0, transform=transform) if v == 1
    ]
    return poly


def test_staircase_t_gives_the_three_lines_a_person_draws() -> None:
    # a T of 40 m strokes, turned 30°: a person draws three lines (the bar's two arms
    # and the stem), whatever the pixel steps of its outline
    tee = shapely.union_all([box(0, 0, 400, 40), box(180, -300, 220, 0)])
    tee = affinity.rotate(tee, 30, origin=(200, 0))
    for px in (10.0, 5.0):
        stairs = traced(tee, px)
        raw = skelprune.prune(stairs).to_geojson()
        branches = [f for f in raw["features"] if f["properties"]["kind"] == "branch"]
        assert len(branches) > 3  # the pruning's answer keeps corners' branches
        rows, _ = feature_lines(stairs)
        assert [r["kind"] for r in rows] == ["line"] * 3
        lines = [r["geometry"] for r in rows]
        assert all(stairs.covers(ln) for ln in lines)
        # few vertices: at most 4 a mean width of line
        vertices = sum(len(ln.coords) for ln in lines)
        assert vertices <= 4 * sum(ln.length for ln in lines) / 40
        # the lines meet: one network
        assert shapely.union_all(lines).geom_type in ("MultiLineString", "LineString")
        ends = [Point(c) for ln in lines for c in (ln.coords[0], ln.coords[-1])]
        assert sum(any(e.distance(f) < 1e-6 for f in ends if f is not e) for e in ends) >= 3
        # main_path: one line, the longest path (arm to arm, or arm to the stem's end)
        (main,), _ = feature_lines(stairs, main_path=True)
        assert main["geometry"].length > 350


@pytest.mark.parametrize(
    ("kind", "shape_kw"),
    [
        ("lake with islands", {"seed": 2, "islands": 3, "stretch": 1.5, "roughness": 0.2}),
        ("lake with islets", {"seed": 4, "islets": 4, "stretch": 1.5, "roughness": 0.2}),
        ("coastal strip", {"seed": 3, "stretch": 4, "roughness": 0.2}),
    ],
)
def test_ragged_outlines_give_few_vertices_per_width(kind: str, shape_kw: dict) -> None:
    geom = lake(**shape_kw)
    rows, _ = feature_lines(geom)
    lines = [r for r in rows if r["kind"] == "line"]
    assert lines, kind
    length = sum(r["geometry"].length for r in lines)
    width = sum(r["width"] * r["geometry"].length for r in lines) / length
    vertices = sum(len(r["geometry"].coords) for r in lines)
    assert vertices / (length / width) <= 4, kind
    assert all(geom.covers(r["geometry"]) for r in lines), kind
    # every part has its row: the islets their points
    parts = len(getattr(geom, "geoms", [geom]))
    assert sorted({r["part"] for r in rows}) == list(range(parts))


def test_each_feature_on_its_own_with_ids_and_attributes() -> None:
    # two lakes that overlap: two features, each its own line, never merged
    lakes = gpd.GeoDataFrame(
        {"name": ["west", "east"]},
        geometry=[box(0, 0, 3000, 600), box(2500, 0, 5500, 600)],
        index=["w7", "e9"],
        crs="EPSG:32633",
    )
    out = centerlines(lakes)
    assert out.crs == lakes.crs
    assert out["feature"].tolist() == ["w7", "e9"]
    assert out["name"].tolist() == ["west", "east"]
    assert out["length"].round().tolist() == [3000, 3000]
    assert out["width"].between(500, 700).all()


def test_lonlat_frame_comes_back_in_lonlat_with_lengths_in_metres() -> None:
    reach = river(5_000, 20, 60, seed=1)
    frame = gpd.GeoDataFrame(geometry=[on_earth(reach.polygon, 10.0, 60.0)], crs="EPSG:4326")
    out = centerlines(frame, jobs=2)
    assert out.crs == frame.crs
    (line,) = out.geometry
    lon, lat = np.asarray(line.coords).T
    assert np.all((lon > 9.9) & (lon < 10.1) & (lat > 59.9) & (lat < 60.1))
    assert 4500 < out["length"][0] < 5100  # metres, along a 5 km river
    assert 20 < out["width"][0] < 60


def test_cli_writes_a_geopackage_of_mixed_polygons(tmp_path: Path) -> None:
    islets = MultiPolygon(
        [box(0, 0, 2000, 600), *(box(3000 + 40 * i, 0, 3005 + 40 * i, 5) for i in range(3))]
    )
    lake_with_island = Point(0, 0).buffer(500).difference(Point(100, 50).buffer(120))
    frame = gpd.GeoDataFrame(
        {"name": ["river", "lake", "islets", "nothing"]},
        geometry=[river(3_000, 20, 60, seed=2).polygon, lake_with_island, islets, None],
        crs="EPSG:32633",
    )
    source, target = tmp_path / "mixed.gpkg", tmp_path / "lines.gpkg"
    frame.to_file(source, driver="GPKG")
    run = subprocess.run(
        [*CLI, "centerlines", str(source), str(target), "--jobs", "2", "--pixel-size", "4"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 1  # one feature failed: said, and the others written
    assert "feature 3" in run.stderr and "no polygon" in run.stderr
    out = gpd.read_file(target)
    assert out.crs == frame.crs
    assert sorted(set(out["name"])) == ["islets", "lake", "nothing", "river"]
    islet_rows = out[out["name"] == "islets"]
    # every part of the multi-polygon has its row: a line, and a point for each islet
    assert islet_rows["kind"].tolist() == ["line", "point", "point", "point"]
    assert islet_rows["part"].tolist() == [0, 1, 2, 3]
    points = islet_rows[islet_rows["kind"] == "point"].geometry
    assert all(islets.geoms[i + 1].contains(p) for i, p in enumerate(points))
    failed = out[out["name"] == "nothing"]
    assert failed.geometry.isna().all() and "no polygon" in failed["error"].iloc[0]
    lake_rows = out[out["name"] == "lake"]
    assert (lake_rows["kind"] == "line").all()
    assert all(lake_with_island.covers(g) for g in lake_rows.geometry)


def strip_geotiff(path: Path, crs: str, origin: tuple[float, float]) -> Path:
    """A GeoTIFF mask of 200×60 pixels of 2 m, its top-left corner at ``origin``, in
    ``crs``, holding a strip: rows 20-39, columns 10-189."""
    mask = np.zeros((60, 200), np.uint8)
    mask[20:40, 10:190] = 1
    with rasterio.open(
        path,
        "w",
        driver="GTiff",
        width=200,
        height=60,
        count=1,
        dtype="uint8",
        crs=crs,
        transform=from_origin(*origin, 2, 2),
    ) as f:
        f.write(mask, 1)
    return path


def test_geotiff_mask_gives_lines_in_its_crs_and_map_coordinates(tmp_path: Path) -> None:
    # a strip 20 px = 40 m wide, 180 px = 360 m long
    path = strip_geotiff(tmp_path / "mask.tif", "EPSG:32633", (500_000, 6_600_000))
    geo = skelprune.prune(path).to_geojson()
    assert geo["crs"] == {"type": "name", "properties": {"name": "EPSG:32633"}}
    branches = [f for f in geo["features"] if f["properties"]["kind"] == "branch"]
    xy = np.concatenate([np.asarray(f["geometry"]["coordinates"]) for f in branches])
    # the strip's map coordinates: x 500020…500380, y 6599920…6599960
    assert np.all((xy[:, 0] >= 500_020) & (xy[:, 0] <= 500_380))
    assert np.all((xy[:, 1] >= 6_599_920) & (xy[:, 1] <= 6_599_960))
    longest = max(f["properties"]["length"] for f in branches)
    assert 250 < longest < 380  # metres: the strip, at most its corner diagonals (2 × 14 px)
    run = subprocess.run(
        [*CLI, "prune", str(path), "--geojson"], capture_output=True, text=True, timeout=120
    )
    assert run.returncode == 0 and '"EPSG:32633"' in run.stdout


def test_prune_takes_a_one_feature_table_with_its_crs_and_refuses_a_merge() -> None:
    reach = box(0, 0, 3000, 800)
    lonlat = gpd.GeoDataFrame(geometry=[on_earth(reach, 10.0, 60.0)], crs="EPSG:4326")
    raster = skelprune.prune(lonlat).to_dict()["raster"]
    assert raster["crs"] == "EPSG:4326" and 2 < raster["pixel_size"] < 20  # metres
    two = gpd.GeoDataFrame(geometry=[reach, box(2500, 0, 5500, 600)], crs="EPSG:32633")
    with pytest.raises(skelprune.InvalidPolygonError, match="each is its own shape"):
        skelprune.prune(two)


def test_a_crs_with_no_epsg_code_is_named_by_its_authority(tmp_path: Path) -> None:
    # ESRI:102003 (USA Contiguous Albers Equal Area) has no EPSG code: its name, not its
    # WKT (which the CRS check refuses), goes with the lines
    path = strip_geotiff(tmp_path / "albers.tif", "ESRI:102003", (1_000_000, 2_000_000))
    geo = skelprune.prune(path).to_geojson()
    assert geo["crs"] == {"type": "name", "properties": {"name": "ESRI:102003"}}
    lakes = gpd.GeoDataFrame(geometry=[box(0, 0, 3000, 600)], crs="ESRI:102003")
    out = centerlines(lakes)
    assert out.crs == lakes.crs and out["length"].round().tolist() == [3000]
    raster = skelprune.prune(lakes).to_dict()["raster"]
    assert raster["crs"] == "ESRI:102003"


def test_a_geotiff_as_bytes_gives_the_files_answer_and_records_its_grid(tmp_path: Path) -> None:
    mask = np.zeros((40, 90), np.uint8)
    mask[10:30, 5:85] = 3
    mask[0:4, 0:4] = 9  # nodata
    path = tmp_path / "mask.tif"
    with rasterio.open(
        path, "w", driver="GTiff", width=90, height=40, count=1, dtype="uint8",
        crs="EPSG:3035", transform=from_origin(4_321_000, 3_210_000, 5, 5), nodata=9,
    ) as f:  # fmt: skip
        f.write(mask, 1)
    from_file = skelprune.prune(path)
    from_bytes = skelprune.prune(path.read_bytes())
    assert from_file.to_dict() == from_bytes.to_dict()
    assert from_file.to_geojson() == from_bytes.to_geojson()
    assert from_file.to_dict()["georeference"] == {
        "crs": "EPSG:3035",
        "transform": [5.0, 0.0, 4_321_000.0, 0.0, -5.0, 3_210_000.0],
    }
    assert len(from_file.components) == 1  # nodata is not the shape


def test_geotiff_tags_pixel_is_point_and_the_model_transformation() -> None:
    import io

    import tifffile

    from skelprune.io.geotiff import geotiff_georeference

    def tags(*extra: tuple) -> bytes:
        buf = io.BytesIO()
        tifffile.imwrite(buf, np.ones((4, 4), np.uint8), extratags=list(extra))
        return buf.getvalue()

    keys = (34735, 3, 12, (1, 1, 0, 2, 1025, 0, 1, 2, 2048, 0, 1, 4326))  # point, EPSG:4326
    scale, tie = (33550, 12, 3, (0.5, 0.5, 0.0)), (33922, 12, 6, (0, 0, 0, 10.0, 60.0, 0))
    geo = geotiff_georeference(tags(scale, tie, keys))
    assert geo.crs == "EPSG:4326"
    assert geo.transform == (0.5, 0.0, 9.75, 0.0, -0.5, 60.25)  # the tie is a pixel centre
    matrix = (34264, 12, 16, (3.0, 0, 0, 100.0, 0, -3.0, 0, 200.0, 0, 0, 1, 0, 0, 0, 0, 1))
    assert geotiff_georeference(tags(matrix)).transform == (3.0, 0.0, 100.0, 0.0, -3.0, 200.0)
    assert geotiff_georeference(tags()) is None  # a plain TIFF
    with pytest.raises(skelprune.InvalidImageError, match="no grid"):
        geotiff_georeference(tags((34735, 3, 4, (1, 1, 0, 0))))


@pytest.mark.parametrize("name", ["croatia", "italy"])
def test_map_lines_on_real_coastlines_carry_at_most_4_vertices_a_width(name: str) -> None:
    import json

    from skelprune.io.polygon import parse_geojson
    from testkit import REPO
    from testkit.rivers import vertices_per_width

    geom = parse_geojson(json.loads((REPO / "data" / "gis" / f"{name}.geojson").read_text()))
    rows, _ = feature_lines(geom)
    lines = [r["geometry"] for r in rows if r["kind"] == "line"]
    per_part, local = vertices_per_width(lines, geom)
    assert per_part <= 4 and local <= 4
    # inside, but where the raster (227 m, 553 m pixels) closes a bay's mouth or a strait
    # narrower than a pixel: there a line crosses the water, by under a pixel
    pixel = skelprune.prune(geom).to_dict()["raster"]["pixel_size"]
    total = sum(ln.length for ln in lines)
    outside = [
        piece
        for ln in lines
        for piece in shapely.get_parts(shapely.difference(ln, geom))
        # on the boundary is inside: pieces a rounding off it are not counted
        if geom.distance(piece.interpolate(0.5, normalized=True)) > 1e-3
    ]
    assert sum(p.length for p in outside) <= 2e-3 * total  # 0.13 % on Croatia
    for piece in outside:
        dense = shapely.segmentize(piece, pixel / 20)
        far = shapely.distance(geom, shapely.points(shapely.get_coordinates(dense))).max()
        assert piece.length < 3 * pixel and far < 0.75 * pixel  # at most 0.62 seen
