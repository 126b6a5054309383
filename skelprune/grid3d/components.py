"""The 26-connected components of a sparse volume, from its foreground voxels alone.

``scipy.ndimage.label`` passes over every voxel of the volume with its provisional
labels; a neuron or a vessel tree fills well under a percent of its box, so a
union-find over the foreground voxels, each joined to its 13 neighbours before it in
raster order, finds the same components several times faster (a voxelized neuron of
about 16,000 voxels in a 190 × 257 × 197 box: 7 ms against 60 ms). Components are
numbered as ``scipy.ndimage.label`` numbers them: by their first voxel in raster order.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..grid._digital import find_root

__all__ = ["SPARSE", "binary_pieces", "sparse_components"]

#: A component: its padded crop, the crop's corner in the volume, its label (None).
Piece = tuple[np.ndarray, tuple[int, int, int], "int | None"]

#: A volume is sparse when at most this share of its voxels is inside: there the
#: union-find wins; on a fuller volume scipy's pass over every voxel is faster.
SPARSE = 1 / 16


@njit(cache=True)
def _components(inside, index_of, nz, ny, nx):
    """Each foreground voxel's component (numbered by first voxel in raster order) and
    the number of components; ``inside`` the flat indices of the foreground, sorted,
    ``index_of`` each voxel's position in ``inside`` (-1: background)."""
    n = inside.size
    parent = np.arange(n)
    for a in range(n):
        f = inside[a]
        z = f // (ny * nx)
        y = (f - z * ny * nx) // nx
        x = f - (z * ny + y) * nx
        for dz in range(-1, 1):  # the 13 neighbours before it in raster order
            for dy in range(-1, 2):
                for dx in range(-1, 2):
                    if dz == 0 and (dy > 0 or (dy == 0 and dx >= 0)):
                        continue
                    zz, yy, xx = z + dz, y + dy, x + dx
                    if zz < 0 or yy < 0 or yy >= ny or xx < 0 or xx >= nx:
                        continue
                    b = index_of[(zz * ny + yy) * nx + xx]
                    if b >= 0:
                        ra, rb = find_root(parent, a), find_root(parent, b)
                        if ra < rb:
                            parent[rb] = ra
                        elif rb < ra:
                            parent[ra] = rb
    # a root is its component's first voxel in raster order (unions keep the smaller)
    component = np.empty(n, np.int64)
    number = np.full(n, -1, np.int64)
    k = 0
    for a in range(n):
        r = find_root(parent, a)
        if number[r] < 0:
            number[r] = k
            k += 1
        component[a] = number[r]
    return component, k


def sparse_components(inside: np.ndarray, shape: tuple[int, int, int]) -> tuple[np.ndarray, int]:
    """The 26-connected component of each foreground voxel, numbered from 0 in the order
    ``scipy.ndimage.label`` numbers them from 1, and the number of components.

    Parameters
    ----------
    inside : (n,) int64 array
        The flat indices of the foreground voxels, sorted (``np.flatnonzero``).
    shape : (Z, Y, X)
        The volume's shape.

    Examples
    --------
    >>> v = np.zeros((2, 3, 4), bool); v[0, 0, 0] = v[1, 1, 1] = v[0, 2, 3] = True
    >>> sparse_components(np.flatnonzero(v), v.shape)
    (array([0, 1, 0]), 2)
    """
    index_of = np.full(int(np.prod(shape)), -1, np.int32)  # scipy's labels: as many bytes
    index_of[inside] = np.arange(inside.size, dtype=np.int32)
    return _components(inside, index_of, *shape)


def binary_pieces(inside: np.ndarray) -> list[Piece]:
    """The 26-connected components of a boolean volume as padded crops with their
    corners, in ``scipy.ndimage.label``'s order; a sparse volume's found from its
    foreground voxels (:func:`sparse_components`), a fuller one's by scipy."""
    n = int(np.count_nonzero(inside))  # no index array for a full volume: scipy's pass
    if n > SPARSE * inside.size or n >= 2**31:
        from scipy import ndimage

        from .distance import pad

        lab, _ = ndimage.label(inside, structure=np.ones((3, 3, 3), bool))
        return [
            (pad(lab[box] == i), (box[0].start - 1, box[1].start - 1, box[2].start - 1), None)
            for i, box in enumerate(ndimage.find_objects(lab), start=1)
            if box is not None
        ]
    flat = np.flatnonzero(inside)
    nz, ny, nx = (int(d) for d in inside.shape)
    component, k = sparse_components(flat, (nz, ny, nx))
    order = np.argsort(component, kind="stable")  # each component's voxels, raster order
    starts = np.searchsorted(component[order], np.arange(k + 1))
    z, rest = np.divmod(flat[order], ny * nx)
    y, x = np.divmod(rest, nx)
    out: list[Piece] = []
    for i in range(k):
        part = slice(starts[i], starts[i + 1])
        cz, cy, cx = z[part], y[part], x[part]
        lo = (int(cz.min()), int(cy.min()), int(cx.min()))
        shape = (int(cz.max()) - lo[0] + 3, int(cy.max()) - lo[1] + 3, int(cx.max()) - lo[2] + 3)
        crop = np.zeros(shape, bool)
        crop[cz - lo[0] + 1, cy - lo[1] + 1, cx - lo[2] + 1] = True
        out.append((crop, (lo[0] - 1, lo[1] - 1, lo[2] - 1), None))
    return out
