"""Synthetic volumes with known centre lines and tips, for tests and benchmarks.

Every shape is a **swept ball**: the union of the balls of radius ``r(c)`` centred on
densely sampled points ``c`` of its centre lines, in physical units, rasterised on a
grid of the given ``spacing = (dz, dy, dx)``. Its curve skeleton is then its centre
lines, and a free end's tip is the centre of its end cap: the last centre point.

- :func:`random_tree`: random branching tubes (seeded), radii from 12 down to 1.5
  (physical units, one unit = the finest voxel), smooth or with surface noise;
- :func:`tube`, :func:`y_tubes`, :func:`torus`, :func:`linked_tori`, :func:`ball`:
  the simple shapes the tests reason about (one branch, one junction, tunnels);
- :func:`random_blobs`: small random lumps for the exactness tests.

A :class:`SweptShape` keeps the signed distance to its clean surface, so that noisy
variants of the same shape (:meth:`SweptShape.volume` with ``noise``) share their
centre lines and tips with the clean one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit

__all__ = [
    "LabelVolume",
    "SweptShape",
    "ball",
    "linked_tori",
    "random_blobs",
    "random_tree",
    "torus",
    "touching_trees",
    "tube",
    "y_tubes",
]

_STEP = 0.5  # physical distance between centre samples


@dataclass
class SweptShape:
    """A shape swept by balls along centre lines.

    Attributes
    ----------
    shape : (Z, Y, X)
    spacing : (dz, dy, dx)
    lines : list of (k, 3) float arrays
        Centre lines in physical coordinates ``(z, y, x)`` (voxel index × spacing).
    radii : list of (k,) float arrays
        The ball radius at each centre point.
    tips : (t, 3) float array
        The free ends of the centre lines, physical coordinates.
    tunnels : int
        The number of tunnels (independent cycles of the centre lines).
    """

    shape: tuple[int, int, int]
    spacing: tuple[float, float, float]
    lines: list[np.ndarray]
    radii: list[np.ndarray]
    tips: np.ndarray
    tunnels: int = 0
    _field: np.ndarray | None = field(default=None, repr=False)

    def signed_distance(self) -> np.ndarray:
        """Distance of each voxel centre to the clean surface (negative inside), float32."""
        if self._field is None:
            f = np.full(self.shape, np.inf, dtype=np.float32)
            sp = np.array(self.spacing, dtype=np.float64)
            for line, r in zip(self.lines, self.radii, strict=True):
                _sweep(f, np.asarray(line, np.float64), np.asarray(r, np.float64), sp)
            self._field = f
        return self._field

    def volume(self, noise: float = 0.0, seed: int = 0) -> np.ndarray:
        """The shape as a bool volume; with ``noise``, its surface moved by a smooth
        random field of that standard deviation (physical units, correlated over about
        a voxel), keeping the largest 26-connected component without cavities."""
        f = self.signed_distance()
        if noise <= 0:
            return f < 0
        from scipy import ndimage

        rng = np.random.default_rng(seed)
        n = ndimage.gaussian_filter(rng.standard_normal(self.shape).astype(np.float32), 1.0)
        n *= noise / max(float(n.std()), 1e-12)
        v = f < n
        lab, count = ndimage.label(v, structure=np.ones((3, 3, 3)))
        if count > 1:
            sizes = np.bincount(lab.ravel())
            sizes[0] = 0
            v = lab == int(np.argmax(sizes))
        return ndimage.binary_fill_holes(v)

    def centre_mask(self) -> np.ndarray:
        """The voxels the centre lines pass through (rounded), a bool volume."""
        out = np.zeros(self.shape, dtype=bool)
        sp = np.array(self.spacing)
        for line in self.lines:
            idx = np.rint(line / sp).astype(np.int64)
            idx = np.clip(idx, 0, np.array(self.shape) - 1)
            out[idx[:, 0], idx[:, 1], idx[:, 2]] = True
        return out

    def tip_voxels(self) -> np.ndarray:
        """The tips as voxel indices (float, ``physical / spacing``)."""
        return np.asarray(self.tips, np.float64).reshape(-1, 3) / np.array(self.spacing)


@njit(cache=True)
def _sweep(f, line, radii, spacing) -> None:
    """``f = min(f, |p − c| − r(c))`` over the centre samples, in a box around each."""
    nz, ny, nx = f.shape
    for k in range(line.shape[0]):
        r = radii[k]
        lo = np.empty(3, np.int64)
        hi = np.empty(3, np.int64)
        size = (nz, ny, nx)
        for a in range(3):
            lo[a] = max(int(np.floor((line[k, a] - r - 2.0) / spacing[a])), 0)
            hi[a] = min(int(np.ceil((line[k, a] + r + 2.0) / spacing[a])), size[a] - 1)
        for z in range(lo[0], hi[0] + 1):
            dz = z * spacing[0] - line[k, 0]
            for y in range(lo[1], hi[1] + 1):
                dy = y * spacing[1] - line[k, 1]
                for x in range(lo[2], hi[2] + 1):
                    dx = x * spacing[2] - line[k, 2]
                    d = math.sqrt(dz * dz + dy * dy + dx * dx) - r
                    if d < f[z, y, x]:
                        f[z, y, x] = d


def _segment(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    n = max(math.ceil(np.linalg.norm(b - a) / _STEP), 1)
    t = np.linspace(0.0, 1.0, n + 1)[:, None]
    return a[None, :] * (1 - t) + b[None, :] * t


def _extent(shape, spacing) -> np.ndarray:
    return (np.array(shape) - 1) * np.array(spacing, dtype=np.float64)


def tube(
    length: float = 40.0,
    radius: float = 4.0,
    spacing: tuple[float, float, float] = (1.0, 1.0, 1.0),
    margin: float = 3.0,
) -> SweptShape:
    """A straight tube along ``x`` with round caps: one branch, two tips."""
    side = 2 * (radius + margin)
    ext = np.array([side, side, length + 2 * (radius + margin)])
    shape = tuple(math.ceil(e / s) + 1 for e, s in zip(ext, spacing, strict=True))
    mid = _extent(shape, spacing) / 2
    a = np.array([mid[0], mid[1], radius + margin])
    b = a + np.array([0.0, 0.0, length])
    line = _segment(a, b)
    return SweptShape(shape, spacing, [line], [np.full(len(line), radius)], np.array([a, b]))


def y_tubes(radius: float = 3.0, arm: float = 24.0) -> SweptShape:
    """Three straight tubes from one point at 120° in a plane: three tips, one junction."""
    size = int(2 * (arm + radius + 3)) + 1
    c = np.full(3, (size - 1) / 2)
    lines, tips = [], []
    for k in range(3):
        t = 2 * math.pi * k / 3 + 0.3
        end = c + arm * np.array([0.25, math.sin(t), math.cos(t)])
        lines.append(_segment(c, end))
        tips.append(end)
    radii = [np.full(len(line), radius) for line in lines]
    return SweptShape((size, size, size), (1.0, 1.0, 1.0), lines, radii, np.array(tips))


def torus(major: float = 14.0, minor: float = 4.0, tilt: float = 0.0) -> SweptShape:
    """A ring tube: one tunnel, no tip."""
    size = int(2 * (major + minor + 3)) + 1
    c = np.full(3, (size - 1) / 2)
    line = _circle(c, major, tilt)
    return SweptShape(
        (size, size, size),
        (1.0, 1.0, 1.0),
        [line],
        [np.full(len(line), minor)],
        np.zeros((0, 3)),
        tunnels=1,
    )


def linked_tori(major: float = 12.0, minor: float = 4.0) -> SweptShape:
    """Two ring tubes side by side, fused where they touch: two tunnels."""
    size_x = int(4 * major + 3 * minor + 6) + 1
    size = int(2 * (major + minor + 3)) + 1
    c1 = np.array([(size - 1) / 2, (size - 1) / 2, major + minor + 3])
    c2 = c1 + np.array([0.0, 0.0, 2 * major + minor])  # the tubes overlap by ``minor``
    lines = [_circle(c1, major, 0.0), _circle(c2, major, 0.0)]
    return SweptShape(
        (size, size, size_x),
        (1.0, 1.0, 1.0),
        lines,
        [np.full(len(l_), minor) for l_ in lines],
        np.zeros((0, 3)),
        tunnels=2,
    )


def _circle(c: np.ndarray, radius: float, tilt: float) -> np.ndarray:
    n = math.ceil(2 * math.pi * radius / _STEP)
    t = np.linspace(0, 2 * math.pi, n + 1)
    return c + radius * np.stack(
        [np.sin(t) * math.sin(tilt), np.sin(t) * math.cos(tilt), np.cos(t)], axis=1
    )


def ball(radius: float = 8.0) -> SweptShape:
    """A ball centred on a voxel: its skeleton is that voxel."""
    size = 2 * int(radius + 3) + 1
    c = np.full((1, 3), (size - 1) / 2)
    return SweptShape((size, size, size), (1.0, 1.0, 1.0), [c], [np.array([radius])], c.copy())


def random_tree(
    seed: int,
    size: int = 128,
    spacing: tuple[float, float, float] = (1.0, 1.0, 1.0),
    depth: int = 3,
    r_root: float | None = None,
) -> SweptShape:
    """Random branching tubes in a cube of ``size`` voxels along ``y`` and ``x`` (and as
    many physical units along ``z``): curved branches that fork in two, thinner at each
    level, radii from ``r_root`` (default ``min(12, size / 12)``) down to no less than
    1.5 and no less than the coarsest voxel side (thinner tubes fall apart on the grid).
    """
    rng = np.random.default_rng(seed)
    sp = np.array(spacing, dtype=np.float64)
    shape = (round((size - 1) / sp[0] * sp[2]) + 1, size, size)
    ext = _extent(shape, spacing)
    r_min = max(1.5, float(sp.max()))
    r0 = float(min(12.0, size / 12)) if r_root is None else float(r_root)
    lines: list[np.ndarray] = []
    radii: list[np.ndarray] = []
    tips: list[np.ndarray] = []
    start = ext * np.array([0.5, 0.5, 0.0]) + np.array([0, 0, r0 + 3])
    start += rng.uniform(-0.15, 0.15, 3) * ext * np.array([1, 1, 0])
    tips.append(start.copy())
    todo = [(start, np.array([0.0, 0.0, 1.0]), r0, 0)]
    while todo:
        p, d, r, level = todo.pop()
        length = rng.uniform(0.22, 0.32) * size * (0.8**level)
        r_end = max(r * 0.85, r_min)
        pts = [p]
        bend = rng.normal(0, 1, 3)
        for i in range(int(length / _STEP)):
            bend = 0.9 * bend + 0.1 * rng.normal(0, 1, 3)
            d = d + 0.02 * bend
            q = pts[-1]
            margin = r + 4
            for a in range(3):  # steer back from the walls
                if q[a] < margin:
                    d[a] += 0.05
                elif q[a] > ext[a] - margin:
                    d[a] -= 0.05
            d /= np.linalg.norm(d)
            pts.append(np.clip(q + _STEP * d, margin * 0.5, ext - margin * 0.5))
            del i
        line = np.array(pts)
        lines.append(line)
        radii.append(np.linspace(r, r_end, len(line)))
        if level < depth and r_end * 0.6 >= r_min * 0.999:
            for sign in (-1, 1):
                axis = np.cross(d, rng.normal(0, 1, 3))
                axis /= np.linalg.norm(axis)
                angle = sign * rng.uniform(0.5, 0.9)
                child = _rotate(d, axis, angle)
                todo.append((line[-1], child, max(r_end * rng.uniform(0.6, 0.8), r_min), level + 1))
        else:
            tips.append(line[-1].copy())
    return SweptShape(shape, spacing, lines, radii, np.array(tips))


def random_blobs(seed: int, shape: tuple[int, int, int] = (12, 14, 16)) -> np.ndarray:
    """A small union of random balls and boxes: lumps, necks, sometimes tunnels."""
    rng = np.random.default_rng(seed)
    grid = np.indices(shape).transpose(1, 2, 3, 0)
    v = np.zeros(shape, bool)
    for _ in range(rng.integers(2, 6)):
        c = rng.uniform(0, 1, 3) * np.array(shape)
        v |= ((grid - c) ** 2).sum(-1) < rng.uniform(2, 20)
    for _ in range(rng.integers(0, 3)):
        lo = rng.integers(0, np.array(shape) - 2)
        hi = lo + rng.integers(2, 9, 3)
        v[lo[0] : hi[0], lo[1] : hi[1], lo[2] : hi[2]] = True
    return v


def _rotate(v: np.ndarray, axis: np.ndarray, angle: float) -> np.ndarray:
    """``v`` turned by ``angle`` about the unit ``axis`` (Rodrigues)."""
    return (
        v * math.cos(angle)
        + np.cross(axis, v) * math.sin(angle)
        + axis * float(axis @ v) * (1 - math.cos(angle))
    )


@dataclass
class LabelVolume:
    """A label volume of touching objects with known centre lines.

    Attributes
    ----------
    labels : (Z, Y, X) uint32 array
        0 outside; each object its own value ``1 .. n``.
    truth : SweptShape
        Every object's centre lines and tips, in the volume's frame, keeping only the
        centre points (and tips) whose voxel carries that object's label: where an object
        runs into an earlier one it is cut there, and its centre line with it (the cut
        is a tip: a free end of the object).
    """

    labels: np.ndarray
    truth: SweptShape


def touching_trees(
    n: int, side: int = 256, seed: int = 0, tree_size: int | None = None
) -> LabelVolume:
    """``n`` small random trees (:func:`random_tree`, ``tree_size`` voxels a side,
    default ``max(24, 2.4·side / n^(1/3))``) packed into a ``side``³ cube, each its own
    label. Trees are placed at random corners, first come first served: a tree keeps only
    the voxels no earlier tree holds, so neighbours touch along their cut faces."""
    rng = np.random.default_rng(seed)
    size = tree_size or max(24, round(2.4 * side / n ** (1 / 3)))
    size = min(size, side)
    labels = np.zeros((side, side, side), np.uint32)
    lines: list[np.ndarray] = []
    radii: list[np.ndarray] = []
    tips: list[np.ndarray] = []
    for k in range(n):
        tree = random_tree(int(rng.integers(1 << 30)), size, depth=2)
        mask = tree.volume()
        corner = rng.integers(0, side - size + 1, 3)
        box = tuple(slice(int(c), int(c) + size) for c in corner)
        region = labels[box]
        mine = mask & (region == 0)
        region[mine] = k + 1
        for line, r in zip(tree.lines, tree.radii, strict=True):
            idx = np.rint(line).astype(np.int64).clip(0, size - 1)
            keep = mine[idx[:, 0], idx[:, 1], idx[:, 2]]
            # each run of kept points a line of its own
            edges = np.flatnonzero(np.diff(np.concatenate([[0], keep.astype(np.int8), [0]])))
            for a, b in zip(edges[::2], edges[1::2], strict=True):
                lines.append(line[a:b] + corner)
                radii.append(r[a:b])
                # where an earlier tree cuts the line, the cut is a free end of this one
                if a > 0:
                    tips.append(line[a] + corner)
                if b < len(line):
                    tips.append(line[b - 1] + corner)
        for t in tree.tips:
            i = np.rint(t).astype(np.int64).clip(0, size - 1)
            if mine[i[0], i[1], i[2]]:
                tips.append(t + corner)
    truth = SweptShape(
        (side, side, side), (1.0, 1.0, 1.0), lines, radii, np.array(tips).reshape(-1, 3)
    )
    return LabelVolume(labels, truth)
