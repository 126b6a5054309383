"""A label volume's objects in one pass: every label's box and voxels, then its pieces.

:func:`label_groups` reads the volume once (twice when the label values span a range
much wider than the volume: then the labelled voxels are sorted once), groups the
labelled voxels by value with a counting sort (raster order kept inside each group) and
keeps each value's bounding box, so that the work grows with the labelled voxels, not
with labels × voxels. :func:`label_pieces` makes each label's mask in its box from its
own voxels and splits it into 26-connected pieces; touching labels never join.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
from numba import njit

__all__ = ["LabelGroups", "label_groups", "label_pieces"]

#: The most distinct values a dense table may span beyond the voxels' count: wider
#: ranges (sparse 64-bit ids) are sorted instead.
DENSE_SPAN = 1 << 22


class LabelGroups:
    """The labelled voxels of a volume grouped by value.

    Attributes
    ----------
    values : list of int
        The non-zero values, ascending.
    boxes : (n, 6) int64 array
        ``z0, y0, x0, z1, y1, x1`` (inclusive) of each value's voxels.
    starts : (n + 1,) int64 array
        Group ``i``'s voxels are ``voxels[starts[i]:starts[i + 1]]``.
    voxels : (k,) int64 array
        Flat (raster) indices of the labelled voxels, by group, raster order inside one.
    shape : (Z, Y, X)
    """

    def __init__(
        self,
        values: list[int],
        boxes: np.ndarray,
        starts: np.ndarray,
        voxels: np.ndarray,
        shape: tuple[int, int, int],
    ) -> None:
        self.values = values
        self.boxes = boxes
        self.starts = starts
        self.voxels = voxels
        self.shape = shape

    def __len__(self) -> int:
        return len(self.values)

    def box(self, i: int) -> tuple[slice, slice, slice]:
        """Group ``i``'s bounding box as slices of the volume."""
        b = self.boxes[i]
        return (
            slice(int(b[0]), int(b[3]) + 1),
            slice(int(b[1]), int(b[4]) + 1),
            slice(int(b[2]), int(b[5]) + 1),
        )

    def mask(self, i: int) -> np.ndarray:
        """Group ``i``'s voxels as a bool mask of its box."""
        b = self.boxes[i]
        out = np.zeros((b[3] - b[0] + 1, b[4] - b[1] + 1, b[5] - b[2] + 1), bool)
        _paint(out, self.voxels[self.starts[i] : self.starts[i + 1]], b, self.shape[1:])
        return out


def label_groups(volume: np.ndarray) -> LabelGroups:
    """The non-zero values of an integer volume with their boxes and voxels.

    >>> v = np.zeros((2, 3, 4), np.int16); v[0, 1, 1:3] = -4; v[1, 2, 3] = 9
    >>> g = label_groups(v)
    >>> g.values, g.boxes.tolist(), g.voxels.tolist()
    ([-4, 9], [[0, 1, 1, 0, 1, 2], [1, 2, 3, 1, 2, 3]], [5, 6, 23])
    """
    shape = (int(volume.shape[0]), int(volume.shape[1]), int(volume.shape[2]))
    flat = np.ascontiguousarray(volume).reshape(-1)
    if flat.size == 0 or not flat.any():
        empty = np.zeros((0, 6), np.int64)
        return LabelGroups([], empty, np.zeros(1, np.int64), np.zeros(0, np.int64), shape)
    lo, hi = int(flat.min()), int(flat.max())
    if hi - lo < DENSE_SPAN + flat.size // 8 and lo >= -(2**63) and hi < 2**63:
        # dense ids: value - lo, read straight from the volume (no copy of the voxels)
        ids_of = flat if flat.dtype.itemsize < 8 or flat.dtype.kind == "i" else flat.view(np.int64)
        counts, boxes = _count(ids_of, lo, hi - lo + 1, shape[1], shape[2])
        present = np.flatnonzero(counts)
        starts = np.zeros(counts.size + 1, np.int64)
        np.cumsum(counts, out=starts[1:])
        voxels = _place(ids_of, lo, starts[:-1].copy(), int(starts[-1]))
        values = (present + lo).tolist()
        return LabelGroups(
            values,
            boxes[present],
            np.append(starts[present], starts[-1]),
            voxels,
            shape,
        )
    # sparse values (64-bit ids, say): sort the labelled voxels' values once
    where = np.flatnonzero(flat)
    uniq, ids = np.unique(flat[where], return_inverse=True)
    ids = ids.astype(np.int64).reshape(-1)
    counts, boxes = _count_ids(ids, where, len(uniq), shape[1], shape[2])
    starts = np.zeros(len(uniq) + 1, np.int64)
    np.cumsum(counts, out=starts[1:])
    voxels = _place_ids(ids, where, starts[:-1].copy())
    return LabelGroups([int(v) for v in uniq.tolist()], boxes, starts, voxels, shape)


