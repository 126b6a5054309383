"""Lines for maps: a skeleton's branches simplified, still meeting, still inside.

The document lists every pixel of a branch; a map wants a few vertices per width. Each
branch's line (from its source node to its target node, :meth:`BranchTable.lines`) is
simplified by Douglas–Peucker within ``tolerance`` pixels, keeping its two ends (a loop
keeps three points round it), so that lines still meet exactly at their nodes and the
network keeps its connections and its rings. A simplified line that leaves the shape,
crosses itself, or crosses another line anywhere but at a shared node, is simplified
again at half the tolerance (three times at most, then the exact path is kept).

``cut_ends``: a reach cut straight across (a river clipped at a map's edge) ends in a
fork, two short branches running to the cut's two corners. Where a junction has two end
branches whose tips lie on one straight stretch of the boundary about the junction's
diameter apart (the chord between them near the boundary all along), the two are replaced
by one line from the junction to the middle of that stretch, and the junction's
remaining branch runs on into it.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import cv2
import numpy as np
import shapely
from scipy.spatial import cKDTree
from shapely.geometry import LineString

from .table import BranchTable

__all__ = [
    "boundary_index",
    "cut_end_forks",
    "douglas_peucker",
    "map_lines",
    "mask_distance",
    "recentre",
]

#: Halvings of the tolerance tried for a line that leaves the shape or crosses another.
RETRIES = 3


def douglas_peucker(xy: np.ndarray, tolerance: float | np.ndarray) -> np.ndarray:
    """Indices of the points kept by Douglas–Peucker (first and last always kept).

    ``tolerance`` may be one per point (how far the line may move at that point: a
    point is kept where its distance most exceeds its own tolerance).

    >>> xy = np.array([[0, 0], [1, 0.1], [2, 0], [3, 2]], float)
    >>> douglas_peucker(xy, 0.5).tolist()
    [0, 2, 3]
    >>> ring = np.array([[0, 0], [1, 0], [2, 0], [2, 1], [1, 1], [0, 1], [0, 0]], float)
    >>> len(douglas_peucker(ring, 5.0))  # a loop keeps three corners and its closing point
    4
    """
    n = len(xy)
    per_point = np.ndim(tolerance) > 0
    if n <= 2 or (not per_point and tolerance <= 0):
        return np.arange(n)
    if per_point:
        tol = np.maximum(np.asarray(tolerance, float), 1e-12)
    keep = np.zeros(n, bool)
    keep[0] = keep[-1] = True
    stack = [(0, n - 1)]
    if n >= 4 and np.array_equal(xy[0], xy[-1]):
        # a closed loop stays a ring: a third and two thirds round are kept too
        keep[n // 3] = keep[2 * n // 3] = True
        stack = [(0, n // 3), (n // 3, 2 * n // 3), (2 * n // 3, n - 1)]
    while stack:
        a, b = stack.pop()
        if b - a < 2:
            continue
        p, q = xy[a], xy[b]
        seg = q - p
        pts = xy[a + 1 : b] - p
        norm = float(np.hypot(*seg))
        if norm == 0:  # a closed line: distance to the point
            d = np.hypot(pts[:, 0], pts[:, 1])
        else:
            d = np.abs(seg[0] * pts[:, 1] - seg[1] * pts[:, 0]) / norm
        if per_point:
            excess = d / tol[a + 1 : b]
            i = int(np.argmax(excess))
            far = bool(excess[i] > 1)
        else:
            i = int(np.argmax(d))
            far = bool(d[i] > tolerance)
        if far:
            m = a + 1 + i
            keep[m] = True
            stack += [(a, m), (m, b)]
    return np.flatnonzero(keep)


#: Spacing of the boundary samples :func:`recentre` measures distances to, in pixels:
#: the nearest sample is then within (spacing/2)²/2 px of the true distance.
BOUNDARY_STEP = 0.25


def boundary_index(polygon: Any) -> tuple[cKDTree, np.ndarray, np.ndarray]:
    """The polygon's boundary, sampled every :data:`BOUNDARY_STEP` pixels, with each
    sample's inward normal, for :func:`recentre` (built once)."""
    oriented = shapely.orient_polygons(polygon)  # exterior counter-clockwise: inside left
    pts, normals = [], []
    for part in shapely.get_parts(oriented):
        for ring in (part.exterior, *part.interiors):
            c = shapely.get_coordinates(shapely.segmentize(ring, BOUNDARY_STEP))
            d = np.diff(c, axis=0)
            length = np.hypot(d[:, 0], d[:, 1])
            keep = length > 0
            d, start = d[keep] / length[keep, None], c[:-1][keep]
            pts.append(start)
            normals.append(np.stack([-d[:, 1], d[:, 0]], 1))  # left of the direction
    # (orientation is a property of the coordinates, whichever way the y axis is drawn)
    return cKDTree(np.concatenate(pts)), np.concatenate(pts), np.concatenate(normals)


