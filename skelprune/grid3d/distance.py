"""Exact squared distance transform of a volume with anisotropic voxels.

A voxel's **squared radius** ``r2`` is the squared physical distance from its centre to
the centre of the nearest background voxel, ``(a·dz)² + (b·dy)² + (c·dx)²`` for the
integer offsets ``(a, b, c)`` between them, on the volume padded by one background voxel
(so a volume touching its border works too). For whole-number spacings it is found by
an exact separable transform in integers; otherwise the nearest background voxel comes
from scipy's exact feature transform with ``sampling=spacing``, and ``r2`` is evaluated
with the same expression, in the same order, as the ball test of
:mod:`skelprune.grid3d.balls`: a ball never covers the background voxel its
radius was measured to.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..errors import EmptyMaskError, InvalidImageError, InvalidOptionError
from ..grid._edt import lower_envelope

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
    volume = np.asarray(volume)
    out = np.zeros(tuple(n + 2 for n in volume.shape), volume.dtype)  # np.pad, faster
    out[(slice(1, -1),) * volume.ndim] = volume
    return out


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
    """:func:`squared_distance` of a volume already padded (bool, checked spacing).

    Whole-number spacings (the isotropic grid, ``(3, 1, 1)``...) take a separable exact
    transform in integers (:func:`_integer_squared`): every squared distance is then a
    whole number, the same whichever exact method finds it. Other spacings take scipy's
    feature transform and the ball test's expression, so that values match bit for bit.
    """
    weights = [round(s * s) for s in spacing]
    if all(float(s).is_integer() and s <= 1 << 10 for s in spacing):
        out = np.empty(padded.shape, dtype=np.float64)
        _integer_squared(np.ascontiguousarray(padded), np.array(weights, np.int64), out)
        return out
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


@njit(cache=True)
def _integer_squared(fg, weights, out) -> None:
    """Exact squared distances in whole numbers, axis by axis (Meijster et al. 2000):
    along ``z`` the nearest background voxel of the column, then along ``y`` and ``x``
    the lower envelope of the parabolas ``w·(u − i)² + g(i)``, with integer separators.
    The volume is padded: every line holds background, so every value is finite."""
    nz, ny, nx = fg.shape
    g = np.empty((nz, ny, nx), np.int64)
    wz = weights[0]
    for z in range(nz):  # down the columns, a plane at a time: the last background above
        for y in range(ny):
            for x in range(nx):
                if not fg[z, y, x]:
                    g[z, y, x] = 0
                elif z == 0:
                    g[z, y, x] = 1
                else:
                    g[z, y, x] = g[z - 1, y, x] + 1
    for z in range(nz - 2, -1, -1):  # and up: the nearer of the two
        for y in range(ny):
            for x in range(nx):
                if g[z + 1, y, x] + 1 < g[z, y, x]:
                    g[z, y, x] = g[z + 1, y, x] + 1
    for z in range(nz):
        for y in range(ny):
            for x in range(nx):
                g[z, y, x] = wz * g[z, y, x] * g[z, y, x]
    n = max(ny, nx)
    line = np.empty(n, np.int64)
    res = np.empty(n, np.int64)
    s = np.empty(n, np.int64)
    t = np.empty(n, np.int64)
    for z in range(nz):  # a line of zeros stays zeros: crops are mostly background
        for x in range(nx):
            busy = False
            for y in range(ny):
                line[y] = g[z, y, x]
                busy |= line[y] != 0
            if not busy:
                continue
            lower_envelope(line, ny, weights[1], res, s, t)
            for y in range(ny):
                g[z, y, x] = res[y]
        for y in range(ny):
            busy = False
            for x in range(nx):
                line[x] = g[z, y, x]
                busy |= line[x] != 0
            if not busy:
                for x in range(nx):
                    out[z, y, x] = 0.0
                continue
            lower_envelope(line, nx, weights[2], res, s, t)
            for x in range(nx):
                out[z, y, x] = float(res[x]) if fg[z, y, x] else 0.0
