"""The 3-D medial axis as a curve skeleton of a volume (docs/volumes.md).

Distance-ordered homotopic thinning (Pudney 1998): the voxels inside are visited in
the order of their squared radius ``r2`` (:mod:`skelprune.grid3d.distance`), smallest
first, and a voxel is deleted when it is simple for (26, 6) connectivity
(:mod:`skelprune.grid3d._topology`). A voxel found not simple leaves the queue and comes
back, at the level being thinned, when a neighbour is deleted, which keeps the order by
distance exact, so the voxels left sit on the ridge of the distance transform. A voxel
that is simple but a curve end point (one 26-neighbour) is kept for good, an
**anchor**, when it is the centre of a maximal ball: no 26-neighbour's ball contains its
ball (the discrete balls, exactly). End points that are not such centres are deleted,
so a branch retracts until its end is a centre of a maximal ball: that is where the
union of balls stops losing volume.

What comes out:

- one voxel thin: every voxel left is an anchored end point or not simple (deleting
  it would split a component or open a tunnel or a cavity), so a path is one voxel
  wide and only junctions keep small clusters;
- 26-connected and homotopic to the volume: the same components, and **each tunnel
  gives one cycle** of the skeleton;
- a **cavity** (background enclosed by the volume) cannot be kept by curves: the
  thinning leaves a closed shell of voxels one voxel thick around it, which the branch
  graph sees as a junction cluster. Fill cavities first (``scipy.ndimage.binary_fill_holes``)
  when a curve skeleton is wanted;
- every voxel with its ball: squared radius ``r2`` in physical units, the exact
  squared distance to the background.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from ._topology import ADJ6, ADJ26, FACES, N18, OFFSETS, end_point, is_simple, neighbourhood_code
from .balls import row_half_width
from .distance import check_spacing, check_volume, pad, padded_squared_distance

__all__ = ["CurveSkeleton", "curve_skeleton"]


@dataclass(frozen=True)
class CurveSkeleton:
    """The curve skeleton of a volume, in the volume's own frame.

    Attributes
    ----------
    z, y, x : (n,) int64
        Voxel coordinates of the skeleton, in raster order (``x`` the last array axis).
    r2 : (n,) float64
        Squared radius of each voxel's ball, in squared physical units.
    spacing : (dz, dy, dx)
        Physical size of a voxel.
    shape : (Z, Y, X)
        Shape of the volume.
    """

    z: np.ndarray
    y: np.ndarray
    x: np.ndarray
    r2: np.ndarray
    spacing: tuple[float, float, float]
    shape: tuple[int, int, int]

    @property
    def radius(self) -> np.ndarray:
        """Ball radius of each voxel, in physical units."""
        return np.sqrt(self.r2)

    def __len__(self) -> int:
        return int(self.z.size)

    def mask(self) -> np.ndarray:
        """The skeleton as a bool volume of :attr:`shape`."""
        out = np.zeros(self.shape, dtype=bool)
        out[self.z, self.y, self.x] = True
        return out


def curve_skeleton(
    volume: np.ndarray, spacing: tuple[float, float, float] = (1.0, 1.0, 1.0)
) -> CurveSkeleton:
    """The curve skeleton (3-D medial axis) of a volume.

    Parameters
    ----------
    volume : (Z, Y, X) array
        Non-zero inside; any number of 26-connected components.
    spacing : (dz, dy, dx)
        Physical size of a voxel along each axis.

    Returns
    -------
    CurveSkeleton

    Raises
    ------
    InvalidImageError
        Not a 3-D array.
    EmptyMaskError
        No voxel inside.
    InvalidOptionError
        A bad spacing.

    Examples
    --------
    >>> v = np.zeros((9, 9, 30), bool); v[2:7, 2:7, 3:27] = True   # a bar along x
    >>> sk = curve_skeleton(v)
    >>> int(((sk.z == 4) & (sk.y == 4)).sum()), len(sk)   # on its axis but one end voxel
    (20, 21)
    >>> float(sk.r2.max())
    9.0
    """
    spacing = check_spacing(spacing)
    padded = pad(check_volume(volume))
    r2 = padded_squared_distance(padded, spacing)
    inside = np.flatnonzero(padded)
    order = inside[np.argsort(r2.ravel()[inside], kind="stable")]
    del inside
    nz, ny, nx = padded.shape
    steps = OFFSETS[:, 0] * (ny * nx) + OFFSETS[:, 1] * nx + OFFSETS[:, 2]
    fg = padded.ravel()  # a view: the thinning deletes in place
    _thin(fg, r2.ravel(), order, steps, OFFSETS, np.array(spacing), ADJ26, ADJ6, N18, FACES)
    z, y, x = np.nonzero(padded)
    values = r2[z, y, x]
    return CurveSkeleton(
        (z - 1).astype(np.int64),
        (y - 1).astype(np.int64),
        (x - 1).astype(np.int64),
        values,
        spacing,
        (nz - 2, ny - 2, nx - 2),
    )


@njit(cache=True)
def _thin(fg, r2, order, steps, offsets, spacing, adj26, adj6, n18, faces) -> None:
    """Distance-ordered homotopic thinning of the flat padded volume ``fg`` in place.

    ``order``: the voxels inside, by ``r2`` (raster order among equals). Each level
    (one value of ``r2``) is thinned to the end before the next: first its voxels in
    order, then, first in first out, those queued again by a neighbour's deletion.
    """
    n = order.size
    queued = fg.copy()
    anchored = np.zeros(fg.size, dtype=np.bool_)
    ring = np.empty(n + 1, dtype=np.int64)  # a voxel is queued at most once at a time
    head = 0
    tail = 0
    k = 0
    while k < n:
        level = r2[order[k]]
        while True:
            if k < n and r2[order[k]] == level:
                p = order[k]
                k += 1
            elif head != tail:
                p = ring[head]
                head = head + 1 if head < n else 0
            else:
                break
            queued[p] = False
            if not fg[p] or anchored[p]:
                continue
            code = neighbourhood_code(fg, p, steps)
            if not is_simple(code, adj26, adj6, n18, faces):
                continue
            if end_point(code) and _maximal(r2, p, steps, offsets, spacing):
                anchored[p] = True
                continue
            fg[p] = False
            for i in range(26):
                q = p + steps[i]
                if fg[q] and not queued[q] and not anchored[q]:
                    ring[tail] = q
                    tail = tail + 1 if tail < n else 0
                    queued[q] = True


@njit(cache=True)
def _maximal(r2, p, steps, offsets, spacing) -> bool:
    """Whether the ball of voxel ``p`` lies in no 26-neighbour's ball.

    Ball ``{o : |o|² < r2(p)}`` over integer offsets, in physical units. For each row
    ``(a, b)`` of the ball only its two extreme voxels can be farthest from a neighbour
    (the distance is convex along the row), so a row costs two tests per neighbour.
    """
    sz, sy, sx = spacing[0], spacing[1], spacing[2]
    v = r2[p]
    farthest = np.zeros(26, dtype=np.float64)
    reach_a = int(math.sqrt(v) / sz) + 1
    reach_b = int(math.sqrt(v) / sy) + 1
    for a in range(-reach_a, reach_a + 1):
        az = a * sz
        for b in range(-reach_b, reach_b + 1):
            by = b * sy
            c = row_half_width(v, az * az + by * by, sx)
            if c < 0:
                continue
            for i in range(26):
                oz = (a - offsets[i, 0]) * sz
                oy = (b - offsets[i, 1]) * sy
                for sign in (-1, 1):
                    ox = (sign * c - offsets[i, 2]) * sx
                    d = oz * oz + oy * oy + ox * ox
                    if d > farthest[i]:
                        farthest[i] = d
    dominated = False  # a loop, not all(): numba compiles no generator there
    for i in range(26):
        dominated |= r2[p + steps[i]] > farthest[i]
    return not dominated
