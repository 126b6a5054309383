"""Pruning volumes: the sequence against a naive oracle that repaints from scratch, and
the 3-D document, table, networkx, SWC and overlay (docs/volumes.md)."""

from __future__ import annotations

import sys

import numpy as np
import pytest
from scipy import ndimage

import skelprune
from skelprune.errors import ImageTooLargeError, InvalidImageError, InvalidOptionError
from skelprune.grid3d.skeleton import VolumeSkeleton
from skelprune.pruning.bayesian import pruning_sequence
from testkit import volume_oracle as oracle
from testkit.volumes import random_tree, tube, y_tubes

SPACINGS = [(1.0, 1.0, 1.0), (3.0, 1.0, 1.0), (0.7, 1.3, 0.4)]


def largest(v: np.ndarray) -> np.ndarray:
    lab, _ = ndimage.label(v, np.ones((3, 3, 3)))
    return lab == np.argmax(np.bincount(lab.ravel())[1:]) + 1


def cases() -> list[tuple[str, np.ndarray]]:
    out = []
    for seed in range(2):
        out.append((f"tree{seed}", random_tree(seed, size=48, depth=2).volume(0.7, seed)))
        noise = np.random.default_rng(seed).random((9, 10, 11)) < 0.55
        out.append((f"noise{seed}", largest(noise)))
    return out


CASES = cases()


