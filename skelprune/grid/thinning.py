"""Topology-preserving thinning of a binary image (Guo & Hall's two-subiteration
algorithm, the one of ``skimage.morphology.thin``), in numpy and scipy alone: the local
scope thins its seams with it, in the service too, where scikit-image is not installed.

A pixel's eight neighbours are read as the bits of one byte, and two lookup tables say
which pixels each subiteration removes; the subiterations alternate until nothing
changes.

References
----------
Z. Guo and R. W. Hall, "Parallel thinning with two-subiteration algorithms",
Communications of the ACM 32(3), 359-373, 1989.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage as ndi

__all__ = ["thin"]

#: The weight of each neighbour in the byte: bit k is neighbour x_{k+1} of the paper,
#: x1 the east neighbour, going anticlockwise.
_WEIGHTS = np.array([[8, 4, 2], [16, 0, 1], [32, 64, 128]], np.int32)


def _tables() -> tuple[np.ndarray, np.ndarray]:
    """The two subiterations' tables: which neighbourhood bytes delete the pixel."""
    first = np.zeros(256, bool)
    second = np.zeros(256, bool)
    for n in range(256):
        x = [bool(n >> k & 1) for k in range(8)]  # x[0] = x1 … x[7] = x8
        # G1: the crossing number is one
        crossing = sum(not x[i] and (x[i + 1] or x[(i + 2) % 8]) for i in (0, 2, 4, 6))
        # G2: 2 <= min(N1, N2) <= 3
        n1 = sum(x[2 * k - 2] or x[2 * k - 1] for k in range(1, 5))
        n2 = sum(x[2 * k - 1] or x[(2 * k) % 8] for k in range(1, 5))
        g12 = crossing == 1 and 2 <= min(n1, n2) <= 3
        # G3 and G3': the pixel is not on the side each subiteration keeps
        first[n] = g12 and not ((x[1] or x[2] or not x[7]) and x[0])
        second[n] = g12 and not ((x[5] or x[6] or not x[3]) and x[4])
    return first, second


_FIRST, _SECOND = _tables()


def thin(image: np.ndarray) -> np.ndarray:
    """The image thinned to lines one pixel wide, its 8-connected topology kept.

    Parameters
    ----------
    image : (M, N) ndarray
        Non-zero pixels are the shape.

    Returns
    -------
    ndarray of bool
        The thinned shape, a subset of ``image != 0``.

    Examples
    --------
    >>> bar = np.zeros((5, 9), bool); bar[1:4, 1:8] = True
    >>> thin(bar).astype(int)
    array([[0, 0, 0, 0, 0, 0, 0, 0, 0],
           [0, 0, 0, 0, 0, 0, 0, 0, 0],
           [0, 0, 1, 1, 1, 1, 1, 0, 0],
           [0, 0, 0, 0, 0, 0, 0, 0, 0],
           [0, 0, 0, 0, 0, 0, 0, 0, 0]])
    """
    if image.ndim != 2:
        raise ValueError("thin takes a 2-D image")
    skel = np.asarray(image != 0, np.uint8).copy()
    while True:
        before = int(skel.sum())
        for table in (_FIRST, _SECOND):
            code = ndi.correlate(skel, _WEIGHTS.astype(np.uint8), mode="constant")
            skel[np.take(table, code)] = 0
        if int(skel.sum()) == before:
            return skel.astype(bool)
