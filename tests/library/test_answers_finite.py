"""No answer of the library holds NaN or infinity: over a corpus of awkward shapes
(cycles, lakes with islands, one-pixel components, straight lines, loops, shapes touching
the border, noise) every answer type, the JSON document, the GeoJSON branches and map
lines, both CSV tables, GraphML, a volume's document, table and SWC, writes a number that
is not defined as null (CSV: an empty cell), through skelprune/output/finite.py."""

from __future__ import annotations

import csv
import io
import json
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import skelprune
from skelprune.errors import InvalidOptionError
from skelprune.output.finite import finite_json
from skelprune.output.summary import BRANCH_COLUMNS, _component_branches, unit_of
from testkit import awkward

gpd = pytest.importorskip("geopandas", reason="the geo extra")  # make test installs it
from skelprune.geo import (  # noqa: E402
    centerlines,
    geojson_lines,
    lines_geojson,
    write_frame,
)

pytestmark = pytest.mark.timeout(600)

MASKS = awkward.masks()
POLYGONS = awkward.polygons()
VOLUMES = awkward.volumes()


def image_answers(res: skelprune.PruneResult) -> None:
    """Every text answer of an image's or a polygon's result, checked."""
    awkward.assert_finite_json(json.dumps(res.to_dict(sequence=True)))
    awkward.assert_finite_json(json.dumps(res.to_geojson()))
    awkward.assert_finite_json(json.dumps(res.to_geojson(simplify=0, cut_ends=True)))
    for level in ("branch", "component"):
        awkward.assert_finite_text(res.to_csv(level))
    awkward.assert_finite_text(res.to_graphml())


def test_the_corpus_holds_numbers_that_are_not_defined() -> None:
    """The noise mask has branches without a direction: their junction angles are NaN
    in the raw numbers, null in the GeoJSON and empty cells in the CSV."""
    res = skelprune.prune(MASKS["noise"])
    scale, unit = unit_of(res)
    raw = [
        row
        for ci, c in enumerate(res.components)
        for row in _component_branches(c.table, ci, c.label, scale, unit)
    ]
    undefined = {
        (row["component"], row["branch"], key)
        for row in raw
        for key, value in row.items()
        if isinstance(value, float) and not math.isfinite(value)
    }
    assert undefined, "the noise mask has no undefined number: the corpus is not awkward"
    assert {key for *_, key in undefined} <= set(BRANCH_COLUMNS)
    rows = list(csv.DictReader(io.StringIO(res.to_csv())))
    by_branch = {(int(r["component"]), int(r["branch"])): r for r in rows}
    assert all(by_branch[(c, b)][key] == "" for c, b, key in undefined)
    lines = {
        (f["properties"]["component"], f["properties"]["id"]): f["properties"]
        for f in res.to_geojson()["features"]
        if f["properties"]["kind"] == "branch"
    }
    assert all(lines[(c, b)][key] is None for c, b, key in undefined if (c, b) in lines)


@pytest.mark.parametrize("name", sorted(MASKS))
def test_every_answer_of_an_awkward_mask_is_finite(name: str) -> None:
    image_answers(skelprune.prune(MASKS[name]))


@pytest.mark.parametrize("name", sorted(POLYGONS))
def test_every_answer_of_an_awkward_polygon_is_finite(name: str) -> None:
    polygon = POLYGONS[name]
    image_answers(skelprune.prune(polygon))
    for main_path in (False, True):
        lines = awkward.assert_finite_json(geojson_lines(polygon, main_path=main_path))
        errors = [f["properties"]["error"] for f in lines["features"]]
        assert errors and errors == [None] * len(errors)


@pytest.mark.parametrize("name", sorted(VOLUMES))
def test_every_answer_of_an_awkward_volume_is_finite(name: str) -> None:
    res = skelprune.prune(VOLUMES[name], spacing=(2.0, 1.0, 1.0))
    awkward.assert_finite_json(json.dumps(res.to_dict()))
    awkward.assert_finite_text(res.to_csv())
    swc = res.to_swc()
    awkward.assert_finite_text(swc)
    assert len(swc.splitlines()) > 1


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    seed=st.integers(0, 2**16),
    size=st.tuples(st.integers(6, 40), st.integers(6, 40)),
    density=st.floats(0.3, 0.9),
    holes=st.integers(0, 4),
)
def test_any_noisy_mask_with_holes_answers_finite(seed, size, density, holes) -> None:
    rng = np.random.default_rng(seed)
    mask = rng.random(size) < density
    for _ in range(holes):  # square holes: cycles
        y, x = rng.integers(0, size[0]), rng.integers(0, size[1])
        mask[y : y + 3, x : x + 3] = False
    if not mask.any():
        mask[0, 0] = True
    image_answers(skelprune.prune(mask))


def test_the_one_rule_takes_numpy_floats_too() -> None:
    doc = {"a": np.float32("nan"), "b": [np.float64("inf"), 1.5]}
    assert json.loads(finite_json(doc)) == {"a": None, "b": [None, 1.5]}


def test_a_map_line_without_a_number_is_null() -> None:
    """A Feature that fails keeps its row, its numbers null (the CLI's file, the
    service's answer)."""
    lines = centerlines(gpd.GeoDataFrame({"name": ["none"]}, geometry=[None]))
    doc = awkward.assert_finite_json(lines_geojson(lines))
    (props,) = [f["properties"] for f in doc["features"]]
    assert (props["length"], props["width"], props["name"]) == (None, None, "none")
    assert "no polygon" in props["error"]


def test_a_geojson_file_of_map_lines_is_what_gdal_writes(tmp_path) -> None:
    """``skelprune centerlines OUT.geojson`` writes :func:`lines_geojson`'s bytes, which
    are GDAL's own file of the same table."""
    frame = gpd.GeoDataFrame.from_features(
        json.loads(geojson_lines(POLYGONS["lake-with-islands"]))["features"], crs="EPSG:32633"
    )
    ours, gdal = tmp_path / "lakes.geojson", tmp_path / "gdal" / "lakes.geojson"
    gdal.parent.mkdir()
    write_frame(frame, ours)
    frame.to_file(gdal, driver="GeoJSON", engine="pyogrio")
    assert ours.read_bytes() == gdal.read_bytes() == lines_geojson(frame, "lakes")


def test_a_result_refuses_map_lines_and_names_where_they_are() -> None:
    res = skelprune.prune(POLYGONS["square"], lines="map")
    with pytest.raises(InvalidOptionError, match=r"skelprune\.geo\.geojson_lines"):
        res.to_geojson()
    with pytest.raises(InvalidOptionError, match="lines must be one of branches, map"):
        skelprune.prune(POLYGONS["square"], lines="mapp")
