"""Label images: every label pruned on its own even where labels touch; the hint; the
cleaning options."""

from __future__ import annotations

import io

import numpy as np
import pytest
from PIL import Image

import skelprune
from skelprune.errors import InvalidImageError, InvalidOptionError
from testkit.shapes import blobs


def touching_labels(seed: int = 3, size: int = 160, n: int = 9) -> np.ndarray:
    """A Voronoi-like tiling of blobs: many labels, most touching their neighbours, one
    label in two pieces, one with a hole."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[:size, :size]
    seeds = rng.uniform(10, size - 10, (n, 2))
    d = np.stack([np.hypot(yy - y, xx - x) for y, x in seeds])
    lab = (np.argmin(d, axis=0) + 1) * 700  # 16-bit values, far apart
    lab[np.min(d, axis=0) > 30] = 0
    cut = lab[:, size // 2 : size // 2 + 3]  # a view: one label cut in two pieces
    cut[cut == lab[size // 2, size // 2]] = 0
    lab[blobs(5, size, 2) & (lab == 0)] = 65000  # a label of irregular shape
    return lab.astype(np.uint16)


def strip_label(doc):
    return {k: v for k, v in doc.items() if k != "label"}


def png16(a: np.ndarray) -> bytes:
    buf = io.BytesIO()
    Image.fromarray(a.astype(np.uint16)).save(buf, "PNG")
    return buf.getvalue()


@pytest.mark.parametrize("seed", [3, 8])
def test_touching_labels_come_back_as_each_pruned_alone(seed):
    lab = touching_labels(seed)
    res = skelprune.prune(png16(lab), labels=True)
    doc = res.to_dict()
    assert doc["foreground"]["shape"] == "labels"
    got: dict[int, list] = {}
    for comp in doc["components"]:
        got.setdefault(comp["label"], []).append(strip_label(comp))
    values = sorted(int(v) for v in np.unique(lab) if v)
    assert sorted(got) == values
    for v in values:
        alone = skelprune.prune(lab == v).to_dict()["components"]
        assert got[v] == alone, v


def test_labels_never_join_and_pieces_keep_their_label():
    lab = np.zeros((40, 90), np.int32)
    lab[5:35, 5:45] = 4
    lab[5:35, 45:85] = 2  # touching 4 along a whole side
    lab[37:39, 5:30] = 4  # a second piece of 4
    res = skelprune.prune(lab, labels=True)
    assert [c.label for c in res.components] == [2, 4, 4]
    assert [c.area for c in res.components] == [1200, 1200, 50]
    rows = res.summary()
    assert set(rows["label"]) == {2, 4}
    assert res.summary("component")["label"].tolist() == [2, 4, 4]
    mask = res.skeleton_mask()
    assert mask.dtype == np.int64 and set(np.unique(mask).tolist()) == {0, 2, 4}
    g = res.to_networkx()
    assert {d["label"] for _, d in g.nodes(data=True)} == {2, 4}
    lines = res.to_geojson()
    assert {f["properties"]["label"] for f in lines["features"]} == {2, 4}
    # without the option the two objects are one shape
    assert len(skelprune.prune(lab > 0).components) == 2


def test_label_image_of_the_auto_rule_gets_a_hint():
    lab = touching_labels(3)
    doc = skelprune.prune(png16(lab)).to_dict()
    assert "labels" in doc["hint"] and "label image" in doc["hint"]
    # an anti-aliased two-level mask, a plain mask: no hint
    m = np.zeros((60, 60), np.uint8)
    m[15:45, 15:45] = 255
    m[14, 15:45] = m[45, 15:45] = m[15:45, 14] = m[15:45, 45] = 128
    assert "hint" not in skelprune.prune(m, foreground="auto").to_dict()
    assert "hint" not in skelprune.prune(m > 0).to_dict()


def test_labels_refuse_what_is_not_a_label_image():
    rgb = np.zeros((10, 10, 3), np.uint8)
    with pytest.raises(InvalidImageError, match="one-channel"):
        skelprune.prune(rgb, labels=True)
    with pytest.raises(InvalidImageError, match="whole"):
        skelprune.prune(np.full((10, 10), 0.5), labels=True)
    with pytest.raises(InvalidOptionError, match="fill_holes"):
        skelprune.ReadOptions(fill_holes=-1)
    with pytest.raises(InvalidOptionError, match="labels"):
        skelprune.ReadOptions(labels="yes")


def test_cleaning_fills_small_holes_and_drops_small_components():
    m = np.zeros((60, 100), bool)
    m[10:50, 10:60] = True
    m[20:23, 20:23] = False  # a pinhole of 9 px
    m[25:45, 35:55] = False  # a real hole of 400 px
    m[5:8, 80:83] = True  # a speck of 9 px
    plain = skelprune.prune(m)
    table = plain.summary("component")
    assert len(plain.components) == 2
    assert table.loc[table["area"].idxmax(), "cycles"] == 2
    clean = skelprune.prune(m, fill_holes=10, min_area=10)
    doc = clean.to_dict()
    assert doc["foreground"]["fill_holes"] == 10 and doc["foreground"]["min_area"] == 10
    assert len(clean.components) == 1
    assert clean.components[0].area == 40 * 50 - 400
    assert clean.summary("component")["cycles"][0] == 1
    # off by default: nothing recorded, nothing changed
    assert "fill_holes" not in plain.to_dict()["foreground"]


def test_cleaning_label_images_label_by_label():
    lab = np.zeros((40, 80), np.int32)
    lab[5:35, 5:40] = 1
    lab[5:35, 40:75] = 2
    lab[15:17, 15:17] = 0  # a hole inside 1: filled with 1
    lab[5:35, 39:41] = 0  # a gap between 1 and 2, touching both: kept
    lab[1:3, 70:72] = 3  # a speck: dropped
    res = skelprune.prune(lab, labels=True, fill_holes=10, min_area=10)
    assert [c.label for c in res.components] == [1, 2]
    assert res.components[0].area == 30 * 34
    assert res.input.labels[15, 15] == 1 and res.input.labels[20, 39] == 0


def test_overlay_legend_fits_and_shades_each_label():
    from PIL import ImageDraw, ImageFont

    from skelprune.output.render import LEGEND_LINES, _wrap

    items = [f"label {i}: RER 1.00 %, SS 1.000" for i in range(40)]
    font = ImageFont.load_default(size=14)
    draw = ImageDraw.Draw(__import__("PIL.Image").Image.new("RGB", (1, 1)))

    def fits(text):
        return draw.textlength(text, font=font) <= 300

    lines = _wrap(items, fits)
    assert len(lines) == LEGEND_LINES and all(fits(line) for line in lines)
    shown = sum(line.count("label ") for line in lines)
    assert lines[-1].endswith(f"… and {40 - shown} more")
    lab = touching_labels(3)
    res = skelprune.prune(lab, labels=True)
    plain = res.render_overlay()
    with_legend = res.render_overlay(legend=True)
    assert with_legend.shape[1] == plain.shape[1] and with_legend.shape[0] > plain.shape[0]
    # each label's reconstructed part in its shade: touching labels differ
    a, b = (int(v) for v in np.unique(lab)[1:3])
    colour_a = {tuple(p) for p in plain[(lab == a) & res.mask].reshape(-1, 3)}
    colour_b = {tuple(p) for p in plain[(lab == b) & res.mask].reshape(-1, 3)}
    assert colour_a != colour_b