def recentre(lines: list[np.ndarray], index: Any) -> list[np.ndarray]:
    """Move each line's inner vertices to the polygon's medial point across the line.

    A skeleton pixel lies up to about half a pixel off the true medial axis. Across the
    line (along its normal ``n``) the distance to the boundary is a tent,
    ``min(L + t, R - t)``; sampled at ``t = ±h`` on both slopes it gives the medial point
    ``t* = (d(+h) - d(-h)) / 2`` between the two boundary points the disk touches, and
    its radius (distances are signed, negative outside, so a sample beyond a bank still
    counts). Ends (the nodes) stay, so that lines still meet there.
    """
    tree, bpts, bnormals = index
    out = []
    for ln in lines:
        if len(ln) < 3:
            out.append(ln)
            continue
        xy = ln[:, :2]
        tangent = xy[2:] - xy[:-2]
        norm = np.hypot(tangent[:, 0], tangent[:, 1])
        ok = norm > 0
        n = np.zeros_like(tangent)
        n[ok] = np.stack([-tangent[ok, 1], tangent[ok, 0]], 1) / norm[ok, None]
        h = np.clip(0.8 * ln[1:-1, 2], 0.25, 1.5)[:, None]
        mid = xy[1:-1]
        samples = np.concatenate([mid - n * h, mid + n * h])
        dist, near = tree.query(samples)
        inward = np.einsum("ij,ij->i", samples - bpts[near], bnormals[near]) >= 0
        dist = np.where(inward, dist, -dist)  # signed: the tent goes on below zero
        d_lo, d_hi = dist[: len(mid)], dist[len(mid) :]
        t = np.clip((d_hi - d_lo) / 2, -h[:, 0], h[:, 0])
        new = ln.copy()
        new[1:-1][ok, :2] = mid[ok] + n[ok] * t[ok, None]
        # the medial point's radius: the tent's top
        new[1:-1][ok, 2] = (d_lo[ok] + d_hi[ok]) / 2 + h[ok, 0]
        out.append(new)
    return out


def mask_distance(mask: np.ndarray) -> Callable[[], np.ndarray]:
    """The mask's Euclidean distance transform, computed on the first call only."""
    cache: list[np.ndarray] = []

    def get() -> np.ndarray:
        if not cache:
            padded = np.pad(mask, 1).astype(np.uint8)
            cache.append(
                cv2.distanceTransform(padded, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)[1:-1, 1:-1]
            )
        return cache[0]

    return get


def _inside_mask(mask: np.ndarray) -> Callable[[np.ndarray], bool]:
    """A test that a pixel-coordinate polyline ``(x, y)`` stays on the mask's pixels
    (sampled every quarter pixel; a pixel's square counts as the shape)."""
    h, w = mask.shape

    def inside(xy: np.ndarray) -> bool:
        if len(xy) < 2:
            return True
        seg = np.diff(xy, axis=0)
        steps = np.maximum(np.ceil(np.hypot(seg[:, 0], seg[:, 1]) * 4), 1).astype(int)
        t = np.concatenate([np.arange(k) / k for k in steps])
        start = np.repeat(xy[:-1], steps, axis=0)
        pts = start + np.repeat(seg, steps, axis=0) * t[:, None]
        cols = np.clip(np.rint(pts[:, 0]).astype(int), 0, w - 1)
        rows = np.clip(np.rint(pts[:, 1]).astype(int), 0, h - 1)
        return bool(mask[rows, cols].all())

    return inside


