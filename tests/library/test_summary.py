"""The branch and component tables, on shapes whose numbers are known, and the exports
(CSV, GraphML, the skeleton image and its hand-over to skan)."""

from __future__ import annotations

import io
import math

import numpy as np
import pytest

import skelprune
from skelprune.output.summary import BRANCH_COLUMNS, COMPONENT_COLUMNS


def capsule_segments(segments, w, shape):
    """The union of round-ended strokes of width ``w`` along ``segments``."""
    m = np.zeros(shape, bool)
    yy, xx = np.mgrid[: shape[0], : shape[1]]
    for (x0, y0), (x1, y1) in segments:
        d = np.array([x1 - x0, y1 - y0], float)
        length = np.hypot(*d)
        u = d / length
        px, py = xx - x0, yy - y0
        t = np.clip(px * u[0] + py * u[1], 0, length)
        m |= np.hypot(px - t * u[0], py - t * u[1]) <= w / 2
    return m


def band(w: int, length: int = 300) -> np.ndarray:
    """A straight band ``w`` pixels wide with round ends."""
    h = 80
    m = np.zeros((h, length + 2 * w + 20), bool)
    top = h // 2 - w // 2
    m[top : top + w, w + 10 : w + 10 + length] = True
    yy, xx = np.mgrid[: m.shape[0], : m.shape[1]]
    for x in (w + 10, w + 9 + length):
        m |= (yy - (top + (w - 1) / 2)) ** 2 + (xx - x) ** 2 < (w / 2) ** 2
    return m


def half_annulus(radius: int = 150, width: int = 21) -> np.ndarray:
    """The lower half of a ring (centre line of radius ``radius``), with round ends."""
    h, w = radius + width + 20, 2 * radius + 2 * width + 20
    yy, xx = np.mgrid[:h, :w]
    cy, cx = 10 + width, w / 2
    d = np.hypot(yy - cy, xx - cx)
    m = (d < radius + width / 2) & (d > radius - width / 2) & (yy >= cy)
    for x in (cx - radius, cx + radius):
        m |= (yy - cy) ** 2 + (xx - x) ** 2 < (width / 2) ** 2
    return m


def longest(rows):
    return rows.loc[rows["length"].idxmax()]


@pytest.mark.parametrize("w", [6, 9, 12, 15, 16])
def test_straight_band_width_and_tortuosity(w):
    rows = skelprune.prune(band(w)).summary()
    main = longest(rows)
    assert abs(main["width_mean"] - w) <= 1.0
    assert abs(main["tortuosity"] - 1.0) <= 0.01
    assert main["chord"] <= main["length"]
    assert abs(main["angle_source"]) < 3 or abs(abs(main["angle_source"]) - 180) < 3


def test_half_annulus_tortuosity_is_half_pi():
    rows = skelprune.prune(half_annulus()).summary()
    main = longest(rows)
    assert main["tortuosity"] == pytest.approx(math.pi / 2, rel=0.02)
    # the arc's centre line: π·R long, within 2 %
    assert main["length"] == pytest.approx(math.pi * 150, rel=0.02)


def y_shape(angles, arm=90, w=11, n=260):
    c = (n / 2, n / 2)
    ends = [
        (c[0] + arm * math.cos(math.radians(a)), c[1] - arm * math.sin(math.radians(a)))
        for a in angles
    ]
    return capsule_segments([(c, e) for e in ends], w, (n, n))


def angle_gap(a, b):
    return abs((a - b + 180.0) % 360.0 - 180.0)


@pytest.mark.parametrize("angles", [(90, 210, 330), (0, 100, 230), (20, 150, 250)])
def test_y_angles(angles):
    rows = skelprune.prune(y_shape(angles)).summary()
    assert len(rows) == 3 and set(rows["kind"]) == {"end-junction"}
    for _, row in rows.iterrows():
        at_junction = "source" if row["junction_angle_source"] is not None else "target"
        leaving = row[f"angle_{at_junction}"]
        arm = min(angles, key=lambda a: angle_gap(a, leaving))
        assert angle_gap(arm, leaving) <= 3.0
        expected = min(angle_gap(arm, other) for other in angles if other != arm)
        assert abs(row[f"junction_angle_{at_junction}"] - expected) <= 3.0
        end = "target" if at_junction == "source" else "source"
        assert row[f"junction_angle_{end}"] is None  # null at an end
        assert angle_gap(row[f"angle_{end}"], arm + 180) <= 3.0
        assert row["strahler"] == 1


def tree():
    """An H of H's: a centre stroke, each end forking in two, each fork in two again."""
    segs = []
    centre = ((150, 150), (250, 150))
    segs.append(centre)
    for x, dx in ((150, -1), (250, 1)):
        for dy in (-1, 1):
            mid = (x + dx * 60, 150 + dy * 60)
            segs.append(((x, 150), mid))
            for ex, ey in ((dx * 60, 0), (0, dy * 60)):
                segs.append((mid, (mid[0] + ex, mid[1] + ey)))
    return capsule_segments(segs, 9, (300, 400))


def test_strahler_orders_of_a_known_tree():
    rows = skelprune.prune(tree()).summary()
    assert len(rows) == 13
    kinds = rows["kind"].tolist()
    orders = rows["strahler"].tolist()
    assert sorted(o for k, o in zip(kinds, orders, strict=True) if k == "end-junction") == [1] * 8
    inner = [
        (o, r["length"])
        for (_, r), k, o in zip(rows.iterrows(), kinds, orders, strict=True)
        if k == "junction-junction"
    ]
    # the centre stroke (100 px) is 3, the four forks (85 px) 2
    assert sorted(inner, key=lambda p: p[1])[-1][0] == 3
    assert sorted(o for o, _ in inner) == [2, 2, 2, 2, 3]


