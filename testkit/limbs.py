"""Blobs with limbs: bodies with straight or slightly curved limbs whose axes are known.

A body (ellipse, circle, cell with a wavy outline, small soma, fruit with a dimple) gets
one to five limbs of several widths and lengths beyond the body, some close beside
another, or a fruit its stem. Each limb is a tube of constant half-width around a
polyline that starts inside the body, leaves it at its *exit* and runs on to a round or
flat end; ``length`` is how far the shape reaches beyond the body along that polyline.
A skeleton *keeps* a limb when it reaches into the limb, beyond the body, by at least
half that length (:func:`limb_reach`).

:func:`box_limb_test` is the limb test as first written (the box of the branch's disks,
its counts and a distance transform), the oracle of the pipeline's;
:func:`checked_limb_tests` makes every limb test of the pipeline compare the two.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np
from numba import njit

from skelprune.grid._edt import _squared_edt
from skelprune.grid._rowcover import uncover

__all__ = [
    "BODIES",
    "Limb",
    "LimbShape",
    "box_limb_test",
    "checked_limb_tests",
    "limb_reach",
    "limb_shape",
    "limb_shapes",
]

#: Body kinds, drawn in turn.
BODIES = ("ellipse", "circle", "cell", "soma", "fruit")


@dataclass(frozen=True)
class Limb:
    """One limb: its axis beyond the body (``axis``: (n, 2) row/col samples a pixel
    apart, from the exit to the axis's end), ``half`` its half-width, ``length`` how far
    the shape reaches beyond the body along the axis (to the end of the round cap, or the
    flat end)."""

    axis: np.ndarray
    half: float
    length: float
    round_end: bool


@dataclass(frozen=True)
class LimbShape:
    name: str
    mask: np.ndarray
    body: np.ndarray
    limbs: tuple[Limb, ...]


def _body(kind: str, rng: np.random.Generator, yy, xx, cy, cx, size):
    """Body mask and its radius along a direction (by marching, below)."""
    if kind in ("ellipse", "circle"):
        a = size * (rng.uniform(1.0, 1.6) if kind == "ellipse" else 1.0)
        b = size * (rng.uniform(0.6, 1.0) if kind == "ellipse" else 1.0)
        t = rng.uniform(0, np.pi)
        u = (xx - cx) * np.cos(t) + (yy - cy) * np.sin(t)
        v = -(xx - cx) * np.sin(t) + (yy - cy) * np.cos(t)
        return (u / a) ** 2 + (v / b) ** 2 <= 1
    ang = np.arctan2(yy - cy, xx - cx)
    rad = np.hypot(yy - cy, xx - cx)
    if kind == "cell":
        r = np.full(ang.shape, size, float)
        for h in (2, 3, 5):
            r += size * rng.uniform(0.02, 0.08) * np.cos(h * ang + rng.uniform(0, 2 * np.pi))
        return rad <= r
    if kind == "soma":
        r = size * (1 + 0.06 * np.cos(2 * ang + rng.uniform(0, 2 * np.pi)))
        return rad <= r
    # fruit: a round body with a dimple at the top, where the stem leaves
    m = rad <= size
    dimple = (yy - (cy - 1.05 * size)) ** 2 + (xx - cx) ** 2 <= (0.35 * size) ** 2
    return m & ~dimple


def _exit(body: np.ndarray, cy: float, cx: float, theta: float) -> float:
    """Distance from the centre along ``theta`` to where the body ends."""
    d = 0.0
    h, w = body.shape
    while True:
        y, x = cy + (d + 0.5) * np.sin(theta), cx + (d + 0.5) * np.cos(theta)
        iy, ix = int(np.rint(y)), int(np.rint(x))
        if not (0 <= iy < h and 0 <= ix < w) or not body[iy, ix]:
            return d
        d += 0.5


def _polyline(p0: np.ndarray, u: np.ndarray, length: float, bend: float) -> np.ndarray:
    """Samples a pixel apart (about) of a gently bent path of ``length`` from ``p0``."""
    n = max(int(np.ceil(length)), 1)
    t = np.linspace(0.0, 1.0, n + 1)[:, None]
    normal = np.array([u[1], -u[0]])
    return p0 + t * length * u + bend * length * (t * t) * normal


def _tube(yy, xx, line: np.ndarray, half: float) -> np.ndarray:
    m = np.zeros(yy.shape, bool)
    lo = np.maximum(np.floor(line.min(0) - half - 1).astype(int), 0)
    hi = np.ceil(line.max(0) + half + 2).astype(int)
    win = (slice(lo[0], hi[0]), slice(lo[1], hi[1]))
    wy, wx = yy[win], xx[win]
    for (y0, x0), (y1, x1) in itertools.pairwise(line):
        dy, dx = y1 - y0, x1 - x0
        t = np.clip(((wy - y0) * dy + (wx - x0) * dx) / (dy * dy + dx * dx), 0, 1)
        m[win] |= (wy - y0 - t * dy) ** 2 + (wx - x0 - t * dx) ** 2 <= half * half
    return m


def _apart(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.min(np.hypot(*(a[:, None, :] - b[None, :, :]).transpose(2, 0, 1))))


def limb_shape(seed: int, kind: str | None = None) -> LimbShape:
    """One blob with limbs, drawn from ``seed`` (the body kind in turn unless given)."""
    rng = np.random.default_rng(seed)
    kind = kind or BODIES[seed % len(BODIES)]
    size = float(rng.uniform(12, 22) if kind == "soma" else rng.uniform(16, 60))
    n = 1 + int(rng.random() < 0.3) if kind == "fruit" else int(rng.integers(1, 6))
    reach = 3.2 * size + 20
    side = int(2 * (1.7 * size + reach)) + 8
    cy = cx = side / 2 + rng.uniform(-0.5, 0.5)
    yy, xx = np.mgrid[:side, :side].astype(float)
    body = _body(kind, rng, yy, xx, cy, cx, size)
    mask = body.copy()
    limbs: list[Limb] = []
    tries = 0
    while len(limbs) < n and tries < 60:
        tries += 1
        if kind == "fruit" and not limbs:
            theta, half = -np.pi / 2 + rng.uniform(-0.2, 0.2), rng.uniform(1.5, 3.0)
            length = rng.uniform(0.3, 0.8) * size + 3 * half
        else:
            if limbs and rng.random() < 0.35:  # close beside an earlier limb
                near = limbs[int(rng.integers(len(limbs)))]
                a0 = np.arctan2(*(near.axis[1] - near.axis[0]))
                theta = a0 + rng.choice([-1, 1]) * rng.uniform(0.25, 0.6)
            else:
                theta = rng.uniform(-np.pi, np.pi)
            top = 3.0 if kind == "soma" else min(0.3 * size, 10.0)
            half = rng.uniform(1.5, max(top, 1.6))
            longest = (3.0 if kind == "soma" else 1.6) * size
            length = rng.uniform(max(3.0 * half, 8.0), max(longest, 3.0 * half + 8))
        u = np.array([np.sin(theta), np.cos(theta)])
        d = _exit(body, cy, cx, theta)
        exit_ = np.array([cy, cx]) + d * u
        round_end = bool(rng.random() < 0.6)
        axis_len = length - half if round_end else length
        bend = rng.uniform(-0.15, 0.15) if rng.random() < 0.5 else 0.0
        outside = _polyline(exit_, u, axis_len, bend)
        line = np.vstack([np.array([cy, cx]) + 0.5 * d * u, outside])
        if any(_apart(outside, o.axis) < half + o.half + 2.5 for o in limbs):
            continue  # would touch another limb beyond the body
        tube = _tube(yy, xx, line, half)
        if not round_end:  # flat end: nothing beyond the axis's end
            end = outside[-1]
            direction = outside[-1] - outside[-2]
            direction /= np.hypot(*direction)
            tube &= (yy - end[0]) * direction[0] + (xx - end[1]) * direction[1] <= 0
        mask |= tube
        limbs.append(Limb(outside, half, float(length), round_end))
    rows, cols = np.nonzero(mask)
    top, left = rows.min() - 4, cols.min() - 4
    crop = (slice(top, rows.max() + 5), slice(left, cols.max() + 5))
    shift = np.array([top, left], float)
    limbs = [Limb(lb.axis - shift, lb.half, lb.length, lb.round_end) for lb in limbs]
    return LimbShape(f"{kind}-{seed}", mask[crop], body[crop], tuple(limbs))


def limb_shapes(n: int, seed: int = 0) -> list[LimbShape]:
    """``n`` blobs with limbs, seeded: the body kinds in turn."""
    return [limb_shape(seed * 100_000 + i, BODIES[i % len(BODIES)]) for i in range(n)]


def limb_reach(limb: Limb, body: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> float:
    """How far beyond the body (along the limb's axis) skeleton pixels ``rows, cols``
    reach into the limb: the largest arc position, from the exit, of a skeleton pixel
    outside the body and within the limb's half-width (plus 1.5 px) of its axis."""
    if rows.size == 0:
        return 0.0
    out = ~body[rows, cols]
    pts = np.stack([rows[out], cols[out]], 1).astype(float)
    if not len(pts):
        return 0.0
    seg = np.hypot(*np.diff(limb.axis, axis=0).T)
    arc = np.concatenate([[0.0], np.cumsum(seg)])
    d = np.hypot(*(pts[:, None, :] - limb.axis[None, :, :]).transpose(2, 0, 1))
    near = d.argmin(1)
    inside = d[np.arange(len(pts)), near] <= limb.half + 1.5
    return float(arc[near[inside]].max()) if inside.any() else 0.0


def round_ended(seed: int) -> tuple[np.ndarray, list[tuple[float, float, float]]]:
    """A lollipop (one disc on a stick) or a dumbbell (two discs and a bar), seeded, off
    the pixel grid: the mask and each disc's (row, col, radius), whose axis should end
    at the centre."""
    rng = np.random.default_rng(seed)
    discs = []
    n = 1 + int(rng.random() < 0.5)
    size = 6 * 60 + 40
    yy, xx = np.mgrid[:size, :size].astype(float)
    theta = rng.uniform(-np.pi, np.pi)
    u = np.array([np.sin(theta), np.cos(theta)])
    start = np.array([size / 2, size / 2]) - u * rng.uniform(60, 150) + rng.uniform(-0.5, 0.5, 2)
    length = rng.uniform(60, 200)
    end = start + u * length
    rmax = 0.0
    for p in [end] if n == 1 else [start, end]:
        r = float(rng.uniform(10, 50))
        discs.append((float(p[0]), float(p[1]), r))
        rmax = max(rmax, r)
    half = float(rng.uniform(2.0, max(0.3 * min(d[2] for d in discs), 2.5)))
    m = _tube(yy, xx, np.stack([start, end]), half)
    for cy, cx, r in discs:
        m |= (yy - cy) ** 2 + (xx - cx) ** 2 < r * r
    rows, cols = np.nonzero(m)
    top, left = rows.min() - 4, cols.min() - 4
    crop = m[top : rows.max() + 5, left : cols.max() + 5]
    return crop, [(cy - top, cx - left, r) for cy, cx, r in discs]


def box_limb_test(graph, mask: np.ndarray, r2: np.ndarray, b: int) -> bool:
    """The limb test of end branch ``b`` on ``graph``'s current skeleton as first written
    (docs/algorithm.md, "Limbs"): the disk counts of every live point, the counts without
    the branch's disks over the box of its disks, and a distance transform of the pixels
    only the branch covers; a point's disk is whole when its centre lies at least its
    radius from any other pixel. The oracle of :class:`skelprune.grid.limbs.LimbGuard`
    (without its area screen, ``exclusive``, and its memory of the limbs found)."""
    from skelprune.grid._rowcover import cover_counts

    alive = graph.alive_points()
    h, w = mask.shape
    counts = cover_counts(h, w, graph.rows[alive], graph.cols[alive], r2[alive])
    pts = np.asarray(graph.branches[b].points, np.int64)
    whole, widest = _box_whole_disks(counts, graph.rows[pts], graph.cols[pts], r2[pts])
    return bool(whole > 0 and whole >= 2.0 * math.sqrt(float(widest)))


@njit(cache=True)
def _box_whole_disks(counts, rows, cols, r2):
    """How many of a branch's points deeper than the rim have their whole disk covered
    by the branch alone, and the largest squared radius among them (0, 0 when fewer than
    4 points are deeper than the rim: ``2·r > 2·√2`` needs at least 4).

    ``counts``: the disk counts of the current skeleton, the branch's disks included.
    """
    deep = 0
    for k in range(r2.size):
        if r2[k] > 2:
            deep += 1
    if deep < 4:
        return 0, 0
    # The box of the branch's disks and one pixel more: what it alone covers lies
    # inside, with a pixel it does not cover all around (for the distances).
    h, w = counts.shape
    top, left, bottom, right = h, w, 0, 0
    for k in range(rows.size):
        rad = math.ceil(math.sqrt(r2[k]))
        top = min(top, rows[k] - rad)
        left = min(left, cols[k] - rad)
        bottom = max(bottom, rows[k] + rad + 1)
        right = max(right, cols[k] + rad + 1)
    top, left = max(top, 0), max(left, 0)
    bottom, right = min(bottom, h), min(right, w)
    before = counts[top:bottom, left:right]
    after = before.copy()
    uncover(after, rows - top, cols - left, r2)
    d2 = _squared_edt((after == 0) & (before > 0))
    whole = widest = 0
    for k in range(rows.size):
        if r2[k] > 2 and d2[rows[k] - top, cols[k] - left] >= r2[k]:
            whole += 1
            widest = max(widest, r2[k])
    return whole, widest


@contextmanager
def checked_limb_tests() -> Iterator[list[int]]:
    """Within the block, every limb test of the image grid's pruning is also made by
    :func:`box_limb_test` and the two must agree (``AssertionError`` otherwise); yields a
    list whose one item counts the tests compared."""
    from skelprune.grid.limbs import MIN_LIMB_AREA, LimbGuard
    from skelprune.skeleton import Skeleton

    calls = [0]

    class Checked(LimbGuard):
        def is_limb(self, b: int, exclusive: int) -> bool:
            known = bool(self.limb[b])
            found = super().is_limb(b, exclusive)
            if not known and exclusive >= MIN_LIMB_AREA:
                expected = box_limb_test(self.graph, self.mask, self.r2, b)
                assert found == expected, (b, found, expected)
                calls[0] += 1
            return found

    original = Skeleton.limb_test

    def limb_test(self: Skeleton, graph):  # type: ignore[no-untyped-def]
        guard = original(self, graph)
        checked = Checked(graph, guard.mask, guard.r2)
        checked.limb[:] = guard.limb
        return checked

    Skeleton.limb_test = limb_test  # type: ignore[method-assign]
    try:
        yield calls
    finally:
        Skeleton.limb_test = original  # type: ignore[method-assign]
