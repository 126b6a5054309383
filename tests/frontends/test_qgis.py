"""The QGIS Processing provider, headless with Debian's QGIS (``qgis_process.bin``,
installed by ``make test``): the plugin enables, both algorithms are listed, and each
gives the lines the library gives: ``skelprune:centerlines`` those of ``skelprune
centerlines`` on the same GeoPackage, ``skelprune:rasterlines`` those of
:func:`skelprune.prune` on the same GeoTIFF mask."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import geopandas as gpd
import numpy as np
import pytest
import shapely
from shapely.geometry import Point, box

import skelprune
from testkit import REPO

pytestmark = pytest.mark.timeout(300)

QGIS = "/usr/bin/qgis_process.bin"


def _env(home: Path, python: str | None) -> dict[str, str]:
    """The plugin folder of this checkout, a QGIS profile of its own under ``home``, and
    the library's Python (none: unset)."""
    env = {
        **os.environ,
        "QGIS_PLUGINPATH": str(REPO / "qgis"),
        "QT_QPA_PLATFORM": "offscreen",
        "HOME": str(home),
        "XDG_CONFIG_HOME": str(home / ".config"),
        "XDG_DATA_HOME": str(home / ".local" / "share"),
    }
    env.pop("SKELPRUNE_PYTHON", None)
    if python is not None:
        env["SKELPRUNE_PYTHON"] = python
    return env


def _qgis(home: Path, *arguments: str, python: str | None = sys.executable) -> str:
    """``qgis_process.bin ARGUMENTS`` (:func:`_env`): its output, having succeeded."""
    run = subprocess.run(
        [QGIS, *arguments], env=_env(home, python), capture_output=True, text=True, timeout=240
    )
    assert run.returncode == 0, run.stdout + run.stderr
    return run.stdout


