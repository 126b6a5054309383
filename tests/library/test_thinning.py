"""The seams' thinning: Guo & Hall's algorithm without scikit-image, pixel for pixel
what ``skimage.morphology.thin`` gives (scikit-image is a test dependency only)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage as ndi
from skimage.morphology import thin as skimage_thin

from skelprune.grid.thinning import thin


@pytest.mark.parametrize("seed", range(4))
def test_thin_is_skimages_thin(seed: int) -> None:
    rng = np.random.default_rng(seed)
    for _ in range(40):
        h, w = rng.integers(3, 90, 2)
        image = rng.random((h, w)) < rng.uniform(0.02, 0.4)
        image = ndi.binary_dilation(image, iterations=int(rng.integers(0, 4)))
        assert np.array_equal(thin(image), skimage_thin(image))


def test_thin_keeps_a_ring_a_ring_and_takes_integers() -> None:
    yy, xx = np.mgrid[:41, :41]
    ring = ((yy - 20) ** 2 + (xx - 20) ** 2 <= 15**2) & ((yy - 20) ** 2 + (xx - 20) ** 2 >= 9**2)
    out = thin(ring.astype(np.uint8) * 7)
    assert out.dtype == bool and (out <= ring).all()
    # one loop: one hole in the thinned ring, one component
    assert ndi.label(out, np.ones((3, 3)))[1] == 1
    assert ndi.label(~out)[1] == 2
    with pytest.raises(ValueError, match="2-D"):
        thin(np.zeros((2, 2, 2)))
