"""How rough a shape's boundary is: what a one-step opening and closing change.

The coarse DCE stage raises its stop with it, and the noise-floor choice grows the
disks by the boundary's noise depth it implies (:mod:`skelprune.pruning.choice`).
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["boundary_roughness", "volume_roughness"]


def boundary_roughness(mask: np.ndarray) -> float:
    """Pixels a one-pixel opening and closing change, per boundary pixel.

    A clean digital boundary only loses its corner pixels to a 3×3-cross opening and
    closing; a boundary with pixel-scale noise loses its spikes and gets its notches
    filled all along. The ratio is scale-free in the sense that matters here: it counts
    per boundary pixel, not per shape.

    Parameters
    ----------
    mask : (H, W) bool array

    Returns
    -------
    float
        0 for a shape no opening or closing changes; typically 0.01–0.14 for a clean
        silhouette and 0.3–0.7 under boundary noise of one pixel or more.

    Examples
    --------
    >>> m = np.zeros((40, 40), bool); m[5:35, 5:35] = True
    >>> round(boundary_roughness(m), 3)  # only the 4 corner pixels change
    0.034
    >>> comb = m.copy(); comb[4, 5:35:2] = comb[5:35:2, 4] = True; comb[6, 6:34:2] = False
    >>> boundary_roughness(comb) > 0.1  # 1-px teeth and notches along two sides
    True
    """
    mask = np.asarray(mask, dtype=bool)
    m = np.zeros((mask.shape[0] + 4, mask.shape[1] + 4), bool)  # np.pad costs more here
    m[2:-2, 2:-2] = mask
    perimeter, changed = _opening_closing_changes(m)
    return changed / perimeter if perimeter else 0.0


@numba.njit(cache=True)
def _opening_closing_changes(m: np.ndarray) -> tuple[int, int]:
    """Boundary pixels of ``m``, and pixels a 3×3-cross opening or closing changes.

    ``m`` has two empty rows/columns on each side, so no operation meets the border.
    Same counts as ``scipy.ndimage`` binary_erosion / binary_opening / binary_closing
    with the cross (``tests/library/test_coarse.py`` checks), in two passes and no temporaries
    beyond the eroded and dilated images.
    """
    h, w = m.shape
    eroded = np.zeros((h, w), np.bool_)
    dilated = np.zeros((h, w), np.bool_)
    perimeter = 0
    for i in range(1, h - 1):
        for j in range(1, w - 1):
            around = (m[i - 1, j], m[i + 1, j], m[i, j - 1], m[i, j + 1])
            if m[i, j]:
                eroded[i, j] = around[0] and around[1] and around[2] and around[3]
                perimeter += not eroded[i, j]
                dilated[i, j] = True
            else:
                dilated[i, j] = around[0] or around[1] or around[2] or around[3]
    changed = 0
    for i in range(1, h - 1):
        for j in range(1, w - 1):
            if m[i, j]:  # removed by the opening: no eroded pixel in its cross
                changed += not (
                    eroded[i, j]
                    or eroded[i - 1, j]
                    or eroded[i + 1, j]
                    or eroded[i, j - 1]
                    or eroded[i, j + 1]
                )
            else:  # added by the closing: its whole cross is dilated
                changed += (
                    dilated[i, j]
                    and dilated[i - 1, j]
                    and dilated[i + 1, j]
                    and dilated[i, j - 1]
                    and dilated[i, j + 1]
                )
    return perimeter, changed


def volume_roughness(volume: np.ndarray) -> float:
    """:func:`boundary_roughness` of a volume: voxels a one-voxel opening and closing
    with the 6-neighbour cross change, per boundary voxel (a voxel inside with a face
    neighbour outside).

    Examples
    --------
    >>> v = np.zeros((12, 12, 12), bool); v[2:10, 2:10, 2:10] = True
    >>> round(volume_roughness(v), 3)  # the opening takes the cube's edges and corners
    0.27
    """
    m = np.pad(np.asarray(volume, dtype=bool), 2)
    perimeter, changed = _volume_counts(m)  # scipy's cross erosions and dilations, in one kernel
    if not perimeter:
        return 0.0
    return changed / perimeter


@numba.njit(cache=True)
def _cross_all(a, z, y, x) -> bool:
    return (
        a[z, y, x]
        and a[z - 1, y, x]
        and a[z + 1, y, x]
        and a[z, y - 1, x]
        and a[z, y + 1, x]
        and a[z, y, x - 1]
        and a[z, y, x + 1]
    )


@numba.njit(cache=True)
def _cross_any(a, z, y, x) -> bool:
    return (
        a[z, y, x]
        or a[z - 1, y, x]
        or a[z + 1, y, x]
        or a[z, y - 1, x]
        or a[z, y + 1, x]
        or a[z, y, x - 1]
        or a[z, y, x + 1]
    )


@numba.njit(cache=True)
def _volume_counts(m):  # type: ignore[no-untyped-def]
    """Boundary voxels and voxels the 6-cross opening and closing change, of ``m``
    padded by two: its outer two layers are background, so every voxel the counts read
    has its six face neighbours in the array (scipy's border value 0 changes nothing).

    Only voxels inside and their face neighbours can change: a voxel is eroded when its
    cross is inside, dilated when its cross meets the inside, each read from ``m``."""
    nz, ny, nx = m.shape
    seen = np.zeros(m.shape, np.bool_)  # background voxels already tested for the closing
    perimeter = 0
    changed = 0
    for z in range(2, nz - 2):
        for y in range(2, ny - 2):
            for x in range(2, nx - 2):
                if not m[z, y, x]:
                    continue
                perimeter += not _cross_all(m, z, y, x)
                opened = (
                    _cross_all(m, z, y, x)
                    or _cross_all(m, z - 1, y, x)
                    or _cross_all(m, z + 1, y, x)
                    or _cross_all(m, z, y - 1, x)
                    or _cross_all(m, z, y + 1, x)
                    or _cross_all(m, z, y, x - 1)
                    or _cross_all(m, z, y, x + 1)
                )
                changed += not opened  # removed by the opening
                for k in range(6):
                    a, b, c = z, y, x
                    if k == 0:
                        a -= 1
                    elif k == 1:
                        a += 1
                    elif k == 2:
                        b -= 1
                    elif k == 3:
                        b += 1
                    elif k == 4:
                        c -= 1
                    else:
                        c += 1
                    if m[a, b, c] or seen[a, b, c]:
                        continue
                    seen[a, b, c] = True
                    if a == 1 or b == 1 or c == 1 or a == nz - 2 or b == ny - 2 or c == nx - 2:
                        continue  # its cross meets the outer layer, never dilated
                    changed += (  # added by the closing: its whole cross is dilated
                        _cross_any(m, a, b, c)
                        and _cross_any(m, a - 1, b, c)
                        and _cross_any(m, a + 1, b, c)
                        and _cross_any(m, a, b - 1, c)
                        and _cross_any(m, a, b + 1, c)
                        and _cross_any(m, a, b, c - 1)
                        and _cross_any(m, a, b, c + 1)
                    )
    return perimeter, changed
