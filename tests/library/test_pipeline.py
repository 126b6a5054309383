"""One input type and one pipeline: every input read into an ``Input``, every option one
value of its class, the result carrying both, and every option in the document."""

from __future__ import annotations

import io
import json
import subprocess
import sys
from dataclasses import fields, replace
from typing import Any

import numpy as np
import pytest
import shapely
from PIL import Image
from shapely.geometry import LineString, Point, shape

import skelprune
from skelprune import Input, OutputOptions, PruneOptions, RasterOptions, ReadOptions, read_input
from skelprune.errors import InvalidImageError, InvalidOptionError
from skelprune.io.frame import IDENTITY
from skelprune.options import GROUPS

# An L of two arms, far from the origin: pixel coordinates would lie outside it.
L_SHAPE = {
    "type": "Polygon",
    "coordinates": [
        [
            [5000, 3000],
            [5400, 3000],
            [5400, 3060],
            [5060, 3060],
            [5060, 3300],
            [5000, 3300],
            [5000, 3000],
        ]
    ],
}


def rectangle() -> np.ndarray:
    m = np.zeros((30, 60), bool)
    m[5:25, 5:55] = True
    return m


def png_bytes(a: np.ndarray) -> bytes:
    buf = io.BytesIO()
    Image.fromarray(a).save(buf, "PNG")
    return buf.getvalue()


def test_geojson_in_one_call_answers_in_the_polygons_coordinates() -> None:
    res = skelprune.prune(L_SHAPE)
    polygon = shape(L_SHAPE)
    near = polygon.buffer(1e-6)
    geo = res.to_geojson()
    lines = [f for f in geo["features"] if f["geometry"]["type"] == "LineString"]
    assert lines
    for f in geo["features"]:
        geom = shape(f["geometry"])
        assert near.contains(geom), f["properties"]
    # the skeleton reaches into both arms, in polygon units
    skeleton = shapely.union_all([LineString(f["geometry"]["coordinates"]) for f in lines])
    assert skeleton.intersects(Point(5300, 3030).buffer(30))
    assert skeleton.intersects(Point(5030, 3200).buffer(30))
    doc = res.to_dict()
    xs = [p[0] for b in doc["components"][0]["skeleton"]["branches"] for p in b["points"]]
    assert min(xs) >= 5000 and max(xs) <= 5400
    assert doc["foreground"]["shape"] == "polygon" and res.frame.flip_y


def test_every_input_reads_into_one_input(tmp_path) -> None:
    grey = np.full((30, 60), 255, np.uint8)
    grey[rectangle()] = 0  # black on white: the auto rule takes the dark side
    data = png_bytes(grey)
    path = tmp_path / "rect.png"
    path.write_bytes(data)
    from_bytes, from_path = read_input(data), read_input(str(path))
    assert from_bytes.kind == from_path.kind == "image"
    assert np.array_equal(from_bytes.mask, rectangle())
    assert np.array_equal(from_path.mask, rectangle())
    assert from_bytes.foreground.shape == "dark" and from_bytes.frame == IDENTITY
    # an array is a mask: its non-zero pixels, unless told otherwise
    assert np.array_equal(read_input(grey).mask, grey != 0)
    assert np.array_equal(read_input(grey, read=ReadOptions("auto")).mask, rectangle())
    # GeoJSON as a mapping, as text, as a file and as a shapely geometry: the same raster
    text = json.dumps(L_SHAPE)
    (tmp_path / "l.geojson").write_text(text)
    opts = RasterOptions(longest_side=64)
    reads = [
        read_input(src, raster=opts)
        for src in (L_SHAPE, text, tmp_path / "l.geojson", shape(L_SHAPE))
    ]
    for r in reads:
        assert r.kind == "geojson" and r.raster is not None
        assert r.raster.options == opts and r.frame == reads[0].frame
        assert np.array_equal(r.mask, reads[0].mask)
    assert read_input(reads[0]) is reads[0]


def test_data_of_a_known_kind_is_never_a_file_name(tmp_path) -> None:
    path = tmp_path / "rect.png"
    path.write_bytes(png_bytes(rectangle().astype(np.uint8) * 255))
    with pytest.raises(InvalidImageError, match="not a file name"):
        read_input(str(path), kind="image")
    with pytest.raises(InvalidImageError, match="not a file name"):
        read_input(path, kind="image")
    assert read_input(path.read_bytes(), kind="image").mask.sum() == rectangle().sum()


def test_prune_takes_an_input_and_carries_its_frame() -> None:
    shape_ = read_input(L_SHAPE, raster=RasterOptions(longest_side=64))
    res = skelprune.prune(shape_)
    assert res.input is shape_ and res.frame == shape_.frame and res.raster is shape_.raster
    assert res.to_dict() == skelprune.prune(L_SHAPE, longest_side=64).to_dict()
    with pytest.raises(InvalidOptionError, match="is read"):
        skelprune.prune(shape_, longest_side=32)


