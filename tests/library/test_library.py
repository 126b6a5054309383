"""Behaviour of the library: medial axis, pruning result, degenerate shapes, options."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from skimage.measure import euler_number, label

import skelprune
from skelprune.api import components
from skelprune.grid._open_edge import open_edge
from skelprune.grid._roughness import boundary_roughness
from skelprune.grid.medial_axis import DEGREE, SIMPLE, medial_axis, squared_distance
from skelprune.grid.reconstruction import reconstruction, reconstruction_error
from skelprune.pruning.choice import noise_depth
from skelprune.skeleton import Skeleton
from testkit.shapes import (
    blobs,
    dataset,
    load,
    rectangle_with_holes,
    touching_border,
    two_components,
)


def topology(mask: np.ndarray) -> tuple[int, int]:
    """(8-connected components, Euler number with 8-connected foreground)."""
    return int(label(mask, connectivity=2).max()), int(euler_number(mask, connectivity=2))


def skeleton_mask(res: skelprune.PruneResult) -> np.ndarray:
    rows, cols, _ = res.skeleton_points()
    out = np.zeros(res.mask.shape, bool)
    out[rows, cols] = True
    return out


# -- medial axis ------------------------------------------------------------------------


def test_medial_axis_reconstructs_datasets():
    """Target: median AR(M) <= 0.3 % on kimia216 (and on both sets together)."""
    ars: dict[str, list[float]] = {"kimia216": [], "kimia99": []}
    for name, values in ars.items():
        for path in dataset(name):
            for crop, _ in components(load(path)):
                ma = medial_axis(crop)
                values.append(reconstruction_error(crop, ma.rows, ma.cols, ma.r2))
    assert len(ars["kimia216"]) == 204 and len(ars["kimia99"]) == 99
    assert np.median(ars["kimia216"]) <= 0.003
    assert np.median(ars["kimia216"] + ars["kimia99"]) <= 0.003
    assert np.median(ars["kimia99"]) <= 0.005


@pytest.mark.parametrize(
    "make",
    [
        rectangle_with_holes,
        touching_border,
        two_components,
        lambda: blobs(7, holes=3),
        lambda: load(dataset("kimia216")[0]),
    ],
)
def test_medial_axis_is_thin_homotopic_and_exact_radii(make):
    for crop, _ in components(make()):
        r2 = squared_distance(crop)
        ma = medial_axis(crop, r2)
        skel = np.zeros_like(crop)
        skel[ma.rows, ma.cols] = True
        assert topology(skel) == topology(crop)
        assert skel[crop].sum() == skel.sum()  # inside the shape
        # one pixel thin: every simple point is an endpoint
        for r, c in zip(ma.rows, ma.cols, strict=True):
            code = sum(
                1 << i
                for i, (dr, dc) in enumerate(
                    [(-1, -1), (-1, 0), (-1, 1), (0, 1), (1, 1), (1, 0), (1, -1), (0, -1)]
                )
                if skel[r + dr, c + dc]
            )
            assert not (SIMPLE[code] and DEGREE[code] >= 2)
        # radii are exact squared distances to the nearest background pixel
        bg = np.argwhere(~crop)
        for k in range(0, len(ma.rows), max(1, len(ma.rows) // 20)):
            d2 = ((bg - [ma.rows[k], ma.cols[k]]) ** 2).sum(1).min()
            assert ma.r2[k] == d2


@pytest.mark.parametrize("name", ["kimia216", "kimia99"])
def test_medial_axis_end_branches_reach_the_boundary(name):
    """docs/algorithm.md: every end branch of M ends within a pixel or two of the boundary."""
    from skelprune.grid.graph import BranchGraph

    tips = []
    for path in dataset(name)[::3]:
        for crop, _ in components(load(path)):
            ma = medial_axis(crop)
            g = BranchGraph(ma.rows, ma.cols, crop.shape)
            tips += [int(ma.r2[g.endpoint(b)]) for b in g.end_branches()]
    assert len(tips) > 300
    assert max(tips) <= 2  # squared distance to the background: 1 or 2


def test_disks_of_all_shape_pixels_reconstruct_the_shape():
    crop = np.pad(blobs(3, holes=2), 1)
    r2 = squared_distance(crop)
    rows, cols = np.nonzero(crop)
    assert (reconstruction(crop.shape, rows, cols, r2[rows, cols]) == crop).all()


# -- results ----------------------------------------------------------------------------


def test_one_pixel_end_branches_keep_their_endpoint_nodes():
    m = np.zeros((12, 12), bool)
    m[5, 2:10] = True  # a plus: four one-pixel arms around a junction
    m[2:10, 5] = True
    comp = skelprune.prune(m).components[0]
    sk = comp.to_dict()["skeleton"]
    assert len(sk["endpoints"]) == comp.graph.n_endpoints() >= 2
    assert all(b["source"] != b["target"] for b in sk["branches"])


def test_rectangle_has_four_endpoints_and_small_error():
    m = np.zeros((70, 170), bool)
    m[5:65, 5:165] = True
    comp = skelprune.prune(m).to_dict()["components"][0]
    assert len(comp["skeleton"]["endpoints"]) == 4
    assert comp["rer"] < 0.02
    assert comp["alpha"] > 0


def test_document_is_plain_json_and_consistent():
    res = skelprune.prune(two_components())
    doc = res.to_dict(curve=True, overlay=True)
    assert json.loads(json.dumps(doc)) == doc
    assert doc["width"] == 80 and doc["height"] == 50 and len(doc["components"]) == 2
    for comp in doc["components"]:
        sk = comp["skeleton"]
        ids = {n["id"] for n in sk["nodes"]}
        assert all(b["source"] in ids and b["target"] in ids for b in sk["branches"])
        assert comp["curve"][comp["chosen_step"]]["objective"] == min(
            c["objective"] for c in comp["curve"]
        )
        assert abs(sum(b["length"] for b in sk["branches"]) - sk["length"]) < 1e-6
        # every point in exactly one branch or junction node
        pts = [tuple(p[:2]) for b in sk["branches"] for p in b["points"] + b["off_path"]]
        pts += [tuple(p[:2]) for n in sk["nodes"] if n["kind"] == "junction" for p in n["points"]]
        assert len(pts) == len(set(pts))


def test_frame_maps_coordinates_and_lengths():
    m = np.zeros((30, 60), bool)
    m[5:25, 5:55] = True
    res = skelprune.prune(m)
    plain = res.to_dict(curve=False)["components"][0]["skeleton"]
    frame = skelprune.io.frame.PixelFrame(x0=100.0, y0=50.0, pixel_size=0.5, flip_y=True)
    mapped = res.to_dict(curve=False, frame=frame)["components"][0]["skeleton"]
    n0, m0 = plain["nodes"][0], mapped["nodes"][0]
    assert m0["x"] == pytest.approx(100 + 0.5 * n0["x"])
    assert m0["y"] == pytest.approx(50 - 0.5 * n0["y"])
    assert m0["radius"] == pytest.approx(0.5 * n0["radius"])
    # rounded to the frame's decimals
    assert mapped["length"] == round(0.5 * plain["length"], frame.decimals)


def test_geojson_and_overlay():
    res = skelprune.prune(rectangle_with_holes())
    gj = res.to_geojson()
    kinds = {f["geometry"]["type"] for f in gj["features"]}
    assert gj["type"] == "FeatureCollection" and kinds == {"LineString", "Point"}
    img = res.render_overlay()
    assert img.shape == (*res.mask.shape, 3)
    assert res.overlay_png()[:8] == b"\x89PNG\r\n\x1a\n"


# -- degenerate shapes and options ------------------------------------------------------


@pytest.mark.parametrize(
    "name,mask",
    [
        ("one pixel", np.pad(np.ones((1, 1), bool), 3)),
        ("one-pixel line", np.pad(np.ones((1, 20), bool), 3)),
        ("two pixels", np.pad(np.ones((1, 2), bool), 3)),
        ("disk", np.hypot(*np.mgrid[-15:16, -15:16]) < 12),
        ("all foreground", np.ones((25, 40), bool)),
        ("single pixel image", np.ones((1, 1), bool)),
    ],
)
def test_degenerate_shapes_never_raise(name, mask):
    res = skelprune.prune(mask)
    doc = res.to_dict()
    assert len(doc["components"]) == 1
    comp = doc["components"][0]
    assert comp["rer"] <= 0.2
    assert skeleton_mask(res).any()
    if name in ("one pixel", "one-pixel line", "two pixels"):
        assert comp["chosen_step"] == 0  # nothing to prune
        # a single point has no α; a single path has one (its two end paths)
        assert (comp["alpha"] is None) == (name == "one pixel")
        assert len(doc["components"][0]["skeleton"]["endpoints"]) == (
            1 if name == "one pixel" else 2
        )


def test_empty_mask_is_a_clear_error():
    with pytest.raises(skelprune.EmptyMaskError, match="no foreground"):
        skelprune.prune(np.zeros((10, 10), bool))


@pytest.mark.parametrize(
    "kwargs",
    [
        {"beta": 0},
        {"beta": -1.0},
        {"beta": float("nan")},
        {"beta": float("inf")},
        {"method": "magic"},
        {"coarse": "wavelet"},
    ],
)
def test_bad_options_are_clear_errors(kwargs):
    with pytest.raises(skelprune.InvalidOptionError):
        skelprune.prune(np.ones((5, 5), bool), **kwargs)


# -- properties on random shapes --------------------------------------------------------

shapes = st.builds(
    blobs,
    seed=st.integers(0, 10_000),
    size=st.integers(20, 48),
    n=st.integers(1, 5),
    holes=st.integers(0, 2),
)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mask=shapes)
def test_pruned_skeleton_properties(mask):
    if not mask.any():
        return
    res = skelprune.prune(mask)
    again = skelprune.prune(mask)
    assert res.to_dict() == again.to_dict()  # deterministic
    skel = skeleton_mask(res)
    # a subset of the medial axis of each component (where a component runs off the
    # image, the axis of the shape going on across the border)
    for comp, (crop, origin) in zip(res.components, components(mask), strict=True):
        noise = noise_depth(boundary_roughness(crop), 1.0)
        if open_edge(crop, origin, mask.shape, noise) is None:
            m_axis = medial_axis(crop)
            ma_rows, ma_cols = m_axis.rows + origin[0], m_axis.cols + origin[1]
        else:
            axis = Skeleton.medial_axis(crop, origin, mask.shape)
            ma_rows, ma_cols = axis.image_coordinates(axis.rows, axis.cols)
        ma = np.zeros(mask.shape, bool)
        ma[np.asarray(ma_rows, int), np.asarray(ma_cols, int)] = True
        rows, cols, _ = comp.points()
        assert ma[rows, cols].all()
    # components and cycles (holes) are kept
    assert topology(skel) == topology(mask)
    # the reported RER is what the returned points and radii reconstruct
    doc = res.to_dict(curve=False)
    for comp, cdoc in zip(res.components, doc["components"], strict=True):
        assert len(cdoc["skeleton"]["endpoints"]) == comp.graph.n_endpoints()
    for cdoc in doc["components"]:
        pts = [p for b in cdoc["skeleton"]["branches"] for p in b["points"] + b["off_path"]]
        pts += [p for n in cdoc["skeleton"]["nodes"] for p in n["points"]]
        rows = np.array([int(p[1]) for p in pts])
        cols = np.array([int(p[0]) for p in pts])
        r2 = np.array([round(p[2] ** 2) for p in pts])
        rec = reconstruction((mask.shape[0] + 2, mask.shape[1] + 2), rows + 1, cols + 1, r2)
        cmask = np.zeros_like(rec)
        comp_pixels = label(mask, connectivity=2)
        k = comp_pixels[rows[0], cols[0]]
        cmask[1:-1, 1:-1] = comp_pixels == k
        ar = (cmask & ~rec).sum() / cmask.sum()
        assert ar == pytest.approx(cdoc["rer"], abs=1e-12)


def test_overlay_scale_keeps_the_mask_crisp_and_grows_the_marks():
    from skelprune.output.render import COLOURS

    res = skelprune.prune(rectangle_with_holes())
    plain = res.render_overlay()
    big = res.render_overlay(scale=4)
    assert big.shape == (plain.shape[0] * 4, plain.shape[1] * 4, 3)
    # nearest neighbour: every input pixel that is not a node is a 4 × 4 block of its colour
    blocks = big.reshape(plain.shape[0], 4, plain.shape[1], 4, 3)
    uniform = (blocks == blocks[:, :1, :, :1]).all(axis=(1, 3, 4))
    assert uniform.mean() > 0.97
    endpoint = np.array(COLOURS["endpoint"], np.uint8)
    # markers scale with the picture (a disc 1.5 input pixels in radius, not a 3 × 3 dot)
    assert (big == endpoint).all(-1).sum() > 10 * (plain == endpoint).all(-1).sum()
    legend = res.render_overlay(scale=4, legend=True)
    assert legend.shape[1] == big.shape[1] and legend.shape[0] > big.shape[0]
    assert res.overlay_png()[:8] == b"\x89PNG\r\n\x1a\n"


def test_frame_none_is_the_image_frame():
    res = skelprune.prune(rectangle_with_holes())
    assert res.to_dict(frame=None) == res.to_dict()
    assert res.to_geojson(frame=None) == res.to_geojson()