@pytest.fixture(scope="module")
def home(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A QGIS profile with the plugin enabled."""
    where = tmp_path_factory.mktemp("qgis-home")
    _qgis(where, "plugins", "enable", "skelprune_qgis")
    return where


def _polygons(path: Path) -> None:
    lake = box(500000, 6600000, 503000, 6600800)
    river = shapely.union(
        box(500000, 6602000, 504000, 6602150), box(502000, 6602000, 502150, 6604000)
    )
    islands = shapely.MultiPolygon(
        [box(506000, 6600000, 509000, 6600600), Point(510000, 6600300).buffer(20)]
    )
    frame = gpd.GeoDataFrame(
        {"name": ["lake", "river", "islands", "nothing"], "depth": [3.5, 1.0, 2.0, 0.0]},
        geometry=[lake, river, islands, None],
        crs="EPSG:32633",
    )
    frame.to_file(path, driver="GPKG", engine="pyogrio")


def _same_rows(got: gpd.GeoDataFrame, want: gpd.GeoDataFrame) -> None:
    assert len(got) == len(want) > 0
    assert got.crs == want.crs
    for column in ("feature", "part", "kind", "name", "depth", "error"):
        values = [got[column].astype(object).where(got[column].notna(), None).tolist()]
        values.append(want[column].astype(object).where(want[column].notna(), None).tolist())
        assert values[0] == values[1], column
    np.testing.assert_allclose(got["length"].astype(float), want["length"].astype(float))
    for a, b in zip(got.geometry, want.geometry, strict=True):
        assert (a is None or a.is_empty) == (b is None or b.is_empty)
        if b is not None and not b.is_empty:
            assert a.equals_exact(b, 1e-6), (a.wkt, b.wkt)


def test_both_algorithms_are_listed(home: Path) -> None:
    listing = _qgis(home, "list")
    assert "skelprune:centerlines" in listing and "skelprune:rasterlines" in listing


@pytest.mark.parametrize("options", [[], ["--main-path", "--pixel-size", "20"]])
def test_centerlines_are_those_of_the_command_line(home: Path, tmp_path: Path, options) -> None:
    given = tmp_path / "in.gpkg"
    _polygons(given)
    cli = tmp_path / "cli.gpkg"
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "skelprune.cli",
            "centerlines",
            given,
            cli,
            "--no-progress",
            *options,
        ],
        capture_output=True,
        text=True,
        timeout=240,
    )
    assert run.returncode == 1, run.stderr  # the feature without geometry fails
    assert "feature 3: the feature has no polygon" in run.stderr
    qgis, points = tmp_path / "qgis.gpkg", tmp_path / "points.gpkg"
    parameters = [f"INPUT={given}", f"OUTPUT={qgis}", f"POINTS={points}"]
    if options:
        parameters += ["MAIN_PATH=true", "PIXEL_SIZE=20"]
    _qgis(home, "run", "skelprune:centerlines", "--", *parameters)
    want = gpd.read_file(cli)
    lines = want[want["kind"] != "point"].reset_index(drop=True)
    _same_rows(gpd.read_file(qgis), lines)
    _same_rows(gpd.read_file(points), want[want["kind"] == "point"].reset_index(drop=True))
    assert gpd.read_file(qgis)["error"].tolist()[-1].startswith("the feature has no polygon")


def test_centerlines_of_longitude_latitude_are_measured_in_metres(
    home: Path, tmp_path: Path
) -> None:
    given = tmp_path / "lonlat.gpkg"
    lake = box(10.0, 60.0, 10.05, 60.005)  # about 2.8 km by 560 m
    gpd.GeoDataFrame({"name": ["lake"]}, geometry=[lake], crs="EPSG:4326").to_file(given)
    qgis = tmp_path / "qgis.gpkg"
    _qgis(home, "run", "skelprune:centerlines", "--", f"INPUT={given}", f"OUTPUT={qgis}")
    got = gpd.read_file(qgis)
    want = skelprune.geo.centerlines(gpd.read_file(given))
    assert got.crs == "EPSG:4326" and 2500 < got["length"][0] < 2800  # metres
    _same_rows(got.assign(depth=0.0), want.assign(depth=0.0))


def test_rasterlines_are_the_librarys_lines_in_the_rasters_crs(home: Path, tmp_path: Path) -> None:
    import rasterio
    from rasterio.transform import from_origin

    mask = np.zeros((60, 120), np.uint8)
    mask[10:50, 10:110] = 1
    mask[25:35, 60:118] = 1
    mask[0, :] = 255  # nodata: not the shape
    tif = tmp_path / "mask.tif"
    profile = {"driver": "GTiff", "width": 120, "height": 60, "count": 1, "dtype": "uint8",
               "crs": "EPSG:32633", "transform": from_origin(500000, 6600000, 10, 10),
               "nodata": 255}  # fmt: skip
    with rasterio.open(tif, "w", **profile) as f:
        f.write(mask, 1)
    out = tmp_path / "lines.gpkg"
    _qgis(home, "run", "skelprune:rasterlines", "--", f"INPUT={tif}", f"OUTPUT={out}")
    got = gpd.read_file(out)
    want = [
        f for f in skelprune.prune(tif).to_geojson()["features"]
        if f["geometry"]["type"] == "LineString"
    ]  # fmt: skip
    assert got.crs == "EPSG:32633" and len(got) == len(want) > 0
    for row, feature in zip(got.itertuples(), want, strict=True):
        assert row.branch == feature["properties"]["id"]
        assert row.length == pytest.approx(feature["properties"]["length"])
        np.testing.assert_allclose(shapely.get_coordinates(row.geometry),
                                   feature["geometry"]["coordinates"])  # fmt: skip


def test_without_the_librarys_python_the_run_says_how_to_set_it(home: Path, tmp_path: Path) -> None:
    given = tmp_path / "in.gpkg"
    _polygons(given)
    out = tmp_path / "out.gpkg"
    run = subprocess.run(
        [QGIS, "run", "skelprune:centerlines", "--", f"INPUT={given}", f"OUTPUT={out}"],
        env=_env(home, None),
        capture_output=True,
        text=True,
        timeout=240,
    )
    assert run.returncode != 0
    assert "SKELPRUNE_PYTHON" in run.stdout + run.stderr
