"""The branch table and its views: the document's skeleton and sequence, the networkx
graph and the lines, against the point-by-point reference on every Kimia shape; the
documents against the library's own schema."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image

import skelprune
from skelprune.io.frame import IDENTITY, PixelFrame
from skelprune.output.schema import PruneDocument, SkeletonGeoJSON, problems
from skelprune.output.table import round_like_python
from testkit.document_oracle import branch_line, component_dict, volume_skeleton_dict
from testkit.shapes import dataset

#: A frame with a flip, an offset and a pixel size whose products need rounding.
FRAME = PixelFrame(x0=1.5, y0=-2.25, pixel_size=0.37, flip_y=True)
SHAPES = dataset("kimia216") + dataset("kimia99")


def _mask(path) -> np.ndarray:
    return np.asarray(Image.open(path).convert("L")) >= 128


def _same(a: object, b: object) -> bool:
    # as JSON: 1 and 1.0 differ there, and must not swap
    return json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)


@pytest.mark.parametrize("frame", [IDENTITY, FRAME], ids=["pixels", "framed"])
def test_views_equal_the_point_by_point_document_on_every_kimia_shape(frame) -> None:
    for path in SHAPES:
        res = skelprune.prune(_mask(path), coarse=None if path.stem.endswith("1") else "dce")
        for comp in res.components:
            doc = comp.to_dict(frame=frame, sequence=True)
            ref = component_dict(comp, frame)
            sk, seq = doc["skeleton"], dict(doc["sequence"])
            assert _same(sk["nodes"], ref["nodes"]), path.stem
            assert _same(sk["branches"], ref["branches"]), path.stem
            assert sk["endpoints"] == [n["id"] for n in ref["nodes"] if n["kind"] == "endpoint"]
            del seq["frame"]
            assert _same(seq, ref["sequence"]), path.stem
            lines = [ln.tolist() for ln in comp.table.framed(frame).lines()]
            assert lines == [branch_line(ref["nodes"], b) for b in ref["branches"]], path.stem


def test_the_table_is_flat_and_consistent() -> None:
    res = skelprune.prune(_mask(dataset("kimia216")[5]))
    t = res.components[0].table
    assert t.path_offsets[0] == 0 and t.path_offsets[-1] == t.paths.size
    assert np.all(np.diff(t.path_offsets) >= 1)  # every branch has a path
    assert t.source.size == t.target.size == t.length.size == t.n_branches
    # consecutive path pixels are 8-neighbours, in image coordinates
    for j in range(t.n_branches):
        p = t.path(j)
        assert np.all(np.abs(np.diff(p[:, :2], axis=0)) <= 1)
    # the identity frame is no copy; another maps the coordinates, not the topology
    assert t.framed(IDENTITY) is t
    f = t.framed(FRAME)
    assert np.array_equal(f.source, t.source) and np.array_equal(f.paths, t.paths)
    assert f.x[0] == FRAME.point(t.x[0], t.y[0])[0] and f.radius[3] == FRAME.distance(t.radius[3])


def test_networkx_is_a_view_of_the_table() -> None:
    res = skelprune.prune(_mask(dataset("kimia216")[40]))
    g = res.to_networkx(frame=FRAME)
    ref = component_dict(res.components[0], FRAME)
    assert g.number_of_nodes() == len(ref["nodes"])
    for b in ref["branches"]:
        data = g.get_edge_data((0, b["source"]), (0, b["target"]), key=b["id"])
        assert data["points"] == b["points"] and data["line"] == branch_line(ref["nodes"], b)


def test_documents_conform_to_the_library_schema() -> None:
    for path in dataset("kimia216")[::20]:
        res = skelprune.prune(_mask(path))
        assert problems(res.to_dict(sequence=True, overlay=True)) == []
        assert problems(res.to_dict(curve=False), PruneDocument) == []
        assert problems(res.to_geojson(cut_ends=True), SkeletonGeoJSON) == []
    polygon = {"type": "Polygon", "coordinates": [[[0, 0], [30, 0], [30, 8], [0, 8], [0, 0]]]}
    res = skelprune.prune(polygon)
    doc = res.to_dict(sequence=True)
    assert "raster" in doc and problems(doc) == []
    assert problems(res.to_geojson(), SkeletonGeoJSON) == []


def test_one_schema_holds_an_images_and_a_volumes_document() -> None:
    """The one document schema: real volume documents (labels, anisotropic voxels, a
    loop with null ends, a lone voxel) and real image documents conform; a volume's
    node without ``z`` or with a three-number point does not."""
    for name, (volume, spacing) in _volumes().items():
        for opts in ({}, {"trim": False, "min_margin": 0}):
            doc = json.loads(json.dumps(skelprune.prune(volume, spacing=spacing, **opts).to_dict()))
            assert problems(doc) == [], name
    labels = np.zeros((40, 60), np.uint8)
    labels[5:35, 5:28], labels[5:35, 32:55] = 3, 7
    ring = np.zeros((40, 60), bool)
    ring[5:35, 5:55], ring[15:25, 20:40] = True, False
    for image, opts in ((labels, {"labels": True}), (ring, {})):
        doc = skelprune.prune(image, **opts).to_dict(sequence=True)
        assert problems(json.loads(json.dumps(doc))) == []
    doc = skelprune.prune(_volumes()["tree0-iso"][0]).to_dict()
    node = doc["components"][0]["skeleton"]["nodes"][0]
    del node["z"]
    node["points"] = [[1.0, 2.0, 3.0, 4.0, 5.0]]
    found = problems(doc)
    assert "$.components[0].skeleton.nodes[0].points[0]: length 5 outside [3, 4]" in found


def test_the_schema_check_finds_what_departs() -> None:
    m = np.zeros((20, 40), bool)
    m[5:15, 5:35] = True
    doc = skelprune.prune(m).to_dict()
    comp = doc["components"][0]
    comp["skeleton"]["nodes"][0]["kind"] = "fork"
    comp["skeleton"]["branches"][0]["points"][0] = [1.0, 2.0]
    comp["rer"] = True
    del comp["chosen_step"]
    doc["extra"] = 1
    doc["beta"] = float("nan")
    found = problems(doc)
    assert len(found) == 6, found
    assert any("unknown key extra" in p for p in found)
    assert any("missing key chosen_step" in p for p in found)
    assert any(".points[0]: length 2" in p for p in found)


def test_frame_rounding_is_pythons_round_exactly() -> None:
    rng = np.random.default_rng(7)
    for n in range(0, 9):
        v = rng.normal(0, 10.0 ** rng.integers(-3, 6), 20000)
        # decimal halves and their neighbours: where scaled rounding goes wrong
        half = (np.round(v * 10**n) + 0.5) / 10**n
        for a in (v, half, np.nextafter(half, np.inf), np.nextafter(half, -np.inf), -half):
            got = round_like_python(a, n)
            want = np.array([round(x, n) for x in a.tolist()])
            assert np.array_equal(got, want) and np.array_equal(np.signbit(got), np.signbit(want))
    assert round_like_python(np.array([1234.5]), -1).tolist() == [round(1234.5, -1)]


def _volumes() -> dict[str, tuple[np.ndarray, tuple[float, float, float]]]:
    from testkit.volume_snapshot import volumes

    out = volumes(quick=True)
    lone = np.zeros((5, 5, 5), bool)
    lone[2, 2, 2] = True
    zz, yy, xx = np.mgrid[:9, :15, :15]
    rr = np.hypot(yy - 7, xx - 7)
    out["lone"] = (lone, (1.0, 1.0, 1.0))
    out["ring"] = ((rr > 3.5) & (rr < 6) & (abs(zz - 4) <= 1), (1.0, 1.0, 1.0))
    return out


def test_a_volume_reads_the_one_branch_table_with_a_z_column() -> None:
    """A volume's answer is the image's table with ``z``: its document part equals the
    voxel-by-voxel walk (loops without a node, lone voxels one node, the graph's branch
    ids), its SWC lists the table's points, its CSV one row a table branch."""
    seen = {"loop": 0, "lone": 0, "junction": 0}
    for name, (volume, spacing) in _volumes().items():
        res = skelprune.prune(volume, spacing=spacing, trim=name != "ring")
        rows = res.summary()
        assert len(rows) == sum(c.table.n_branches for c in res.components), name
        swc = [ln for ln in res.to_swc().splitlines() if not ln.startswith("#")]
        assert len(swc) == sum(c.table.pixels().size for c in res.components), name
        for comp in res.components:
            t = comp.table
            assert t.ndim == 3 and t.coordinates().shape == (t.x.size, 3)
            assert t.xyr().shape == (t.x.size, 4)
            doc = comp.to_dict()["skeleton"]
            ref = volume_skeleton_dict(comp)
            assert _same([doc["nodes"], doc["branches"]], [ref["nodes"], ref["branches"]]), name
            seen["loop"] += int((t.source < 0).sum())
            seen["lone"] += int(np.sum(np.diff(t.path_offsets) == 1))
            seen["junction"] += int(np.sum(t.node_kind == 1))
            assert np.array_equal(t.source < 0, t.target < 0)
    assert all(seen.values()), seen  # every case met


def test_a_volume_table_has_no_frame() -> None:
    v = np.zeros((12, 14, 40), bool)
    v[3:9, 4:10, 3:37] = True
    t = skelprune.prune(v).components[0].table
    assert t.framed(IDENTITY) is t
    with pytest.raises(ValueError, match="volume"):
        t.framed(FRAME)