def label_pieces(
    groups: LabelGroups,
) -> Iterator[tuple[np.ndarray, tuple[int, int, int], int]]:
    """Each label's 26-connected pieces as padded crops with their origins in the
    volume: by label, then as ``scipy.ndimage.label`` finds them in the label's box
    (:func:`skelprune.grid3d.components.binary_pieces`)."""
    from .grid3d.components import binary_pieces

    for i, value in enumerate(groups.values):
        z0, y0, x0 = (int(v) for v in groups.boxes[i][:3])
        for crop, (z, y, x), _ in binary_pieces(groups.mask(i)):
            yield crop, (z0 + z, y0 + y, x0 + x), value


@njit(cache=True)
def _count(flat, lo, n, ny, nx):  # type: ignore[no-untyped-def]
    counts = np.zeros(n, np.int64)
    boxes = np.empty((n, 6), np.int64)
    boxes[:, :3] = 1 << 62
    boxes[:, 3:] = -1
    plane = ny * nx
    for p in range(flat.size):
        v = flat[p]
        if v == 0:
            continue
        i = np.int64(v) - lo
        counts[i] += 1
        z = p // plane
        y = (p - z * plane) // nx
        x = p - z * plane - y * nx
        b = boxes[i]
        if z < b[0]:
            b[0] = z
        if y < b[1]:
            b[1] = y
        if x < b[2]:
            b[2] = x
        if z > b[3]:
            b[3] = z
        if y > b[4]:
            b[4] = y
        if x > b[5]:
            b[5] = x
    return counts, boxes


@njit(cache=True)
def _place(flat, lo, next_slot, total):  # type: ignore[no-untyped-def]
    out = np.empty(total, np.int64)
    for p in range(flat.size):
        v = flat[p]
        if v == 0:
            continue
        i = np.int64(v) - lo
        out[next_slot[i]] = p
        next_slot[i] += 1
    return out


@njit(cache=True)
def _count_ids(ids, where, n, ny, nx):  # type: ignore[no-untyped-def]
    counts = np.zeros(n, np.int64)
    boxes = np.empty((n, 6), np.int64)
    boxes[:, :3] = 1 << 62
    boxes[:, 3:] = -1
    plane = ny * nx
    for k in range(ids.size):
        i = ids[k]
        p = where[k]
        counts[i] += 1
        z = p // plane
        y = (p - z * plane) // nx
        x = p - z * plane - y * nx
        b = boxes[i]
        b[0] = min(b[0], z)
        b[1] = min(b[1], y)
        b[2] = min(b[2], x)
        b[3] = max(b[3], z)
        b[4] = max(b[4], y)
        b[5] = max(b[5], x)
    return counts, boxes


@njit(cache=True)
def _place_ids(ids, where, next_slot):  # type: ignore[no-untyped-def]
    out = np.empty(ids.size, np.int64)
    for k in range(ids.size):
        i = ids[k]
        out[next_slot[i]] = where[k]
        next_slot[i] += 1
    return out


@njit(cache=True)
def _paint(out, voxels, box, plane_shape) -> None:  # type: ignore[no-untyped-def]
    ny, nx = plane_shape[0], plane_shape[1]
    plane = ny * nx
    for p in voxels:
        z = p // plane
        y = (p - z * plane) // nx
        x = p - z * plane - y * nx
        out[z - box[0], y - box[1], x - box[2]] = True
