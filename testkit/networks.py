"""Generated line networks with a known truth: roads, vessel trees and crack maps.

A network is a graph drawn by hand in code: nodes (positions, which may lie outside the
image) and edges (a wavy centre line from node to node, a radius). The mask is every
pixel within the radius of its nearest centre line, with ragged edges (the radius
perturbed by a smooth random field of about ±1.5 px) and pinholes (a few background
pixels inside the widest parts, as a segmentation leaves them). Widths run from 6 to 20 px.

The truth a pruned skeleton is measured against:

- ``dead_ends``: nodes of degree 1 inside the image (at least a width from its border)
  whose edge is at least :data:`KEEP_LENGTH` long and four widths long, and whose end
  does not run into another road: a road a person would keep, ending there;
- ``border_roads``: where an edge's centre line crosses the image border (a road running
  off the image), one point per crossing;
- ``centre``: every centre line, as (row, col) points.

The mask is drawn in strips of rows, so an 8000 × 8000 network costs well under a gigabyte
to make.

>>> net = network("road", 1024, seed=1)
>>> net.mask.shape, bool(0.03 < net.mask.mean() < 0.12), len(net.dead_ends) > 0
((1024, 1024), True, True)
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage
from scipy.spatial import Voronoi

__all__ = ["KEEP_LENGTH", "KINDS", "Network", "network", "truth_counts"]

KINDS = ("road", "vessel", "crack")
#: The shortest dead-end road counted as one a person keeps (px).
KEEP_LENGTH = 60.0
#: Rows drawn at a time.
_STRIP = 1024


@dataclass
class Network:
    """A drawn network: its mask and its truth (docstring of the module)."""

    kind: str
    mask: np.ndarray
    centre: list[np.ndarray]
    radius: list[float]
    dead_ends: np.ndarray  # (k, 2) row, col
    dead_end_radius: np.ndarray  # (k,)
    border_roads: np.ndarray  # (k, 2) row, col on the border
    border_radius: np.ndarray  # (k,)
    pinholes: int = 0
    extra: dict[str, float] = field(default_factory=dict)

    @property
    def road_pixels(self) -> int:
        return int(np.count_nonzero(self.mask))


def _wavy(p: np.ndarray, q: np.ndarray, rng: np.random.Generator, amp: float) -> np.ndarray:
    """A centre line from ``p`` to ``q`` (row, col) bending gently sideways: points every
    pixel or so."""
    length = float(np.hypot(*(q - p)))
    n = max(int(length), 2)
    t = np.linspace(0.0, 1.0, n + 1)
    normal = np.array([-(q - p)[1], (q - p)[0]]) / max(length, 1e-9)
    bend = np.zeros_like(t)
    for k in (1, 2, 3):
        bend += rng.normal(0.0, amp / k) * np.sin(np.pi * k * t)
    return p[None, :] + t[:, None] * (q - p)[None, :] + bend[:, None] * normal[None, :]


def _road_graph(size: int, rng: np.random.Generator) -> tuple[np.ndarray, list, list]:
    """A jittered grid of streets reaching past the image, some removed, with dead-end
    spurs."""
    spacing = 420.0
    n = int(np.ceil(size / spacing)) + 3
    base = (np.arange(n) - 1) * spacing
    gy, gx = np.meshgrid(base, base, indexing="ij")
    pts = np.stack([gy.ravel(), gx.ravel()], 1) + rng.uniform(-110, 110, (n * n, 2))
    edges, radii = [], []

    def idx(i: int, j: int) -> int:
        return i * n + j

    for i in range(n):
        for j in range(n):
            for di, dj in ((0, 1), (1, 0)):
                if i + di < n and j + dj < n and rng.random() > 0.18:
                    edges.append((idx(i, j), idx(i + di, j + dj)))
                    radii.append(float(rng.uniform(3.0, 10.0)))
    nodes = [p for p in pts]
    # dead-end spurs from edge middles: cul-de-sacs 80-300 px long
    for e in list(range(len(edges))):
        if rng.random() < 0.35:
            a, b = edges[e]
            mid = (nodes[a] + nodes[b]) / 2
            d = nodes[b] - nodes[a]
            side = np.array([-d[1], d[0]]) / max(np.hypot(*d), 1e-9) * rng.choice([-1, 1])
            end = mid + side * rng.uniform(80, 300)
            nodes.append(mid)
            nodes.append(end)
            m, t = len(nodes) - 2, len(nodes) - 1
            # split the edge at its middle so the spur meets it at a node
            edges[e] = (a, m)
            edges.append((m, b))
            radii.append(radii[e])
            edges.append((m, t))
            radii.append(float(rng.uniform(3.0, 7.0)))
    return np.array(nodes), edges, radii


def _vessel_graph(size: int, rng: np.random.Generator) -> tuple[np.ndarray, list, list]:
    """Trees growing in from the image border, forking and thinning to 6 px."""
    nodes: list[np.ndarray] = []
    edges: list[tuple[int, int]] = []
    radii: list[float] = []
    n_roots = max(1, round(size / 1400))
    centre = np.array([size / 2, size / 2])
    for k in range(n_roots * 4):
        side = k % 4
        s = rng.uniform(0.1, 0.9) * size
        root = [
            np.array([-40.0, s]),
            np.array([size + 40.0, s]),
            np.array([s, -40.0]),
            np.array([s, size + 40.0]),
        ][side]
        heading = np.arctan2(*(centre - root)) + rng.uniform(-0.5, 0.5)
        nodes.append(root)
        stack = [(len(nodes) - 1, heading, 10.0, 0)]
        while stack:
            a, h, r, gen = stack.pop()
            seg = rng.uniform(160, 320) * (0.85**gen)
            seg = max(seg, 4 * 2 * r + 20)
            q = nodes[a] + seg * np.array([np.sin(h), np.cos(h)])
            nodes.append(q)
            b = len(nodes) - 1
            edges.append((a, b))
            radii.append(r)
            inside = -200 < q[0] < size + 200 and -200 < q[1] < size + 200
            if gen < 5 and r > 3.2 and inside:
                r2 = max(3.0, r * rng.uniform(0.72, 0.85))
                spread = rng.uniform(0.35, 0.7)
                stack.append((b, h - spread, r2, gen + 1))
                stack.append((b, h + spread, max(3.0, r2 * rng.uniform(0.8, 1.0)), gen + 1))
    return np.array(nodes), edges, radii


def _crack_graph(size: int, rng: np.random.Generator) -> tuple[np.ndarray, list, list]:
    """Voronoi cell walls (a crack map), a quarter of them missing, narrow."""
    spacing = 330.0
    k = int(((size + 2 * spacing) / spacing) ** 2)
    seeds = rng.uniform(-spacing, size + spacing, (k, 2))
    vor = Voronoi(seeds)
    verts = vor.vertices
    edges, radii = [], []
    for a, b in vor.ridge_vertices:
        if a < 0 or b < 0:
            continue
        pa, pb = verts[a], verts[b]
        if np.hypot(*(pa - pb)) < 25:
            continue
        far = -2 * spacing
        if min(pa.min(), pb.min()) < far or max(pa.max(), pb.max()) > size - far:
            continue
        if rng.random() < 0.25:
            continue
        edges.append((a, b))
        radii.append(float(rng.uniform(3.0, 6.0)))
    return verts, edges, radii


_GRAPHS = {"road": _road_graph, "vessel": _vessel_graph, "crack": _crack_graph}


def _border_crossings(line: np.ndarray, size: int) -> list[np.ndarray]:
    """Points where a centre line crosses the image border (inside to outside)."""
    inside = (line[:, 0] >= 0) & (line[:, 0] <= size - 1) & (line[:, 1] >= 0)
    inside &= line[:, 1] <= size - 1
    change = np.flatnonzero(inside[1:] != inside[:-1])
    out = []
    for c in change:
        p = line[c] if inside[c] else line[c + 1]
        out.append(np.clip(p, 0, size - 1))
    return out


def network(kind: str, size: int, seed: int = 0, pinholes: float = 1.0) -> Network:
    """A ``kind`` network (``road``, ``vessel`` or ``crack``) on a ``size`` × ``size`` mask.

    ``pinholes`` scales the number of pinholes (1.0: one per 3000 road pixels; 0: none).
    """
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}")
    rng = np.random.default_rng(seed)
    nodes, edges, radii = _GRAPHS[kind](size, rng)
    lines = [
        _wavy(nodes[a], nodes[b], rng, 0.06 * np.hypot(*(nodes[b] - nodes[a]))) for a, b in edges
    ]
    # the centre lines as a radius image (0: no line); the widest wins where they meet
    rad = np.zeros((size, size), np.float32)
    for line, r in zip(lines, radii, strict=True):
        p = np.round(line).astype(np.int64)
        ok = (p[:, 0] >= 0) & (p[:, 0] < size) & (p[:, 1] >= 0) & (p[:, 1] < size)
        p = p[ok]
        np.maximum.at(rad, (p[:, 0], p[:, 1]), np.float32(r))
    # lines just outside still draw their edge inside: a ring of 12 px outside the image
    pad = 12
    ring = np.zeros((size + 2 * pad, size + 2 * pad), np.float32)
    for line, r in zip(lines, radii, strict=True):
        p = np.round(line).astype(np.int64) + pad
        ok = (p[:, 0] >= 0) & (p[:, 0] < size + 2 * pad) & (p[:, 1] >= 0)
        ok &= p[:, 1] < size + 2 * pad
        p = p[ok]
        outside = (p[:, 0] < pad) | (p[:, 0] >= size + pad) | (p[:, 1] < pad)
        outside |= p[:, 1] >= size + pad
        p = p[outside]
        np.maximum.at(ring, (p[:, 0], p[:, 1]), np.float32(r))
    ring[pad:-pad, pad:-pad] = rad
    del rad
    mask = np.zeros((size, size), bool)
    halo = pad + 2
    n_holes = 0
    for top in range(0, size, _STRIP):
        bot = min(size, top + _STRIP)
        lo, hi = top + pad - halo, bot + pad + halo
        lo_c, hi_c = max(lo, 0), min(hi, size + 2 * pad)
        sub = ring[lo_c:hi_c]
        dist, (ii, jj) = ndimage.distance_transform_edt(sub == 0, return_indices=True)
        r = sub[ii, jj]
        srng = np.random.default_rng([seed, top])
        noise = ndimage.gaussian_filter(srng.normal(0, 1, sub.shape).astype(np.float32), 2.0)
        noise *= 1.5 / max(float(noise.std()), 1e-6)
        fg = (r > 0) & (dist <= r + noise)
        core = fg[top + pad - lo_c : bot + pad - lo_c, pad : pad + size]
        # pinholes: 1-3 px of background well inside the wider roads
        deep = np.flatnonzero(
            (
                dist[top + pad - lo_c : bot + pad - lo_c, pad : pad + size]
                < r[top + pad - lo_c : bot + pad - lo_c, pad : pad + size] - 4
            )
            & core
        )
        k = int(deep.size / 3000 * pinholes)
        if k:
            hole = srng.choice(deep, k, replace=False)
            hr, hc = np.divmod(hole, size)
            core[hr, hc] = False
            grow = srng.random(k) < 0.5
            core[hr[grow], np.minimum(hc[grow] + 1, size - 1)] = False
            n_holes += k
        mask[top:bot] = core
        del dist, ii, jj, r, noise, fg
    del ring
    degree = np.zeros(len(nodes), np.int64)
    for a, b in edges:
        degree[a] += 1
        degree[b] += 1
    # a dead end drawn onto another road is no dead end in the mask: the truth leaves it out
    from scipy.spatial import cKDTree

    owner = np.concatenate([np.full(len(line), k) for k, line in enumerate(lines)])
    tree = cKDTree(np.concatenate(lines))
    widest = max(radii) if radii else 0.0
    dead, dead_r = [], []
    for k, ((a, b), line, r) in enumerate(zip(edges, lines, radii, strict=True)):
        length = float(np.sum(np.hypot(*np.diff(line, axis=0).T)))
        for node, end in ((a, line[0]), (b, line[-1])):
            w = 2 * r
            if degree[node] != 1 or length < max(KEEP_LENGTH, 4 * w):
                continue
            near = tree.query_ball_point(end, r + widest + 6)
            if any(owner[q] != k for q in near):
                continue
            if w <= end[0] <= size - 1 - w and w <= end[1] <= size - 1 - w:
                dead.append(end)
                dead_r.append(r)
    border, border_r = [], []
    for line, r in zip(lines, radii, strict=True):
        for p in _border_crossings(line, size):
            border.append(p)
            border_r.append(r)
    return Network(
        kind=kind,
        mask=mask,
        centre=lines,
        radius=list(radii),
        dead_ends=np.array(dead, float).reshape(-1, 2),
        dead_end_radius=np.array(dead_r, float),
        border_roads=np.array(border, float).reshape(-1, 2),
        border_radius=np.array(border_r, float),
        pinholes=n_holes,
    )


def truth_counts(
    net: Network, rows: np.ndarray, cols: np.ndarray, end_rows: np.ndarray, end_cols: np.ndarray
) -> dict[str, int]:
    """How much of the truth a skeleton keeps.

    ``rows``, ``cols``: every skeleton pixel; ``end_rows``, ``end_cols``: its endpoints.
    A dead end is found when an endpoint lies within its road's width plus 6 px of it
    (the tip is cut back by about a radius); a border road is kept when a skeleton pixel
    lies within its width plus 6 px of where its centre line crosses the border.
    """
    from scipy.spatial import cKDTree

    found = kept = 0
    if end_rows.size and len(net.dead_ends):
        tree = cKDTree(np.stack([end_rows, end_cols], 1))
        d, _ = tree.query(net.dead_ends)
        found = int(np.sum(d <= 2 * net.dead_end_radius + 6))
    if rows.size and len(net.border_roads):
        tree = cKDTree(np.stack([rows, cols], 1))
        d, _ = tree.query(net.border_roads)
        kept = int(np.sum(d <= 2 * net.border_radius + 6))
    return {
        "dead_ends": len(net.dead_ends),
        "dead_ends_found": found,
        "border_roads": len(net.border_roads),
        "border_roads_kept": kept,
    }
