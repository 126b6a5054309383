"""Lines a cartographer draws, from a pruned skeleton's GeoJSON in metres.

The pruning's answer keeps every branch that reconstructs enough of the shape; on a
ragged or staircase outline (a polygon traced from raster pixels) that is a short branch
to many corners, which a map does not want. From the skeleton's branches (in a planar
CRS, lengths and radii in its units):

1. **Chains become lines.** Branches meeting at a node of degree two are joined: one line
   from junction (or end) to junction (or end).
2. **Short ends go.** An end line (one end free, the other at a junction) shorter than
   :data:`END_FACTOR` times the junction's radius runs into a corner or a bump of the
   outline, not into a part of the shape: it is dropped, the lines joined again, and
   again, until none is.
3. **Ends run straight to the boundary.** A free end's last stretch, as far as the tip
   lies within √2 radii of a vertex before it (a right angle's corner), bends into a
   corner: it is cut, and the line runs on in its own direction to the boundary.
4. **Simplified by the local width.** Douglas–Peucker where each vertex may move by
   ``share`` of its own half-width (the skeleton's radius there): a wide lake's line
   keeps few vertices, a narrow inlet's its detail. A line that leaves the polygon is
   simplified again at half the share (three times at most, then kept).
5. ``main_path``: one line per connected network, its longest path (for labels).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import shapely
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra
from shapely.geometry import LineString

from ..output.lines import douglas_peucker

__all__ = ["END_FACTOR", "SHARE", "CartoLine", "cartographic_lines"]

#: An end branch shorter than this many junction radii is a corner's, not a part's.
END_FACTOR = 2.0
#: How far (in radii of a vertex's inscribed disk) a free end may run on into a corner
#: and still be cut: a right angle's corner lies √2 radii from the disk's centre.
CORNER_REACH = float(np.sqrt(2.0))
#: Share of the local half-width a simplified line may move by.
SHARE = 0.25
#: Halvings of the share tried for a line that leaves the polygon.
RETRIES = 3


@dataclass
class CartoLine:
    """One map line: its coordinates, its skeleton radii, and its network."""

    xy: np.ndarray  # (n, 2)
    radii: np.ndarray  # (n,)
    network: tuple[int, int]  # (component, smallest node id): lines of one network share it

    @property
    def length(self) -> float:
        return float(np.hypot(*np.diff(self.xy, axis=0).T).sum())

    @property
    def width(self) -> float:
        """Mean width along the line, weighted by length (twice the radius)."""
        if len(self.xy) < 2:
            return float(2 * self.radii.mean()) if len(self.radii) else 0.0
        seg = np.hypot(*np.diff(self.xy, axis=0).T)
        mid = (self.radii[1:] + self.radii[:-1]) / 2
        return float(2 * (seg * mid).sum() / max(seg.sum(), 1e-300))


def _branches(geo: dict[str, Any]) -> tuple[list[dict[str, Any]], dict[tuple[int, int], float]]:
    branches, radius = [], {}
    for f in geo["features"]:
        p = f["properties"]
        if p["kind"] == "branch":
            xy = np.asarray(f["geometry"]["coordinates"], float)
            branches.append(
                {
                    "xy": xy,
                    "radii": np.asarray(p["radii"], float),
                    "ends": ((p["component"], p["source"]), (p["component"], p["target"])),
                    "length": float(p["length"]),
                }
            )
        else:
            radius[(p["component"], p["id"])] = float(p["radius"])
    return branches, radius


def _degrees(branches: list[dict[str, Any]]) -> dict[tuple[int, int], int]:
    degree: dict[tuple[int, int], int] = {}
    for b in branches:
        a, c = b["ends"]
        degree[a] = degree.get(a, 0) + 1
        degree[c] = degree.get(c, 0) + 1
    return degree


def _length(xy: np.ndarray) -> float:
    return float(np.hypot(*np.diff(xy, axis=0).T).sum()) if len(xy) > 1 else 0.0


def _drop_short_ends(
    lines: list[dict[str, Any]], radius: dict[tuple[int, int], float], factor: float
) -> list[dict[str, Any]]:
    """Lines (chains) without the short ends, joined again after each round, so that a
    tree of small branches into a bump goes branch by branch."""
    while True:
        degree = _degrees(lines)
        short: dict[tuple[int, int], list[int]] = {}
        for i, ln in enumerate(lines):
            a, c = ln["ends"]
            if a == c:
                continue
            free = [n for n in (a, c) if degree[n] == 1]
            joint = [n for n in (a, c) if degree[n] >= 3]
            if len(free) == 1 and len(joint) == 1 and _length(ln["xy"]) < factor * radius[joint[0]]:
                short.setdefault(joint[0], []).append(i)
        drop: set[int] = set()
        for node, ids in short.items():
            if len(ids) >= degree[node]:  # a star of short ends: its two longest stay
                ids = sorted(ids, key=lambda i: _length(lines[i]["xy"]))[:-2]
            drop.update(ids)
        if not drop:
            return lines
        lines = _chains([ln for i, ln in enumerate(lines) if i not in drop])


def _trim_tip(xy: np.ndarray, radii: np.ndarray) -> int:
    """How many vertices of a free end (at ``xy[0]``) run into a corner: those up to the
    innermost vertex whose inscribed disk, grown by √2, still holds the tip (along the
    line). A right angle's bisector runs √2 radii from the disk's centre to the corner,
    so the stretch into a rectangle's corner is cut as a round end's hook is."""
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
    inside = np.flatnonzero(arc <= CORNER_REACH * radii)
    if len(inside) == 0 or inside[-1] == 0 or inside[-1] >= len(xy) - 1:
        return 0
    return int(inside[-1])


def _extend(xy: np.ndarray, radius: float, polygon: Any, at_start: bool) -> np.ndarray:
    """A line running on straight, from an end cut short, to the polygon's boundary."""
    if len(xy) < 2 or radius <= 0:
        return xy
    line = xy if at_start else xy[::-1]
    end = line[0]
    # the direction over about a radius of the line (not its last, noisiest, step)
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(line, axis=0).T))])
    back = line[min(int(np.searchsorted(arc, radius)), len(line) - 1)]
    d = end - back
    norm = float(np.hypot(*d))
    if norm == 0:
        return xy
    ray = LineString([end, end + d / norm * 3 * radius])
    hit = shapely.intersection(ray, polygon.boundary)
    pts = shapely.get_coordinates(hit)
    if len(pts) == 0:
        return xy
    tip = pts[np.argmin(np.hypot(*(pts - end).T))]
    if not polygon.covers(LineString([end, tip])):
        return xy
    return np.vstack([tip, xy]) if at_start else np.vstack([xy, tip])


