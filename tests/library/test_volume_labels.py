"""Label volumes: one pass groups the voxels by label (boxes, voxels, pieces) as the
per-label oracle does, the integer distance transform equals scipy's path, and the
components pruned in parallel give the serial answer byte for byte."""

from __future__ import annotations

import io
import json

import numpy as np
import pytest
from scipy import ndimage

import skelprune
from skelprune.errors import InvalidOptionError
from skelprune.grid3d.distance import _squared_from_features, pad, padded_squared_distance
from skelprune.volume import prune_volume_labels, volume_components
from skelprune.volume_labels import label_groups
from skelprune.volume_parallel import Progress
from testkit.volumes import touching_trees


def _oracle_groups(v: np.ndarray) -> list[tuple[int, list[int], list[int]]]:
    out = []
    for value in np.unique(v).tolist():
        if value == 0:
            continue
        where = np.argwhere(v == value)
        box = where.min(axis=0).tolist() + where.max(axis=0).tolist()
        out.append((int(value), box, np.flatnonzero(v.ravel() == value).tolist()))
    return out


@pytest.mark.parametrize("dtype", [np.uint8, np.int16, np.int32, np.uint32, np.int64, np.uint64])
def test_groups_hold_each_labels_box_and_voxels_in_raster_order(dtype) -> None:
    rng = np.random.default_rng(3)
    for trial in range(5):
        signed = np.issubdtype(dtype, np.signedinteger)
        v = rng.integers(-4 if signed else 0, 9, (7, 9, 11)).astype(dtype)
        v[rng.random(v.shape) < 0.4] = 0
        if dtype in (np.int64, np.uint64) and trial % 2:  # sparse values: the sorted path
            v[v == 3] = np.iinfo(dtype).max - 1
        g = label_groups(v)
        got = [
            (g.values[i], g.boxes[i].tolist(), g.voxels[g.starts[i] : g.starts[i + 1]].tolist())
            for i in range(len(g))
        ]
        assert got == _oracle_groups(v)
        for i in range(len(g)):
            assert np.array_equal(g.mask(i), v[g.box(i)] == g.values[i])


def test_an_empty_volume_has_no_group() -> None:
    assert len(label_groups(np.zeros((3, 4, 5), np.uint16))) == 0


def test_65535_labels_in_48_cubed_each_one_voxel() -> None:
    v = np.zeros((48, 48, 48), np.uint16)
    v.reshape(-1)[:65535] = np.arange(1, 65536, dtype=np.uint16)
    g = label_groups(v)
    assert len(g) == 65535 and g.voxels.tolist() == list(range(65535))
    assert (g.boxes[:, :3] == g.boxes[:, 3:]).all()
    pieces = volume_components(v[:2])  # the pieces of the first 4,608 labels
    assert [p[2] for p in pieces] == list(range(1, 2 * 48 * 48 + 1))
    assert all(p[0].shape == (3, 3, 3) and p[0].sum() == 1 for p in pieces)


def test_touching_labels_never_join() -> None:
    lv = touching_trees(8, 48, seed=5)
    v = lv.labels
    assert len(np.unique(v)) - 1 == 8
    assert ndimage.label(v != 0, np.ones((3, 3, 3)))[1] < 8  # they do touch
    pieces = volume_components(v)
    for crop, origin, label in pieces:
        z, y, x = (np.argwhere(crop) + origin).T
        assert (v[z, y, x] == label).all()
    assert sum(int(c.sum()) for c, _, _ in pieces) == int((v != 0).sum())


@pytest.mark.parametrize("spacing", [(1.0, 1.0, 1.0), (3.0, 1.0, 1.0), (2.0, 5.0, 1.0)])
def test_integer_distances_equal_scipys_feature_path(spacing) -> None:
    rng = np.random.default_rng(11)
    for _ in range(40):
        v = rng.random(tuple(rng.integers(1, 13, 3))) < rng.uniform(0.3, 0.99)
        p = pad(v)
        ft = ndimage.distance_transform_edt(
            p, sampling=spacing, return_distances=False, return_indices=True
        )
        want = np.empty(p.shape)
        _squared_from_features(p, ft[0], ft[1], ft[2], np.array(spacing), want)
        assert np.array_equal(padded_squared_distance(p, spacing), want)


def _documents(res) -> tuple[str, str, str]:
    return json.dumps(res.to_dict(), sort_keys=True), res.to_csv(), res.to_swc()


@pytest.mark.parametrize("spacing", [(1.0, 1.0, 1.0), (1.5, 1.0, 0.7)])
def test_parallel_components_give_the_serial_answer(spacing) -> None:
    v = touching_trees(10, 56, seed=2).labels
    serial = skelprune.prune(v, spacing=spacing)
    seen: list[tuple[int, int]] = []
    pooled = prune_volume_labels(
        v, spacing=spacing, workers=2, progress=lambda done, total: seen.append((done, total))
    )
    assert _documents(pooled) == _documents(serial)
    total = len(serial.components)
    assert total > 10  # some labels are cut in pieces
    assert seen[0] == (0, total) and seen[-1] == (total, total)
    assert [d for d, _ in seen] == sorted(d for d, _ in seen)
    assert [c.label for c in pooled.components] == sorted(c.label for c in pooled.components)


def test_progress_writes_components_done() -> None:
    out = io.StringIO()
    tick = Progress(3, out, every=0.0)
    for _ in range(3):
        tick()
    assert out.getvalue().endswith("components: 3/3 (100 %), 0.0 s\n")


@pytest.mark.parametrize("workers", [0, -1, 1.5])
def test_bad_worker_counts_are_refused(workers) -> None:
    with pytest.raises(InvalidOptionError, match="workers"):
        prune_volume_labels(np.ones((5, 5, 6), np.uint8), workers=workers)


def _scipy_roughness(volume: np.ndarray) -> float:
    """The roughness by scipy's cross erosions and dilations (the reference)."""
    m = np.pad(volume, 2)
    cross = ndimage.generate_binary_structure(3, 1)
    eroded = ndimage.binary_erosion(m, cross)
    perimeter = int(np.count_nonzero(m & ~eroded))
    if not perimeter:
        return 0.0
    opened = ndimage.binary_dilation(eroded, cross)
    closed = ndimage.binary_erosion(ndimage.binary_dilation(m, cross), cross)
    return (int(np.count_nonzero(m & ~opened)) + int(np.count_nonzero(closed & ~m))) / perimeter


def test_volume_roughness_counts_what_scipys_morphology_counts() -> None:
    from skelprune.grid._roughness import volume_roughness
    from testkit.volumes import random_tree

    rng = np.random.default_rng(5)
    for _ in range(200):
        v = rng.random(tuple(rng.integers(1, 12, 3))) < rng.uniform(0.1, 0.95)
        assert volume_roughness(v) == _scipy_roughness(v)
    tree = random_tree(1, 48).volume(0.7, seed=1)
    assert volume_roughness(tree) == _scipy_roughness(tree) > 0