def _inside_geometry(geom: Any) -> Callable[[np.ndarray], bool]:
    shapely.prepare(geom)

    def inside(xy: np.ndarray) -> bool:
        return len(xy) < 2 or bool(geom.covers(LineString(xy)))

    return inside


def map_lines(
    lines: list[np.ndarray],
    tolerance: float,
    mask: np.ndarray,
    polygon: Any = None,
    exact: list[np.ndarray] | None = None,
) -> list[np.ndarray]:
    """Simplify pixel-coordinate lines ``(x, y, radius)`` within ``tolerance`` pixels.

    ``polygon`` (in pixel coordinates), if given, is the shape the lines must stay in;
    else the ``mask``'s pixels. ``exact``: the skeleton's own pixel paths, which never
    cross, kept for a line that no tolerance keeps inside and uncrossed (default:
    ``lines`` themselves). Returns the kept rows of each line.
    """
    exact = lines if exact is None else exact
    if tolerance <= 0:
        return exact
    inside = _inside_mask(mask) if polygon is None else _inside_geometry(polygon)
    tol = [float(tolerance)] * len(lines)
    out = list(lines)
    todo = list(range(len(lines)))
    for attempt in range(RETRIES + 1):
        again: set[int] = set()
        for i in todo:
            ln = lines[i]
            out[i] = ln
            if attempt == RETRIES:  # the last round keeps the exact path
                out[i] = exact[i]
                continue
            if len(ln) <= 2:
                continue
            cand = ln[douglas_peucker(ln[:, :2], tol[i])]
            if len(cand) < len(ln) and (
                not LineString(cand[:, :2]).is_simple
                or (not inside(cand[:, :2]) and inside(ln[:, :2]))
            ):
                again.add(i)  # it folded onto itself, or left the shape
                continue
            out[i] = cand
        again |= _crossing(out, exact)
        for i in again:
            tol[i] /= 2
        todo = sorted(again)
        if not todo:
            break
    return out


def _crossing(out: list[np.ndarray], exact: list[np.ndarray]) -> set[int]:
    """Lines that meet another anywhere but at an end they share (the exact pixel paths
    never cross: a pair of them is not tested)."""
    geoms = [LineString(o[:, :2]) if len(o) >= 2 else None for o in out]
    valid = [i for i, g in enumerate(geoms) if g is not None]
    if len(valid) < 2:
        return set()
    tree = shapely.STRtree([geoms[i] for i in valid])
    a, b = tree.query([geoms[i] for i in valid], predicate="intersects")
    bad: set[int] = set()
    for ia, ib in zip(a.tolist(), b.tolist(), strict=True):
        if ia >= ib:
            continue
        i, j = valid[ia], valid[ib]
        if out[i] is exact[i] and out[j] is exact[j]:
            continue
        ends = {tuple(out[i][0, :2]), tuple(out[i][-1, :2])} & {
            tuple(out[j][0, :2]),
            tuple(out[j][-1, :2]),
        }
        meet = shapely.intersection(geoms[i], geoms[j])
        pts = shapely.get_coordinates(meet)
        if meet.geom_type not in ("Point", "MultiPoint") or any(
            tuple(p) not in ends for p in pts.tolist()
        ):
            bad.update(k for k in (i, j) if out[k] is not exact[k])
    return bad