def _chains(branches: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Branches joined through nodes of degree two."""
    degree = _degrees(branches)
    at: dict[tuple[int, int], list[int]] = {}
    for i, b in enumerate(branches):
        for n in b["ends"]:
            at.setdefault(n, []).append(i)
    used = [False] * len(branches)
    out = []

    def oriented(i: int, start: tuple[int, int]) -> tuple[np.ndarray, np.ndarray, Any]:
        b = branches[i]
        if b["ends"][0] == start:
            return b["xy"], b["radii"], b["ends"][1]
        return b["xy"][::-1], b["radii"][::-1], b["ends"][0]

    starts = [n for n, d in degree.items() if d != 2] + [n for n, d in degree.items() if d == 2]
    for start in starts:
        for i in at.get(start, []):
            if used[i]:
                continue
            used[i] = True
            xy, radii, node = oriented(i, start)
            parts_xy, parts_r = [xy], [radii]
            while degree.get(node) == 2 and node != start:
                nxt = [j for j in at[node] if not used[j]]
                if not nxt:
                    break
                used[nxt[0]] = True
                xy, radii, node = oriented(nxt[0], node)
                parts_xy.append(xy[1:])
                parts_r.append(radii[1:])
            out.append(
                {
                    "xy": np.concatenate(parts_xy),
                    "radii": np.concatenate(parts_r),
                    "ends": (start, node),
                }
            )
    return out


def _simplify(xy: np.ndarray, radii: np.ndarray, share: float, polygon: Any) -> np.ndarray:
    """Rows kept by Douglas–Peucker within ``share`` of each vertex's half-width, inside
    ``polygon``."""
    if len(xy) <= 2:
        return np.arange(len(xy))
    for _ in range(RETRIES):
        keep = douglas_peucker(xy, share * np.maximum(radii, 0.0))
        if len(keep) == len(xy) or polygon.covers(LineString(xy[keep])):
            return keep
        share /= 2
    return np.arange(len(xy))


def _networks(lines: list[dict[str, Any]]) -> list[int]:
    """A network number for each line (lines sharing a node, transitively)."""
    parent: dict[Any, Any] = {}

    def find(n: Any) -> Any:
        while parent.setdefault(n, n) != n:
            parent[n] = parent[parent[n]]
            n = parent[n]
        return n

    for ln in lines:
        a, c = ln["ends"]
        parent[find(a)] = find(c)
    return [hash(find(ln["ends"][0])) for ln in lines]


def _longest_path(lines: list[dict[str, Any]]) -> dict[str, Any]:
    """The longest path through one network (double sweep: exact on a tree)."""
    nodes = sorted({n for ln in lines for n in ln["ends"]})
    index = {n: i for i, n in enumerate(nodes)}
    length = [float(np.hypot(*np.diff(ln["xy"], axis=0).T).sum()) for ln in lines]
    rows = [index[ln["ends"][0]] for ln in lines]
    cols = [index[ln["ends"][1]] for ln in lines]
    graph = coo_matrix((np.maximum(length, 1e-12), (rows, cols)), shape=(len(nodes),) * 2)
    d0 = dijkstra(graph.tocsr(), directed=False, indices=0)
    a = int(np.argmax(np.where(np.isfinite(d0), d0, -1)))
    d, pred = dijkstra(graph.tocsr(), directed=False, indices=a, return_predecessors=True)
    b = int(np.argmax(np.where(np.isfinite(d), d, -1)))
    by_pair = {}
    for ln, r, c in zip(lines, rows, cols, strict=True):
        by_pair.setdefault((r, c), ln)
        by_pair.setdefault((c, r), {**ln, "xy": ln["xy"][::-1], "radii": ln["radii"][::-1]})
    xy, radii = [], []
    node = b
    while node != a and pred[node] >= 0:
        prev = int(pred[node])
        ln = by_pair[(prev, node)]
        xy.append(ln["xy"])
        radii.append(ln["radii"])
        node = prev
    if not xy:  # one node: the network's single loop or point
        return max(lines, key=lambda ln: len(ln["xy"]))
    xy.reverse()
    radii.reverse()
    return {
        "xy": np.concatenate([xy[0]] + [s[1:] for s in xy[1:]]),
        "radii": np.concatenate([radii[0]] + [s[1:] for s in radii[1:]]),
        "ends": (nodes[a], nodes[b]),
    }


def cartographic_lines(
    geo: dict[str, Any],
    polygon: Any,
    *,
    share: float = SHARE,
    end_factor: float = END_FACTOR,
    main_path: bool = False,
) -> list[CartoLine]:
    """Map lines from a skeleton's GeoJSON (``to_geojson(simplify=0)`` or any simplify,
    in a planar CRS) and the polygon it came from (the same CRS).

    Examples
    --------
    >>> import skelprune
    >>> from shapely.geometry import box
    >>> reach = box(0, 0, 3000, 800)
    >>> lines = cartographic_lines(skelprune.prune(reach).to_geojson(), reach)
    >>> len(lines), [len(ln.xy) for ln in lines]  # the end forks were a corner's: one line
    (1, [2])
    """
    branches, radius = _branches(geo)
    shapely.prepare(polygon)
    boundary = polygon.boundary
    for b in branches:  # exact radii: the distance to the polygon's boundary
        b["radii"] = shapely.distance(boundary, shapely.points(b["xy"]))
    lines = _drop_short_ends(_chains(branches), radius, end_factor)
    degree = _degrees(lines)
    for ln in lines:
        for k, node in enumerate(ln["ends"]):
            if degree.get(node) != 1 or ln["ends"][0] == ln["ends"][1]:
                continue
            xy, radii = (ln["xy"], ln["radii"]) if k == 0 else (ln["xy"][::-1], ln["radii"][::-1])
            cut = _trim_tip(xy, radii)
            xy, radii = xy[cut:], radii[cut:]
            longer = _extend(xy, float(radii[0]), polygon, at_start=True)
            if len(longer) > len(xy):
                xy, radii = longer, np.concatenate([radii[:1], radii])
            ln["xy"], ln["radii"] = (xy, radii) if k == 0 else (xy[::-1], radii[::-1])
    if main_path and lines:
        nets = _networks(lines)
        lines = [
            _longest_path([ln for ln, n in zip(lines, nets, strict=True) if n == net])
            for net in dict.fromkeys(nets)
        ]
    out = []
    nets = _networks(lines)
    for ln, net in zip(lines, nets, strict=True):
        keep = _simplify(ln["xy"], ln["radii"], share, polygon)
        out.append(CartoLine(ln["xy"][keep], ln["radii"][keep], (net, 0)))
    return out
