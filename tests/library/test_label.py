"""The run-based component labelling equals scipy's, and the package imports lazily."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from scipy import ndimage

from skelprune.grid._label import components8, label8

EIGHT = np.ones((3, 3), bool)


@pytest.mark.parametrize("seed", range(40))
def test_label8_equals_scipy(seed):
    rng = np.random.default_rng(seed)
    mask = rng.random((rng.integers(1, 50), rng.integers(1, 50))) < rng.random()
    want, n = ndimage.label(mask, structure=EIGHT)
    got, k = label8(mask)
    assert k == n
    np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("seed", range(20))
def test_components8_are_scipy_crops(seed):
    rng = np.random.default_rng(100 + seed)
    mask = rng.random((40, 60)) < 0.3
    labels, _ = ndimage.label(mask, structure=EIGHT)
    want = [
        (np.pad(labels[sl] == k, 1), (sl[0].start - 1, sl[1].start - 1))
        for k, sl in enumerate(ndimage.find_objects(labels), start=1)
    ]
    got = components8(mask)
    assert [o for _, o in got] == [o for _, o in want]
    for (a, _), (b, _) in zip(got, want, strict=True):
        np.testing.assert_array_equal(a, b)


def test_empty_mask_has_no_component():
    assert components8(np.zeros((3, 4), bool)) == []
    assert label8(np.zeros((3, 4), bool))[1] == 0


def test_import_loads_no_pipeline_and_keeps_the_function_names():
    code = (
        "import sys, skelprune\n"
        "heavy = [m for m in ('numba', 'scipy', 'PIL', 'cv2', 'shapely') if m in sys.modules]\n"
        "import skelprune.grid.medial_axis, skelprune.grid.reconstruction\n"
        "print(heavy, callable(skelprune.medial_axis), callable(skelprune.encode),\n"
        "      type(skelprune.prune).__name__, 'scipy.optimize' in sys.modules,\n"
        "      skelprune.api.prune is skelprune.prune, hasattr(skelprune, 'no_such_name'))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["[]", "True", "True", "function", "False", "True", "False"]