def cut_end_forks(
    table: BranchTable,
    lines: list[np.ndarray],
    mask: np.ndarray,
    distance: Callable[[], np.ndarray] | None = None,
) -> tuple[list[np.ndarray | None], dict[tuple[int, str], int], dict[int, tuple[float, float]]]:
    """End forks at straight cut ends, in pixel coordinates.

    Returns the lines (a fork's two end branches None, the remaining branch extended to
    the cut's middle), the ends of branches that now end at another node
    (``(branch, "source" | "target") -> node``), and the moved endpoints by node id (the
    first tip's id, moved to the middle of the cut; the junction and the other tip are
    gone). ``distance()`` gives the mask's distance transform (computed once, on the
    first fork that needs it, when shared by the caller).
    """
    distance = distance or mask_distance(mask)
    h, w = mask.shape
    kinds = table.kinds()
    node_x = table.x[table.node_point].tolist()
    node_y = table.y[table.node_point].tolist()
    node_r = table.radius[table.node_point].tolist()
    source, target = table.source.tolist(), table.target.tolist()
    length = table.length.tolist()
    degree: dict[int, list[int]] = {}
    for b, ends in enumerate(zip(source, target, strict=True)):
        for end in ends:
            degree.setdefault(end, []).append(b)
    out: list[np.ndarray | None] = list(lines)
    moved: dict[int, tuple[float, float]] = {}
    ends_at: dict[tuple[int, str], int] = {}
    for nid, kind in enumerate(kinds):
        if kind != "junction" or len(degree.get(nid, [])) != 3:
            continue
        tips = []
        for b in degree[nid]:
            other = target[b] if source[b] == nid else source[b]
            if kinds[other] == "endpoint" and len(degree.get(other, [])) == 1:
                tips.append((b, other))
        if len(tips) == 3:  # a lone junction: the fork is its two short branches
            tips.sort(key=lambda bt: length[bt[0]])
            if length[tips[2][0]] < 3 * length[tips[1][0]]:
                continue
            tips = tips[:2]
        if len(tips) != 2:
            continue
        (b1, t1), (b2, t2) = tips
        a = np.array([node_x[t1], node_y[t1]], float)
        c = np.array([node_x[t2], node_y[t2]], float)
        j = np.array([node_x[nid], node_y[nid]], float)
        r = float(node_r[nid])
        span = float(np.hypot(*(c - a)))
        mid = (a + c) / 2
        if r < 2 or not 1.0 * r <= span <= 2.8 * r:
            continue
        if not 0.5 * r <= float(np.hypot(*(mid - j))) <= 1.4 * r:
            continue
        # the tips' chord runs along the boundary (the tips themselves are cut back from
        # the corners by a few pixels): every point of it near the background
        t = np.linspace(0, 1, max(int(span) * 2, 2))
        pts = a[None] + (c - a)[None] * t[:, None]
        cols = np.clip(np.rint(pts[:, 0]).astype(int), 0, w - 1)
        rows = np.clip(np.rint(pts[:, 1]).astype(int), 0, h - 1)
        # (at most half the junction's radius inside: a chord across the interior runs a
        # radius deep; and mostly on the shape: a notched end's chord runs outside it)
        if float(distance()[rows, cols].max()) > 1.5 + 0.5 * r or mask[rows, cols].mean() < 0.8:
            continue
        (rest,) = [b for b in degree[nid] if b not in (b1, b2)]
        if out[rest] is None or source[rest] == target[rest]:
            continue
        ln = out[rest]
        assert ln is not None
        at_source = source[rest] == nid
        # The line ends on the cut itself, straight on from the remaining branch's
        # direction into the junction: the tips' chord would tilt it, since the two
        # tips are cut back from their corners by different amounts.
        toward = ln[:, :2] if at_source else ln[::-1, :2]
        back = toward[min(len(toward) - 1, max(2, round(4 * r)))]
        ahead = (j - back) / max(float(np.hypot(*(j - back))), 1e-9)
        mid = j.copy()
        for _ in range(int(12 * r)):
            col, row = round(mid[0] + ahead[0] / 4), round(mid[1] + ahead[1] / 4)
            if not (0 <= col < w and 0 <= row < h and mask[row, col]):
                break
            mid = mid + ahead / 4
        end_pt = np.array([[mid[0], mid[1], 0.0]])
        out[rest] = np.concatenate([end_pt, ln]) if at_source else np.concatenate([ln, end_pt])
        out[b1] = out[b2] = None
        ends_at[(rest, "source" if at_source else "target")] = t1
        moved[t1] = (float(mid[0]), float(mid[1]))
    return out, ends_at, moved
