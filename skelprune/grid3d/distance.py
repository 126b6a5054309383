"""Exact squared distance transform of a volume with anisotropic voxels.

A voxel's **squared radius** ``r2`` is the squared physical distance from its centre to
the centre of the nearest background voxel, ``(a·dz)² + (b·dy)² + (c·dx)²`` for the
integer offsets ``(a, b, c)`` between them. The nearest background voxel comes from
scipy's exact feature transform with ``sampling=spacing`` on the volume padded by one
background voxel (so a volume touching its border works too), and ``r2`` is evaluated
with the same expression, in the same order, as the ball test of
:mod:`skelprune.grid3d.balls`: a ball never covers the background voxel its
radius was measured to.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..errors import EmptyMaskError, InvalidImageError, InvalidOptionError

__all__ = [
    "check_spacing",
    "check_volume",
    "pad",
    "padded_squared_distance",
    "squared_distance",
]


def check_volume(volume: object) -> np.ndarray:
    """``volume`` as a C-contiguous 3-D bool array (non-zero = inside).

    Raises
    ------
    InvalidImageError
        Not a 3-D array.
    EmptyMaskError
        No voxel inside.
    """
    arr = np.asarray(volume)
    if arr.ndim != 3:
        raise InvalidImageError(f"a volume is a 3-D array; this one has {arr.ndim} dimensions")
    arr = np.ascontiguousarray(arr != 0)
    if not arr.any():
        raise EmptyMaskError("the volume has no voxel inside")
    return arr


def check_spacing(spacing: object) -> tuple[float, float, float]:
    """``spacing`` as three finite positive floats ``(dz, dy, dx)``.

    Raises
    ------
    InvalidOptionError
        Not three finite positive numbers.
    """
    try:
        values = tuple(float(v) for v in spacing)  # type: ignore[attr-defined]
    except (TypeError, ValueError):
        raise InvalidOptionError(
            f"spacing is three positive numbers (dz, dy, dx), not {spacing!r}"
        ) from None
    if len(values) != 3 or not all(math.isfinite(v) and v > 0 for v in values):
        raise InvalidOptionError(f"spacing is three positive numbers (dz, dy, dx), not {spacing!r}")
    return values  # type: ignore[return-value]


def pad(volume: np.ndarray) -> np.ndarray:
    """``volume`` with one background voxel all around (the kernels look one voxel
    beyond every voxel inside without bounds checks)."""
    return np.pad(volume, 1)


def squared_distance(
    volume: np.ndarray, spacing: tuple[float, float, float] = (1.0, 1.0, 1.0)
) -> np.ndarray:
    """Exact squared distance of each voxel to the nearest background voxel.

    Parameters
    ----------
    volume : (Z, Y, X) array
        Non-zero inside. Anything outside the array counts as background.
    spacing : (dz, dy, dx)
        Physical size of a voxel along each axis.

    Returns
    -------
    (Z, Y, X) float64 array, 0 on the background, in squared physical units.

    Examples
    --------
    >>> v = np.zeros((3, 5, 5), bool); v[:, 1:4, 1:4] = True
    >>> float(squared_distance(v)[1, 2, 2]), float(squared_distance(v, (0.5, 1, 1))[1, 2, 2])
    (4.0, 1.0)
    """
    padded = pad(np.asarray(volume) != 0)
    return padded_squared_distance(padded, check_spacing(spacing))[1:-1, 1:-1, 1:-1]


def padded_squared_distance(padded: np.ndarray, spacing: tuple[float, float, float]) -> np.ndarray:
    """:func:`squared_distance` of a volume already padded (bool, checked spacing)."""
    from scipy import ndimage

    # the feature transform only: scipy's distances would cost three float64 volumes more
    ft = ndimage.distance_transform_edt(
        padded, sampling=spacing, return_distances=False, return_indices=True
    )
    r2 = np.empty(padded.shape, dtype=np.float64)
    _squared_from_features(padded, ft[0], ft[1], ft[2], np.array(spacing), r2)
    return r2


@njit(cache=True)
def _squared_from_features(fg, fz, fy, fx, spacing, out) -> None:
    sz, sy, sx = spacing[0], spacing[1], spacing[2]
    nz, ny, nx = fg.shape
    for z in range(nz):
        for y in range(ny):
            for x in range(nx):
                if not fg[z, y, x]:
                    out[z, y, x] = 0.0
                    continue
                a = (fz[z, y, x] - z) * sz
                b = (fy[z, y, x] - y) * sy
                c = (fx[z, y, x] - x) * sx
                out[z, y, x] = a * a + b * b + c * c