@pytest.mark.parametrize("spacing", SPACINGS)
@pytest.mark.parametrize("name", [name for name, _ in CASES])
def test_sequence_matches_the_oracle_that_repaints(name, spacing) -> None:
    volume = dict(CASES)[name]
    sk = VolumeSkeleton.curve_skeleton(volume, spacing)
    norm = sk.normalisation(9.0)
    assert norm.alpha is not None
    seq = pruning_sequence(sk, norm.alpha, norm.lbar)
    order, lams = oracle.naive_sequence(
        sk.working_graph(), sk.volume, sk.z, sk.y, sk.x, sk.r2, spacing, norm.alpha, norm.lbar
    )
    assert seq.removed == order
    assert seq.objective.tolist() == lams
    # the lost volume of every step, painted from scratch
    for k in (0, len(seq.removed) // 2, len(seq.removed)):
        at = seq.skeleton_at(k)
        idx = at.points()
        lost = oracle.lost_volume(sk.volume, sk.z[idx], sk.y[idx], sk.x[idx], sk.r2[idx], spacing)
        assert seq.lost[k] == lost


def test_some_cases_remove_branches_and_merge() -> None:
    """The oracle comparison above is not vacuous: branches go, junctions dissolve."""
    removed = merges = 0
    for _, volume in CASES:
        sk = VolumeSkeleton.curve_skeleton(volume)
        norm = sk.normalisation(9.0)
        seq = pruning_sequence(sk, norm.alpha, norm.lbar)
        removed += len(seq.removed)
        merges += sum(seq.log.merge(i) is not None for i in range(len(seq.log)))
    assert removed >= 6 and merges >= 3


def test_document_has_z_spacing_and_physical_lengths() -> None:
    bar = tube(length=30.0, radius=3.0).volume()  # along x, the last axis
    doc = skelprune.prune(bar).to_dict()
    assert doc["dimensions"] == 3 and doc["spacing"] == [1.0, 1.0, 1.0]
    assert (doc["depth"], doc["height"], doc["width"]) == bar.shape
    comp = doc["components"][0]
    (branch,) = comp["skeleton"]["branches"]
    pts = np.array(branch["points"])
    assert pts.shape[1] == 4
    assert np.ptp(pts[:, 0]) > 20 and np.ptp(pts[:, 1]) <= 1 and np.ptp(pts[:, 2]) <= 1
    assert {"x", "y", "z", "radius"} <= set(comp["skeleton"]["nodes"][0])
    # the same bar along z, slices twice as thick: the same physical length
    along_z = np.ascontiguousarray(np.transpose(bar, (2, 1, 0))[::2])
    doc2 = skelprune.prune(along_z, spacing=(2.0, 1.0, 1.0)).to_dict()
    (branch2,) = doc2["components"][0]["skeleton"]["branches"]
    assert doc2["spacing"] == [2.0, 1.0, 1.0]
    assert branch2["length"] == pytest.approx(branch["length"], abs=2.5)
    assert np.ptp(np.array(branch2["points"])[:, 2]) > 10  # z varies: the first axis


def test_npy_path_labels_table_networkx_swc_and_overlay(tmp_path) -> None:
    vol = np.zeros((20, 20, 40), np.uint8)
    vol[3:9, 3:9, 3:37] = 2
    vol[12:18, 12:18, 3:37] = 5
    path = tmp_path / "vol.npy"
    np.save(path, vol)
    res = skelprune.prune(str(path), spacing=(1.0, 1.0, 0.5))
    doc = res.to_dict()
    assert [c["label"] for c in doc["components"]] == [2, 5]
    table = res.summary()
    assert list(table["label"]) == [2, 5]
    lengths = [c["skeleton"]["branches"][0]["length"] for c in doc["components"]]
    assert table["length"].tolist() == lengths
    assert all(12 < v < 17 for v in lengths)  # about 30 voxels of 0.5
    assert table["max_width"].max() <= 6.0 + 1e-9
    g = res.to_networkx()
    assert g.number_of_nodes() == 4 and g.number_of_edges() == 2
    swc = [line.split() for line in res.to_swc().splitlines() if not line.startswith("#")]
    n_points = sum(c.skeleton.n_points for c in res.components)
    assert len(swc) == n_points
    ids = [int(r[0]) for r in swc]
    parents = [int(r[6]) for r in swc]
    assert ids == list(range(1, n_points + 1))
    assert parents.count(-1) == 2 and all(p < i for i, p in zip(ids, parents, strict=True))
    img = res.render_overlay()
    # voxels drawn in their physical proportions: z and y twice as long as x
    assert img.shape == (2 * 20 + 4 + 2 * 20, 40 + 4 + 2 * 20, 3)
    assert ((img == (210, 20, 20)).all(-1)).any()


def test_volume_refusals(tmp_path) -> None:
    bar = tube(length=20.0, radius=2.0).volume()
    res = skelprune.prune(bar)
    with pytest.raises(InvalidOptionError, match="GeoJSON") as refused:
        res.to_geojson(simplify=1.0)
    said = str(refused.value)
    assert "map coordinates" in said and "SWC" in said and "CSV" in said
    with pytest.raises(InvalidOptionError) as encoded:
        skelprune.encode(res, "geojson")
    assert str(encoded.value) == said  # one wording
    with pytest.raises(InvalidOptionError, match="images only"):
        skelprune.prune(bar, method="dce")
    with pytest.raises(InvalidOptionError, match="images only"):
        skelprune.prune(bar, scope="local")
    with pytest.raises(InvalidOptionError, match="spacing"):
        skelprune.prune(bar, spacing=(1.0, -1.0, 1.0))
    with pytest.raises(InvalidImageError, match="3-D"):
        skelprune.prune(np.zeros((3, 3)), spacing=(1, 1, 1))
    with pytest.raises(InvalidImageError, match="booleans or integer"):
        skelprune.prune(bar.astype(float))
    bad = tmp_path / "bad.npy"
    bad.write_bytes(b"not an array")
    with pytest.raises(InvalidImageError, match="npy"):
        skelprune.prune(str(bad))
    # the same refusal, in the same words, as the service's and a data-set run's
    with pytest.raises(InvalidOptionError, match="foreground only apply to image input"):
        skelprune.prune(bar, foreground="zero")


def body_with_arms(spacing) -> np.ndarray:
    """A ball of radius 7 with three thin arms (radius 2) reaching far out of it."""
    shape = tuple(round(e / s) for e, s in zip((18, 44, 44), spacing, strict=True))
    zz, yy, xx = (g * s for g, s in zip(np.indices(shape).astype(float), spacing, strict=True))
    v = (zz - 9) ** 2 + (yy - 20) ** 2 + (xx - 22) ** 2 < 7**2
    v |= ((zz - 9) ** 2 + (yy - 20) ** 2 < 4) & (xx > 2) & (xx < 42)
    v |= ((zz - 9) ** 2 + (xx - 22) ** 2 < 4) & (yy > 20) & (yy < 42)
    return v


@pytest.mark.parametrize("spacing", [(1.0, 1.0, 1.0), (0.7, 1.3, 0.4)])
def test_limbs_are_kept_and_the_oracle_agrees(spacing, monkeypatch) -> None:
    sk = VolumeSkeleton.curve_skeleton(body_with_arms(spacing), spacing)
    norm = sk.normalisation(9.0)
    assert len(sk.end_branches()) == 3
    seq = pruning_sequence(sk, norm.alpha, norm.lbar)
    order, lams = oracle.naive_sequence(
        sk.working_graph(), sk.volume, sk.z, sk.y, sk.x, sk.r2, spacing, norm.alpha, norm.lbar
    )
    assert seq.removed == order == []  # every arm is a limb
    assert seq.objective.tolist() == lams
    # without the limb test, the trade-off alone removes arms
    monkeypatch.setattr(VolumeSkeleton, "limb_test", lambda self, graph: None)
    assert pruning_sequence(sk, norm.alpha, norm.lbar).removed


def test_a_voxel_a_torus_and_a_hollow_ball_give_documents() -> None:
    from testkit.volumes import ball, torus

    voxel = np.zeros((3, 3, 3), bool)
    voxel[1, 1, 1] = True
    (comp,) = skelprune.prune(voxel, spacing=(1, 1, 1)).to_dict()["components"]
    assert len(comp["skeleton"]["endpoints"]) == 1 and comp["steps"] == 0
    assert comp["skeleton"]["branches"][0]["points"] == [[1.0, 1.0, 1.0, 1.0]]

    res = skelprune.prune(torus().volume())
    (comp,) = res.to_dict()["components"]
    (loop,) = comp["skeleton"]["branches"]  # one tunnel: one cycle, nothing to prune
    assert loop["source"] is None and comp["skeleton"]["endpoints"] == []
    g = res.to_networkx()
    assert g.number_of_edges() == 1 and nx_self_loops(g) == 1
    swc = [line.split() for line in res.to_swc().splitlines()[1:]]
    assert [r[6] for r in swc].count("-1") == 1  # a tree: of the cycle one step left out

    shell = ball(8.0).volume() & ~ndimage.binary_erosion(ball(8.0).volume(), iterations=3)
    doc = skelprune.prune(shell).to_dict()  # a cavity: a closed shell, one branch
    assert len(doc["components"][0]["skeleton"]["branches"]) == 1


def nx_self_loops(g) -> int:
    import networkx as nx

    return nx.number_of_selfloops(g)


def test_colour_image_arrays_stay_images_unless_spacing_is_given() -> None:
    rgb = np.zeros((20, 30, 3), np.uint8)
    rgb[5:15, 5:25] = 255
    assert type(skelprune.prune(rgb)).__name__ == "PruneResult"
    thin = np.zeros((20, 30, 3), bool)
    thin[5:15, 5:25, 1] = True
    res = skelprune.prune(thin, spacing=(1, 1, 1))
    assert res.to_dict()["dimensions"] == 3


def test_tips_cuts_match_the_oracle_that_repaints() -> None:
    from skelprune.grid3d.tips import trim_volume_tips
    from skelprune.pruning.bayesian import target
    from skelprune.pruning.choice import choose_step

    made = 0
    for spacing in SPACINGS:
        for _, volume in [*CASES, ("arms", body_with_arms(spacing))]:
            sk = VolumeSkeleton.curve_skeleton(volume, spacing)
            norm = sk.normalisation(9.0)
            seq = pruning_sequence(sk, norm.alpha, norm.lbar)
            chosen = choose_step(seq.objective)
            answer = seq.skeleton_at(chosen)
            fast = trim_volume_tips(answer, seq.lost[chosen], norm.alpha, norm.lbar)
            cuts, lost, lam = oracle.naive_trim(
                answer.working_graph(), sk.volume, sk.z, sk.y, sk.x, sk.r2, spacing,
                norm.alpha, norm.lbar,
            )  # fmt: skip
            assert fast.cuts == cuts and fast.lost == lost
            assert target(fast.lost, seq.area, fast.skeleton.length, norm.alpha, norm.lbar) == lam
            assert fast.skeleton.n_endpoints == answer.n_endpoints
            made += sum(k > 0 for *_, k in cuts)
    assert made >= 3  # not vacuous: some tips are cut


def test_multi_page_tiff_stacks_are_volumes(tmp_path) -> None:
    import tifffile

    vol = np.zeros((12, 14, 40), np.uint8)
    vol[3:9, 4:10, 3:37] = 255
    path = tmp_path / "stack.tif"
    tifffile.imwrite(path, vol)  # twelve pages
    from_tiff = skelprune.prune(str(path), spacing=(2.0, 1.0, 1.0)).to_dict()
    from_array = skelprune.prune(vol, spacing=(2.0, 1.0, 1.0)).to_dict()
    assert from_tiff == from_array and from_tiff["depth"] == 12
    rgb = tmp_path / "rgb.tif"
    tifffile.imwrite(rgb, np.zeros((3, 8, 9, 3), np.uint8), photometric="rgb")
    with pytest.raises(InvalidImageError, match="one-channel pages"):
        skelprune.prune(str(rgb))


def test_a_volume_file_declaring_too_many_voxels_is_refused_unread(tmp_path, monkeypatch) -> None:
    from skelprune import volume as volume_module
    from skelprune.errors import ImageTooLargeError

    vol = np.zeros((10, 10, 10), bool)
    vol[2:8, 2:8, 2:8] = True
    np.save(tmp_path / "v.npy", vol)
    monkeypatch.setattr(volume_module, "MAX_VOLUME_VOXELS", 999)
    with pytest.raises(ImageTooLargeError, match="1000 voxels"):
        skelprune.prune(str(tmp_path / "v.npy"))


def test_a_volume_given_as_file_bytes_is_the_arrays_answer() -> None:
    import io

    import tifffile

    from skelprune.volume import check_volume_size, read_volume

    fork = y_tubes(radius=2.5, arm=14.0).volume()
    expected = skelprune.prune(fork, spacing=(2, 1, 1)).to_dict()
    npy = io.BytesIO()
    np.save(npy, np.asfortranarray(fork))  # Fortran order read as written
    stack = io.BytesIO()
    tifffile.imwrite(stack, fork.astype(np.uint8), photometric="minisblack", compression="zlib")
    for data in (npy.getvalue(), stack.getvalue()):
        assert check_volume_size(data, fork.size) == fork.shape
        assert np.array_equal(read_volume(data) != 0, fork)
        assert skelprune.prune(data, spacing=(2, 1, 1)).to_dict() == expected
        with pytest.raises(ImageTooLargeError, match="voxels"):
            check_volume_size(data, fork.size - 1)
        with pytest.raises(ImageTooLargeError, match="voxels"):
            read_volume(data, max_voxels=fork.size - 1)


def test_volume_bytes_that_are_not_a_volume_are_refused_by_name() -> None:
    import io

    import tifffile

    from skelprune.volume import read_volume

    objects = io.BytesIO()
    np.save(objects, np.array([[[None]]], dtype=object), allow_pickle=True)
    with pytest.raises(InvalidImageError, match="no pickles"):
        read_volume(objects.getvalue())
    uneven = io.BytesIO()
    with tifffile.TiffWriter(uneven) as tif:
        tif.write(np.ones((8, 8), np.uint8))
        tif.write(np.ones((8, 9), np.uint8))
    with pytest.raises(InvalidImageError, match="differ in size"):
        read_volume(uneven.getvalue())
    with pytest.raises(InvalidImageError, match="truncated"):
        buf = io.BytesIO()
        np.save(buf, np.ones((6, 6, 6), np.uint16))
        read_volume(buf.getvalue()[:-10])


def test_a_volumes_document_speaks_as_an_images() -> None:
    # the graph's keys mean the same in 2-D and 3-D: endpoints are the end nodes' ids
    image = np.zeros((30, 60), bool)
    image[5:25, 5:55] = True
    flat = skelprune.prune(image).to_dict()["components"][0]["skeleton"]
    deep = skelprune.prune(y_tubes(radius=2.5, arm=14.0).volume()).to_dict()
    sk = deep["components"][0]["skeleton"]
    assert set(sk) == set(flat)
    assert sk["endpoints"] == [n["id"] for n in sk["nodes"] if n["kind"] == "endpoint"]
    assert len(sk["endpoints"]) == 3
    for key in ("nodes", "branches"):
        assert set(sk[key][0]) - {"z"} == set(flat[key][0])


def test_a_volumes_table_without_pandas(monkeypatch: pytest.MonkeyPatch) -> None:
    # the service installs no pandas: the CSV and the rows come without it
    res = skelprune.prune(y_tubes(radius=2.5, arm=14.0).volume())
    with_pandas = res.to_csv()
    monkeypatch.setitem(sys.modules, "pandas", None)  # import pandas raises ImportError
    assert res.to_csv() == with_pandas
    rows = res.summary()
    assert isinstance(rows, list) and len(rows) == 3
    assert with_pandas.splitlines()[0].split(",")[:5] == [
        "component",
        "label",
        "branch",
        "kind",
        "length",
    ]
