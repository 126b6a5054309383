"""Shape perturbations and the rectangle ground truth of the stability benchmarks.

The stability benchmark and the paper's Figs. 6-7 and Table 2: boundary noise (Gaussian or uniform,
along the normal), rotation and rescaling. Every perturbation works on the *contour*,
not on the image: each boundary (outer and holes) is the closed crack curve between shape
and background (vertices at the midpoints of 4-adjacent shape/background pixel pairs,
marching squares with the shape 8-connected), which is moved and then filled again with
the pixel-centre rule (a pixel belongs to the shape iff its centre has non-zero winding
number). Unperturbed, this round trip reproduces the mask exactly.

:data:`PERTURBATIONS` names the perturbations once, for the benchmarks and the evaluation.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy import ndimage as ndi

from skelprune.grid._contours import boundary_polygons

__all__ = [
    "PERTURBATIONS",
    "Perturbation",
    "boundary_flips",
    "boundary_noise",
    "noisy_rectangle",
    "rectangle_medial_axis",
    "resampled_noise",
    "rescale",
    "rotate",
    "skeleton_distance",
    "skeleton_error",
]

NoiseKind = Literal["gaussian", "uniform"]
_EIGHT = np.ones((3, 3), bool)


def _rings(mask: np.ndarray) -> list[np.ndarray]:
    """Boundary polygons (row, col) of the union of the pixel squares, shape on the left.

    The crack polygons of :func:`~skelprune.grid._contours.boundary_polygons` give the
    midpoints; at each turn the pixel corner is put back, so the polygon has exact
    right-angled corners (holes wind the other way round).
    """
    rings = []
    for c, _ in boundary_polygons(np.asarray(mask, dtype=bool)):
        b = np.roll(c, -1, axis=0)
        turn = np.all(c != b, axis=1)
        half = np.abs(c - np.round(c)) > 0.25  # which coordinate of a vertex is on a border
        corner = np.where(half, c, b)
        out = np.empty((len(c) + int(turn.sum()), 2))
        pos = np.arange(len(c)) + np.r_[0, np.cumsum(turn)[:-1]]
        out[pos] = c
        out[pos[turn] + 1] = corner[turn]
        rings.append(out)
    return rings


def _signed_area(ring: np.ndarray) -> float:
    y, x = ring[:, 0], ring[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def _fill(rings: list[np.ndarray], shape: tuple[int, int]) -> np.ndarray:
    """Pixels whose centre has a non-zero winding number w.r.t. all rings together."""
    h, w = shape
    out = np.zeros(shape, bool)
    if not rings:
        return out
    a = np.concatenate(rings)
    b = np.concatenate([np.roll(r, -1, axis=0) for r in rings])
    y0, x0, y1, x1 = a[:, 0], a[:, 1], b[:, 0], b[:, 1]
    up = y1 > y0
    ylo, yhi = np.minimum(y0, y1), np.maximum(y0, y1)
    first = np.ceil(ylo).astype(np.int64)  # rows y with ylo <= y < yhi
    count = np.maximum(np.ceil(yhi).astype(np.int64) - first, 0)
    edge = np.repeat(np.arange(len(a)), count)
    row = first[edge] + (np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count))
    t = (row - y0[edge]) / (y1[edge] - y0[edge])
    xc = x0[edge] + t * (x1[edge] - x0[edge])
    wind = np.where(up[edge], 1, -1)
    inside = (row >= 0) & (row < h)
    row, xc, wind = row[inside], xc[inside], wind[inside]
    order = np.lexsort((xc, row))
    row, xc, wind = row[order], xc[order], wind[order]
    if len(row) == 0:
        return out
    run = np.cumsum(wind)
    start = np.r_[0, np.flatnonzero(np.diff(row)) + 1]
    run -= np.repeat(np.r_[0, run[start[1:] - 1]], np.diff(np.r_[start, len(row)]))
    # the interval after crossing k, up to crossing k+1 in the same row, is inside iff run != 0
    nxt_same = np.r_[row[1:] == row[:-1], False]
    sel = (run != 0) & nxt_same
    c0 = np.clip(np.ceil(xc[sel]).astype(np.int64), 0, w)
    c1 = np.clip(np.ceil(xc[1:][sel[:-1]]).astype(np.int64), 0, w)
    diff = np.zeros((h, w + 1), np.int64)
    np.add.at(diff, (row[sel], c0), 1)
    np.add.at(diff, (row[sel], c1), -1)
    return np.cumsum(diff, axis=1)[:, :w] > 0


def _hole_seeds(rings: list[np.ndarray], shape: tuple[int, int]) -> list[tuple[int, np.ndarray]]:
    """Per hole ring: its index and the hole pixel farthest from the shape (row, col)."""
    out = []
    for k, ring in enumerate(rings):
        if _signed_area(ring) > 0:  # outer boundaries are negative, holes positive
            hole = _fill([ring], shape)
            dist = ndi.distance_transform_edt(hole)
            out.append((k, np.array(np.unravel_index(np.argmax(dist), shape), np.float64)))
    return out


def _clean(filled: np.ndarray, holes: list[tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
    """Keep one component with exactly the original holes.

    ``holes`` pairs each moved hole ring with its moved seed pixel. The largest 8-connected
    component is kept (should the perturbation cut a part off). Of the enclosed background
    pockets, each hole keeps the one that overlaps its moved ring most; the rest were made
    by the perturbation (self-intersections, gaps closed by noise) and are filled. A hole
    the perturbation closed keeps its seed pixel, so a hole narrower than the noise survives.
    """
    lab, n = ndi.label(filled, structure=_EIGHT)
    if n > 1:
        filled = lab == 1 + int(np.argmax(np.bincount(lab.ravel())[1:]))
    h, w = filled.shape
    bg, nb = ndi.label(~filled)  # background is 4-connected
    enclosed = np.ones(nb + 1, bool)
    enclosed[np.unique(np.r_[bg[0], bg[-1], bg[:, 0], bg[:, -1]])] = False
    enclosed[0] = False
    kept: set[int] = set()
    carve = []
    for ring, seed in holes:
        inside = bg[_fill([ring], filled.shape)]
        counts = np.bincount(inside[enclosed[inside]], minlength=nb + 1)
        best = int(np.argmax(counts))
        if counts[best] > 0 and best not in kept:
            kept.add(best)
        else:
            carve.append(np.rint(seed).astype(np.int64))
    pockets = enclosed.copy()
    pockets[list(kept)] = False
    filled = filled | pockets[bg]
    for r, c in carve:
        if 0 <= r < h and 0 <= c < w:
            filled[r, c] = False
    return filled


def _crop(mask: np.ndarray, margin: int) -> np.ndarray:
    """The bounding box of the shape plus ``margin`` background pixels on every side."""
    rows, cols = np.nonzero(mask)
    if rows.size == 0:
        return np.zeros((2 * margin, 2 * margin), bool)
    box = mask[rows.min() : rows.max() + 1, cols.min() : cols.max() + 1]
    return np.pad(box, margin)


def _canvas(rings: list[np.ndarray], margin: int) -> tuple[list[np.ndarray], tuple[int, int]]:
    """Shift rings by an integer offset so that they fit with ``margin`` pixels around."""
    allp = np.concatenate(rings)
    lo = np.ceil(allp.min(axis=0)).astype(np.int64) - margin  # pixel centres that can be in
    hi = np.floor(allp.max(axis=0)).astype(np.int64) + margin
    return [r - lo for r in rings], (int(hi[0] - lo[0] + 1), int(hi[1] - lo[1] + 1))


def _transform(
    mask: np.ndarray, matrix: np.ndarray, centre: np.ndarray, margin: int
) -> tuple[np.ndarray, np.ndarray]:
    """The transformed mask, and the shift ``t`` of its frame: a point ``p`` of the input
    lands at ``(p - centre) @ matrix.T + centre - t`` in the output."""
    mask = np.asarray(mask, dtype=bool)
    rings = _rings(mask)
    if not rings:
        return mask.copy(), np.zeros(2)
    seeds = _hole_seeds(rings, mask.shape)
    moved = [(r - centre) @ matrix.T + centre for r in rings]
    moved_seeds = [((s - centre) @ matrix.T + centre).reshape(1, 2) for _, s in seeds]
    n = len(moved)
    allp = np.concatenate([*moved, *moved_seeds])
    lo = np.ceil(allp.min(axis=0)).astype(np.int64) - 1  # as _canvas with a margin of 1
    shifted, shape = _canvas([*moved, *moved_seeds], 1)
    holes = [(shifted[k], shifted[n + j][0]) for j, (k, _) in enumerate(seeds)]
    cleaned = _clean(_fill(shifted[:n], shape), holes)
    rows, cols = np.nonzero(cleaned)
    box = np.array([rows.min(), cols.min()]) if rows.size else np.zeros(2, np.int64)
    return _crop(cleaned, margin), (lo + box - margin).astype(np.float64)


def _rotation(degrees: float) -> np.ndarray:
    a = np.deg2rad(degrees)
    c, s = np.cos(a), np.sin(a)
    # (row, col) with rows pointing down: counter-clockwise on screen
    return np.array([[c, -s], [s, c]])


def _rotation_centre(mask: np.ndarray) -> np.ndarray:
    return np.array([mask.shape[0] // 2, mask.shape[1] // 2], np.float64)  # a pixel centre


def _scale_centre(mask: np.ndarray) -> np.ndarray:
    return np.array([mask.shape[0] // 2, mask.shape[1] // 2], np.float64) - 0.5


def rotate(mask: np.ndarray, degrees: float, margin: int = 2) -> np.ndarray:
    """Rotate a shape counter-clockwise (as displayed, like ``np.rot90``) by its contour.

    The crack contours are rotated about the pixel nearest the image centre and filled
    again; the output is the tight box of the result plus ``margin`` pixels.

    Examples
    --------
    >>> m = np.zeros((5, 8), bool); m[1:3, 1:7] = True
    >>> r = rotate(m, 90, margin=0)
    >>> bool(np.array_equal(r, np.rot90(m[1:3, 1:7])))
    True
    """
    return _transform(mask, _rotation(degrees), _rotation_centre(mask), margin)[0]


def rescale(mask: np.ndarray, factor: float, margin: int = 2) -> np.ndarray:
    """Scale a shape by ``factor`` (its contour, not the image) and fill it again.

    Examples
    --------
    >>> m = np.zeros((6, 6), bool); m[1:5, 1:5] = True
    >>> int(rescale(m, 2.0).sum())
    64
    """
    if factor <= 0:
        raise ValueError("factor must be positive")
    return _transform(mask, np.eye(2) * float(factor), _scale_centre(mask), margin)[0]


def boundary_noise(
    mask: np.ndarray,
    kind: NoiseKind,
    scale: float,
    rng: np.random.Generator | int | None = None,
    margin: int = 0,
) -> np.ndarray:
    """Move every contour point along its normal by random noise and fill again.

    Each vertex of each crack contour (outer and holes, about one per boundary pixel) moves
    along its normal (the perpendicular of the chord between its two neighbours) by
    ``N(0, scale²)`` (``kind="gaussian"``) or ``U(-scale, scale)`` (``"uniform"``).
    Afterwards only the largest 8-connected component is kept (should the noise cut a thin
    part off) and enclosed background pockets that are not inside a moved hole are filled,
    so holes are kept and none is created. The output has the input's shape plus
    ``margin`` pixels on each side.

    Examples
    --------
    >>> m = np.zeros((40, 40), bool); m[5:35, 5:35] = True
    >>> n = boundary_noise(m, "gaussian", 1.0, rng=0)
    >>> n.shape, abs(int(n.sum()) - 900) < 60
    ((40, 40), True)
    """
    mask = np.asarray(mask, dtype=bool)
    rng = np.random.default_rng(rng)
    rings = _rings(mask)
    moved = []
    for r in rings:
        chord = np.roll(r, -1, axis=0) - np.roll(r, 1, axis=0)
        normal = np.stack([chord[:, 1], -chord[:, 0]], axis=1)
        normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-12)
        if kind == "gaussian":
            d = rng.normal(0.0, scale, len(r))
        elif kind == "uniform":
            d = rng.uniform(-scale, scale, len(r))
        else:
            raise ValueError(f"unknown noise kind {kind!r}")
        moved.append(r + margin + d[:, None] * normal)
    shape = (mask.shape[0] + 2 * margin, mask.shape[1] + 2 * margin)
    holes = [(moved[k], seed + margin) for k, seed in _hole_seeds(rings, mask.shape)]
    return _clean(_fill(moved, shape), holes)


def resampled_noise(
    mask: np.ndarray,
    scale: float,
    rng: np.random.Generator | int | None = None,
    margin: int = 2,
) -> np.ndarray:
    """Gaussian noise along the normal of a contour resampled at one point a pixel.

    A second noise model, independent of :func:`boundary_noise` in every step: the
    contours are OpenCV's pixel-centre boundaries (``findContours``, not crack curves),
    resampled at unit arc length (the original resolution, not one point per crack
    edge), every sample moves along the normal of its chord by ``N(0, scale²)``, and
    the polygons are filled by ``fillPoly`` (pixels on or inside the outer polygons,
    minus the inside of the hole polygons), not by a winding rule on pixel centres.
    As in :func:`boundary_noise`, the largest 8-connected component is kept and the
    original holes, only those, are kept (a hole the noise closes keeps one pixel).
    The output is the input plus ``margin`` pixels on each side.

    Examples
    --------
    >>> m = np.zeros((40, 40), bool); m[5:35, 5:35] = True
    >>> n = resampled_noise(m, 1.0, rng=0)
    >>> n.shape, abs(int(n.sum()) - 900) < 90
    ((44, 44), True)
    """
    import cv2

    mask = np.asarray(mask, dtype=bool)
    rng = np.random.default_rng(rng)
    padded = np.pad(mask, margin).astype(np.uint8)
    contours, hierarchy = cv2.findContours(padded, cv2.RETR_CCOMP, cv2.CHAIN_APPROX_NONE)
    out = np.zeros_like(padded)
    holes_poly = []
    for k, c in enumerate(contours):
        xy = c[:, 0, :].astype(np.float64)
        if len(xy) >= 3:
            seg = np.hypot(*np.diff(xy, axis=0, append=xy[:1]).T)
            arc = np.r_[0.0, np.cumsum(seg)]
            n = max(3, round(float(arc[-1])))
            t = np.arange(n) * (arc[-1] / n)
            closed = np.vstack([xy, xy[:1]])
            xy = np.stack([np.interp(t, arc, closed[:, 0]), np.interp(t, arc, closed[:, 1])], 1)
            chord = np.roll(xy, -1, axis=0) - np.roll(xy, 1, axis=0)
            normal = np.stack([chord[:, 1], -chord[:, 0]], axis=1)
            normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-12)
            xy = xy + rng.normal(0.0, scale, n)[:, None] * normal
        pts = np.round(xy * 16).astype(np.int32).reshape(-1, 1, 2)  # 4 fractional bits
        if hierarchy[0, k, 3] < 0:
            cv2.fillPoly(out, [pts], 1, lineType=cv2.LINE_8, shift=4)
        else:
            holes_poly.append(pts)
    for pts in holes_poly:  # the hole's inside goes, its boundary pixels stay shape
        cv2.fillPoly(out, [pts], 0, lineType=cv2.LINE_8, shift=4)
        cv2.polylines(out, [pts], True, 1, lineType=cv2.LINE_8, shift=4)
    rings = _rings(mask)
    holes = [(rings[k] + margin, seed + margin) for k, seed in _hole_seeds(rings, mask.shape)]
    return _clean(out.astype(bool), holes)


def boundary_flips(
    mask: np.ndarray,
    share: float,
    rng: np.random.Generator | int | None = None,
    margin: int = 2,
) -> np.ndarray:
    """Flip each boundary pixel, inside or outside, with probability ``share``.

    A third noise model, on the pixels themselves: the shape pixels 4-adjacent to the
    background and the background pixels 4-adjacent to the shape each change side
    with probability ``share`` (0.5: a coin per pixel). Then, as in
    :func:`boundary_noise`, the largest 8-connected component and exactly the original
    holes are kept. The output is the input plus ``margin`` pixels on each side.

    Examples
    --------
    >>> m = np.zeros((40, 40), bool); m[5:35, 5:35] = True
    >>> n = boundary_flips(m, 0.5, rng=0)
    >>> n.shape, abs(int(n.sum()) - 900) < 60
    ((44, 44), True)
    """
    mask = np.asarray(mask, dtype=bool)
    rng = np.random.default_rng(rng)
    padded = np.pad(mask, margin)
    cross = ndi.generate_binary_structure(2, 1)
    band = (padded & ~ndi.binary_erosion(padded, cross)) | (
        ~padded & ndi.binary_dilation(padded, cross)
    )
    flipped = padded ^ (band & (rng.random(padded.shape) < share))
    rings = _rings(mask)
    holes = [(rings[k] + margin, seed + margin) for k, seed in _hole_seeds(rings, mask.shape)]
    return _clean(flipped, holes)


def skeleton_distance(a_rc: np.ndarray, b_rc: np.ndarray, area: float) -> float:
    """Symmetric mean distance between two skeletons' points, over ``√area``.

    The mean of (mean distance of each point of ``a`` to the nearest of ``b``) and the
    same from ``b`` to ``a``, divided by the square root of the shape's area, so that
    it reads the same at every scale. ``nan`` if either skeleton is empty.

    Examples
    --------
    >>> a = np.array([[0, 0], [0, 1], [0, 2]]); b = np.array([[1, 0], [1, 1], [1, 2]])
    >>> skeleton_distance(a, b, 100.0)
    0.1
    """
    from scipy.spatial import cKDTree

    a = np.asarray(a_rc, np.float64).reshape(-1, 2)
    b = np.asarray(b_rc, np.float64).reshape(-1, 2)
    if len(a) == 0 or len(b) == 0 or not area > 0:
        return float("nan")
    d_ab = cKDTree(b).query(a)[0].mean()
    d_ba = cKDTree(a).query(b)[0].mean()
    return float(0.5 * (d_ab + d_ba) / np.sqrt(area))


def rectangle_medial_axis(top: float, left: float, bottom: float, right: float) -> np.ndarray:
    """Segments ``(m, 2, 2)`` of (row, col) of the medial axis of an axis-parallel rectangle.

    The centre segment (a point for a square) and the four half-diagonals from the corners.
    """
    h, w = bottom - top, right - left
    half = min(h, w) / 2.0
    cy, cx = (top + bottom) / 2.0, (left + right) / 2.0
    if w >= h:
        e0, e1 = (cy, left + half), (cy, right - half)
    else:
        e0, e1 = (top + half, cx), (bottom - half, cx)
    segs = [(e0, e1), ((top, left), e0), ((bottom, left), e0)]
    segs += [((top, right), e1), ((bottom, right), e1)]
    if w < h:
        segs[2], segs[3] = ((top, right), e0), ((bottom, left), e1)
    return np.array(segs, dtype=np.float64)


def noisy_rectangle(
    height: int,
    width: int,
    kind: NoiseKind,
    scale: float,
    rng: np.random.Generator | int | None = None,
    margin: int = 8,
) -> tuple[np.ndarray, np.ndarray]:
    """A ``height × width`` rectangle with boundary noise, and its ground-truth skeleton.

    The ground truth ``G`` is the exact medial axis of the noise-free rectangle of pixel
    squares (its edges on the pixel borders, half a pixel outside the extreme pixel
    centres), in the returned mask's (row, col) frame: see :func:`rectangle_medial_axis`.

    Examples
    --------
    >>> mask, g = noisy_rectangle(20, 40, "uniform", 1.0, rng=0)
    >>> mask.shape, g.shape
    ((36, 56), (5, 2, 2))
    """
    mask = np.zeros((height + 2 * margin, width + 2 * margin), bool)
    mask[margin : margin + height, margin : margin + width] = True
    if scale > 0:
        mask = boundary_noise(mask, kind, scale, rng)
    g = rectangle_medial_axis(
        margin - 0.5, margin - 0.5, margin + height - 0.5, margin + width - 0.5
    )
    return mask, g


def skeleton_error(points_rc: np.ndarray, segments: np.ndarray) -> float:
    """Eq. 13 of the paper: mean squared distance of each point to the closest point of G.

    Examples
    --------
    >>> g = np.array([[[0.0, 0.0], [0.0, 10.0]]])
    >>> skeleton_error(np.array([[1, 5], [0, 12], [0, 3]]), g)
    1.6666666666666667
    """
    p = np.asarray(points_rc, dtype=np.float64).reshape(-1, 1, 2)
    if p.shape[0] == 0:
        return 0.0
    s = np.asarray(segments, dtype=np.float64).reshape(1, -1, 2, 2)
    a, d = s[..., 0, :], s[..., 1, :] - s[..., 0, :]
    dd = np.maximum(np.sum(d * d, axis=-1), 1e-300)
    t = np.clip(np.sum((p - a) * d, axis=-1) / dd, 0.0, 1.0)
    diff = p - (a + t[..., None] * d)
    return float(np.mean(np.min(np.sum(diff * diff, axis=-1), axis=1)))


@dataclass(frozen=True)
class Perturbation:
    """One named perturbation of the stability benchmark.

    ``kind`` is ``"gaussian"``/``"uniform"`` (boundary noise of that ``param``),
    ``"resampled"`` (:func:`resampled_noise`, σ = ``param``), ``"flips"``
    (:func:`boundary_flips`, probability ``param``), ``"rotate"`` (degrees) or
    ``"scale"`` (factor).
    """

    name: str
    kind: Literal["gaussian", "uniform", "resampled", "flips", "rotate", "scale"]
    param: float

    def apply(self, mask: np.ndarray, rng: np.random.Generator | int | None = None) -> np.ndarray:
        """Perturb ``mask`` (``rng`` seeds the noise; unused by rotation and scaling)."""
        return self.apply_mapped(mask, rng)[0]

    def apply_mapped(
        self, mask: np.ndarray, rng: np.random.Generator | int | None = None
    ) -> tuple[np.ndarray, Callable[[np.ndarray], np.ndarray]]:
        """The perturbed mask, and the map of its (row, col) points back to ``mask``'s frame.

        The map undoes the shift of the noise margin or crop and, for rotation and
        scaling, the transform itself, so that skeletons can be compared point by point.
        """
        if self.kind in ("gaussian", "uniform", "resampled", "flips"):
            if self.kind == "resampled":
                out = resampled_noise(mask, self.param, rng, margin=2)
            elif self.kind == "flips":
                out = boundary_flips(mask, self.param, rng, margin=2)
            else:
                out = boundary_noise(mask, self.kind, self.param, rng, margin=2)  # type: ignore[arg-type]
            return out, lambda q: np.asarray(q, np.float64) - 2.0
        if self.kind == "rotate":
            matrix, centre = _rotation(self.param), _rotation_centre(mask)
        else:
            matrix, centre = np.eye(2) * float(self.param), _scale_centre(mask)
        out, shift = _transform(mask, matrix, centre, 2)
        inverse = np.linalg.inv(matrix)
        return out, lambda q: (np.asarray(q, np.float64) + shift - centre) @ inverse.T + centre


#: The perturbations of the stability benchmarks, by name, in a fixed order.
PERTURBATIONS: dict[str, Perturbation] = {
    p.name: p
    for p in (
        Perturbation("gaussian-1", "gaussian", 1.0),
        Perturbation("gaussian-1.5", "gaussian", 1.5),
        Perturbation("uniform-1", "uniform", 1.0),
        Perturbation("uniform-1.2", "uniform", 1.2),
        Perturbation("uniform-1.5", "uniform", 1.5),
        Perturbation("resampled-1", "resampled", 1.0),
        Perturbation("flips-0.5", "flips", 0.5),
        Perturbation("rotate-15", "rotate", 15.0),
        Perturbation("rotate-30", "rotate", 30.0),
        Perturbation("rotate-45", "rotate", 45.0),
        Perturbation("scale-0.5", "scale", 0.5),
        Perturbation("scale-1.5", "scale", 1.5),
        Perturbation("scale-2", "scale", 2.0),
    )
}