def test_keywords_build_the_options_value_once() -> None:
    m = rectangle()
    a = skelprune.prune(m, beta=4.0, trim=False, curve=False)
    b = skelprune.prune(m, PruneOptions(beta=4.0, trim=False), output=OutputOptions(curve=False))
    assert a.to_dict() == b.to_dict()
    assert "curve" not in a.to_dict()["components"][0]  # the result's own output options
    with pytest.raises(TypeError, match="not both"):
        skelprune.prune(m, PruneOptions(), beta=4.0)
    with pytest.raises(TypeError, match="unknown option 'betta'"):
        skelprune.prune(m, betta=4.0)
    with pytest.raises(InvalidOptionError, match="beta"):
        skelprune.prune(m, beta=-1.0)


def test_the_result_holds_the_options_as_applied() -> None:
    m = rectangle()
    res = skelprune.prune(m, method="dce")
    assert res.options == PruneOptions(method="dce").resolved()
    assert (res.coarse, res.trim, res.options.dce_threshold) == (None, False, 0.01)
    # the applied default prunes as the explicit value does
    assert skelprune.prune(m).to_dict() == skelprune.prune(m, min_margin=0.01).to_dict()


# Each option: a value other than its default (valid together with the others), and where
# the outputs show it. A new option fails the coverage check below until it is listed.
def _doc(res: skelprune.PruneResult) -> dict[str, Any]:
    return res.to_dict()


def _lines(res: skelprune.PruneResult) -> str:
    """The GeoJSON's first feature's kind, or why the map lines are not a result's."""
    try:
        return str(res.to_geojson()["features"][0]["properties"]["kind"])
    except InvalidOptionError as exc:  # lines=map: skelprune.geo.geojson_lines
        return str(exc)


CHANGES: dict[str, tuple[dict[str, Any], Any]] = {
    # PruneOptions: in the document's top level
    "beta": ({"beta": 4.0}, lambda r: _doc(r)["beta"]),
    "method": ({"method": "dce"}, lambda r: _doc(r)["method"]),
    "coarse": ({"coarse": "dce"}, lambda r: _doc(r)["coarse"]),
    "dce_threshold": (
        {"method": "dce", "dce_threshold": 0.05},
        lambda r: _doc(r)["dce_threshold"],
    ),
    "min_margin": ({"min_margin": 0.2}, lambda r: _doc(r)["min_margin"]),
    "choice": ({"choice": "argmin"}, lambda r: _doc(r)["choice"]),
    "trim": ({"trim": False}, lambda r: _doc(r)["trim"]),
    # the paper's global scope goes unsaid (documents stay as they were); local is shown
    "scope": ({"scope": "local"}, lambda r: _doc(r).get("scope", "global")),
    "window": ({"scope": "local", "window": 128}, lambda r: _doc(r).get("window")),
    # ReadOptions: the rule asked for
    "foreground": ({"foreground": "zero"}, lambda r: _doc(r)["foreground"]["rule"]),
    "labels": ({"labels": True}, lambda r: _doc(r)["foreground"]["shape"]),
    "fill_holes": ({"fill_holes": 4}, lambda r: _doc(r)["foreground"].get("fill_holes")),
    "min_area": ({"min_area": 4}, lambda r: _doc(r)["foreground"].get("min_area")),
    # RasterOptions: in the document's raster part
    "pixel_size": ({"pixel_size": 5.0}, lambda r: _doc(r)["raster"]["pixel_size"]),
    "longest_side": ({"longest_side": 40}, lambda r: _doc(r)["raster"]["longest_side"]),
    "pixels_per_width": (
        {"pixels_per_width": 5.0},
        lambda r: _doc(r)["raster"]["pixels_per_width"],
    ),
    "pixel_budget": ({"pixel_budget": 8192}, lambda r: _doc(r)["raster"]["pixel_budget"]),
    "repair": ({"repair": False}, lambda r: _doc(r)["raster"]["repair"]),
    "crs": ({"crs": "EPSG:32633"}, lambda r: _doc(r)["raster"]["crs"]),
    # OutputOptions: what each output holds
    "curve": ({"curve": False}, lambda r: "curve" in _doc(r)["components"][0]),
    "overlay": ({"overlay": True}, lambda r: "overlay_png" in _doc(r)),
    "sequence": ({"sequence": True}, lambda r: "sequence" in _doc(r)["components"][0]),
    "overlay_scale": ({"overlay_scale": 2}, lambda r: Image.open(io.BytesIO(r.overlay_png())).size),
    "overlay_legend": (
        {"overlay_legend": True},
        lambda r: Image.open(io.BytesIO(r.overlay_png())).size,
    ),
    "simplify": ({"simplify": 0.0}, lambda r: r.to_geojson()["properties"]["simplify"]),
    "cut_ends": ({"cut_ends": True}, lambda r: r.to_geojson()["properties"]["cut_ends"]),
    "lines": ({"lines": "map"}, _lines),
    "table": ({"table": "component"}, lambda r: r.to_csv().splitlines()[0]),
    # VolumeOptions: in a volume's document
    "spacing": ({"spacing": (2.0, 1.0, 1.0)}, lambda r: _doc(r)["spacing"]),
}