def test_strahler_orders_of_a_network_with_a_cycle_are_its_widest_trees():
    # the H of H's with a thin vessel joining two of its tips: one cycle
    m = tree() | capsule_segments([((30, 90), (30, 210))], 5, (300, 400))
    rows = skelprune.prune(m).summary()
    assert int(skelprune.prune(m).summary("component")["cycles"][0]) == 1
    narrow = rows["width_mean"].idxmin()
    assert rows["width_mean"][narrow] < 9  # the thin vessel (the tree is 10 px wide): no order
    assert rows["strahler"].isna().tolist() == [j == narrow for j in range(len(rows))]
    orders = rows["strahler"].dropna().astype(int)
    assert orders[rows["kind"] == "end-junction"].eq(1).all()
    # the thin vessel and the two tips it joins are one branch of the cycle, dropped:
    # the left H's forks keep one end each (order 1), the right H's two (order 2), and
    # the centre takes the larger
    inner = rows[(rows["kind"] == "junction-junction") & rows["strahler"].notna()]
    assert inner.sort_values("length")["strahler"].iloc[-1] == 2
    assert sorted(inner["strahler"][inner["length"] > 80].astype(int)) == [1, 1, 2, 2, 2]


def test_strahler_of_a_ring_drops_one_side():
    m = np.zeros((80, 80), bool)
    m[10:70, 10:70] = True
    m[30:50, 30:50] = False
    rows = skelprune.prune(m).summary()
    assert int(skelprune.prune(m).summary("component")["cycles"][0]) == 1
    assert rows["strahler"].isna().sum() == 1  # the cycle's one branch off the tree
    assert rows["strahler"][rows["kind"] == "end-junction"].eq(1).all()


def test_tables_columns_units_and_csv():
    res = skelprune.prune(y_shape((90, 210, 330)))
    rows = res.summary()
    assert tuple(rows.columns) == BRANCH_COLUMNS and rows.attrs["unit"] == "px"
    comp = res.summary("component")
    assert tuple(comp.columns) == COMPONENT_COLUMNS
    assert int(comp["branches"][0]) == 3 and int(comp["ends"][0]) == 3
    assert int(comp["junctions"][0]) == 1 and int(comp["cycles"][0]) == 0
    assert comp["length"][0] == pytest.approx(rows["length"].sum())
    text = res.to_csv()
    import csv

    parsed = list(csv.DictReader(io.StringIO(text)))
    assert len(parsed) == 3 and list(parsed[0]) == list(BRANCH_COLUMNS)
    assert float(parsed[0]["length"]) == pytest.approx(rows["length"][0])
    assert parsed[0]["label"] == ""  # null
    # a pixel size for an image scales lengths and widths, not angles or orders
    scaled = skelprune.prune(y_shape((90, 210, 330)), pixel_size=0.5).summary()
    assert scaled["length"].tolist() == pytest.approx((rows["length"] * 0.5).tolist())
    assert scaled["width_mean"].tolist() == pytest.approx((rows["width_mean"] * 0.5).tolist())
    assert scaled["angle_source"].tolist() == pytest.approx(rows["angle_source"].tolist())
    assert set(scaled["unit"]) == {"pixel_size"}
    with pytest.raises(ValueError, match="level"):
        res.summary("pixel")


def test_summary_without_pandas_is_rows(monkeypatch):
    import builtins

    real = builtins.__import__

    def no_pandas(name, *args, **kwargs):
        if name == "pandas":
            raise ImportError(name)
        return real(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_pandas)
    rows = skelprune.prune(band(9)).summary()
    assert isinstance(rows, list) and set(rows[0]) == set(BRANCH_COLUMNS)


def test_polygon_tables_are_in_its_units():
    strip = {"type": "Polygon", "coordinates": [[[0, 0], [1000, 0], [1000, 20], [0, 20], [0, 0]]]}
    res = skelprune.prune(strip)
    rows = res.summary()
    main = longest(rows)
    assert set(rows["unit"]) == {"polygon"}
    assert main["width_mean"] == pytest.approx(20, abs=2 * res.frame.pixel_size + 1e-9)


def test_graphml_reads_back_as_the_skeleton():
    nx = pytest.importorskip("networkx")
    res = skelprune.prune(tree())
    g = nx.read_graphml(io.StringIO(res.to_graphml()))
    ref = res.to_networkx()
    assert g.number_of_nodes() == ref.number_of_nodes()
    assert g.number_of_edges() == ref.number_of_edges()
    rows = res.summary()
    lengths = sorted(d["length"] for *_, d in g.edges(data=True))
    assert lengths == pytest.approx(sorted(rows["length"]))
    kinds = sorted(d["kind"] for _, d in g.nodes(data=True))
    assert kinds.count("junction") == 6 and kinds.count("endpoint") == 8


def test_skeleton_mask_and_the_hand_over_to_skan():
    res = skelprune.prune(tree())
    mask = res.skeleton_mask()
    rows, cols, _ = res.skeleton_points()
    assert mask.dtype == bool and mask.shape == res.mask.shape
    assert int(mask.sum()) == rows.size and mask[rows, cols].all()
    skan = pytest.importorskip("skan")
    # the hand-over, as docs/tables.md gives it
    skeleton = skan.Skeleton(res.skeleton_mask())
    branches = skan.summarize(skeleton, separator="_")
    assert len(branches) >= res.summary()["branch"].size - 1
    total = branches["branch_distance"].sum()
    assert total == pytest.approx(res.summary()["length"].sum(), rel=0.1)
