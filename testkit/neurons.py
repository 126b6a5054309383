"""Neuron morphologies (SWC trees) drawn as volumes with known centre lines and tips.

A tree of nodes (id, parent, position, radius) becomes a :class:`testkit.volumes.SweptShape`:
every edge a capsule swept from node to parent with the radius going linearly between
theirs, on a grid whose voxel side keeps the longest side within ``side`` voxels. Radii
under ``min_radius`` voxels are raised to it (thinner tubes fall apart on the grid), and
twigs that would hardly leave their parent's tube (an end path shorter than the parent's
radius plus :data:`TWIG_MARGIN` voxels) are dropped first, so that the centre lines and
tips are those a skeleton of the drawn volume can have: the tips are the remaining leaves.

:func:`example_neurons` draws navis's example neurons this way.

>>> ids = np.array([1, 2, 3, 4]); parents = np.array([-1, 1, 2, 2])
>>> xyz = np.array([[0, 0, 0], [40, 0, 0], [70, 20, 0], [70, -20, 0]], float)
>>> shape = swc_shape(ids, parents, xyz, np.full(4, 3.0), side=64)
>>> len(shape.tips), max(shape.shape) <= 64
(3, True)
"""

from __future__ import annotations

import itertools

import numpy as np

from .volumes import SweptShape, _segment

__all__ = ["TWIG_MARGIN", "example_neurons", "swc_shape"]

#: How far (voxels) beyond its parent's radius an end path must reach to be a tip.
TWIG_MARGIN = 3.0


def _paths(parent: dict[int, int], order: list[int]) -> list[list[int]]:
    """Unbranched paths of a tree: from each leaf or branch node up to (and including)
    the next branch node or the root, node ids child first."""
    children: dict[int, int] = {}
    for n in order:
        p = parent[n]
        if p in parent:
            children[p] = children.get(p, 0) + 1
    out = []
    for n in order:
        if children.get(n, 0) == 1 or parent[n] not in parent:
            continue  # inside a path, or the root
        path = [n]
        while parent[path[-1]] in parent:
            path.append(parent[path[-1]])
            if children.get(path[-1], 0) != 1:
                break
        out.append(path)
    return out


def _prune_twigs(
    parent: dict[int, int], xyz: dict[int, np.ndarray], radius: dict[int, float]
) -> dict[int, int]:
    """``parent`` without the end paths too short to leave their parent's tube."""
    parent = dict(parent)
    for _ in range(10):
        order = list(parent)
        has_child = {parent[n] for n in order}
        drop: set[int] = set()
        for path in _paths(parent, order):
            if path[0] in has_child or len(path) < 2:
                continue  # not an end path
            length = sum(
                float(np.linalg.norm(xyz[a] - xyz[b])) for a, b in itertools.pairwise(path)
            )
            if length < radius[path[-1]] + TWIG_MARGIN:
                drop.update(path[:-1])
        if not drop:
            break
        parent = {n: p for n, p in parent.items() if n not in drop}
    return parent


def swc_shape(
    ids: np.ndarray,
    parents: np.ndarray,
    xyz: np.ndarray,
    radii: np.ndarray,
    side: int = 256,
    min_radius: float = 2.0,
    margin: float = 4.0,
) -> SweptShape:
    """The tree (``ids``, ``parents``: -1 or an absent id for the root; ``xyz`` and
    ``radii`` in the tree's own units) drawn on an isotropic grid of at most ``side``
    voxels a side."""
    xyz = np.asarray(xyz, np.float64)
    lo, hi = xyz.min(axis=0), xyz.max(axis=0)
    voxel = float((hi - lo).max()) / (side - 1 - 2 * margin)
    for _ in range(3):  # the margin holds the widest tube
        pad = margin + max(float(np.max(radii)) / voxel, min_radius)
        voxel = float((hi - lo).max()) / (side - 1 - 2 * pad)
    pos = {int(i): (p - lo) / voxel + pad for i, p in zip(ids, xyz, strict=True)}
    rad = {int(i): max(float(r) / voxel, min_radius) for i, r in zip(ids, radii, strict=True)}
    parent = {int(i): int(p) for i, p in zip(ids, parents, strict=True)}
    parent = _prune_twigs(parent, pos, rad)
    shape = tuple(int(np.ceil(e)) for e in (hi - lo) / voxel + 2 * pad + 1)
    lines, line_radii, tips = [], [], []
    has_child = {parent[n] for n in parent}
    for path in _paths(parent, list(parent)):
        pts, rs = [], []
        for a, b in itertools.pairwise(path):
            seg = _segment(pos[a], pos[b])
            t = np.linspace(0.0, 1.0, len(seg))
            pts.append(seg if not pts else seg[1:])
            r = rad[a] * (1 - t) + rad[b] * t
            rs.append(r if len(rs) == 0 else r[1:])
        if not pts:
            continue
        lines.append(np.concatenate(pts)[:, ::-1].copy())  # (x, y, z) -> (z, y, x)
        line_radii.append(np.concatenate(rs))
        if path[0] not in has_child:
            tips.append(lines[-1][0].copy())
    roots = [n for n in parent if parent[n] not in parent]
    for n in roots:  # a root with one child is a free end too
        if sum(parent[m] == n for m in parent) == 1:
            tips.append(pos[n][::-1].copy())
    shape_zyx = (shape[2], shape[1], shape[0])
    return SweptShape(
        shape_zyx, (1.0, 1.0, 1.0), lines, line_radii, np.array(tips, float).reshape(-1, 3)
    )


def example_neurons(side: int = 256) -> list[tuple[str, SweptShape]]:
    """navis's example neurons (``navis.example_neurons()``), each drawn by
    :func:`swc_shape` within ``side`` voxels a side."""
    import navis

    out = []
    for n in navis.example_neurons():
        t = n.nodes
        out.append(
            (
                str(n.id),
                swc_shape(
                    t["node_id"].to_numpy(),
                    t["parent_id"].to_numpy(),
                    t[["x", "y", "z"]].to_numpy(),
                    t["radius"].to_numpy(),
                    side,
                ),
            )
        )
    return out