def test_the_table_covers_every_option() -> None:
    assert set(CHANGES) == {f.name for group in GROUPS for f in fields(group)}


@pytest.mark.parametrize("name", sorted(CHANGES))
def test_every_option_shows_in_the_outputs(name: str) -> None:
    given, shown = CHANGES[name]
    # each option on an input it applies to (its definition's ``where``)
    polygon = name in {f.name for f in fields(RasterOptions)} | {"lines"}
    source: Any = L_SHAPE if polygon else rectangle().astype(np.uint8)
    if name == "spacing":
        source = np.zeros((8, 10, 30), bool)
        source[2:6, 3:7, 2:28] = True
    default, changed = skelprune.prune(source), skelprune.prune(source, **given)
    assert shown(default) != shown(changed)
    if name in {f.name for f in fields(PruneOptions)}:  # recorded as applied
        assert shown(changed) == getattr(PruneOptions(**given).resolved(), name)


def test_every_pruning_option_is_in_the_document_and_the_geojson() -> None:
    res = skelprune.prune(L_SHAPE, longest_side=64)
    doc, geo = res.to_dict(), res.to_geojson()
    unsaid = {"scope": "global", "window": None}  # the global scope's, left out
    for f in fields(PruneOptions):
        shown = doc.get(f.name, unsaid.get(f.name, "missing"))
        assert shown == geo["properties"].get(f.name, unsaid.get(f.name))
        assert shown == getattr(res.options, f.name)
    local = skelprune.prune(L_SHAPE, longest_side=64, scope="local", window=128)
    doc, geo = local.to_dict(), local.to_geojson()
    assert doc["scope"] == geo["properties"]["scope"] == "local"
    assert doc["window"] == geo["properties"]["window"] == 128
    for f in fields(RasterOptions):
        assert f.name in doc["raster"]


def test_cli_and_library_give_the_same_document(tmp_path) -> None:
    path = tmp_path / "l.geojson"
    path.write_text(json.dumps(L_SHAPE))
    png = tmp_path / "rect.png"
    png.write_bytes(png_bytes(rectangle().astype(np.uint8) * 255))
    cases = [
        (path, ["--longest-side", "80", "--min-margin", "0.05", "--no-curve"]),
        (png, ["--method", "dce", "--dce-threshold", "0.02", "--foreground", "nonzero"]),
    ]
    library = [
        skelprune.prune(path, longest_side=80, min_margin=0.05, curve=False),
        skelprune.prune(png, method="dce", dce_threshold=0.02, foreground="nonzero"),
    ]
    for (file, args), res in zip(cases, library, strict=True):
        run = subprocess.run(
            [sys.executable, "-m", "skelprune.cli", "prune", str(file), *args],
            capture_output=True,
            text=True,
            timeout=300,
        )
        assert run.returncode == 0, run.stderr
        assert json.loads(run.stdout) == json.loads(json.dumps(res.to_dict()))


def test_a_match_answers_in_each_inputs_coordinates() -> None:
    moved = json.loads(json.dumps(L_SHAPE))
    moved["coordinates"][0] = [[x - 5000, y - 3000] for x, y in moved["coordinates"][0]]
    doc = skelprune.match(skelprune.prune(L_SHAPE), skelprune.prune(moved)).to_dict()
    assert doc["distance"] < 0.05
    for pair in doc["correspondence"]:
        assert 5000 <= pair["a"]["x"] <= 5400 and 0 <= pair["b"]["x"] <= 400


def test_an_input_refuses_what_is_not_a_mask() -> None:
    with pytest.raises(InvalidImageError, match="2-D"):
        Input(np.zeros((2, 2, 2, 2)))
    assert replace(Input(rectangle()), frame=IDENTITY).mask.dtype == bool


def test_an_options_value_names_every_option_it_refuses() -> None:
    with pytest.raises(InvalidOptionError) as info:
        PruneOptions(beta=-1.0, method="x", trim=True)
    assert [name for name, _ in info.value.errors] == ["beta", "method"]
    assert "beta must be" in str(info.value) and "method must be" in str(info.value)
    with pytest.raises(InvalidOptionError) as info:
        RasterOptions(pixel_size=1.0, longest_side=64)  # refused together: no one option
    assert info.value.errors == []
