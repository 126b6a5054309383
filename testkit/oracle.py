"""Naive oracle for the Bayesian pruning (docs/algorithm.md).

Topology comes from the same :class:`BranchGraph` as the fast code (the rules of
which branch is an end branch and how junctions dissolve are the model, not the
optimisation). Everything the fast code keeps incrementally is recomputed here from
scratch, with an independent numpy reconstruction: at every step, for every
candidate, the disks of all remaining points are painted anew. The target λ and the
tie order are written here again from docs/algorithm.md, not imported, so that the
production formula is checked too.
"""

from __future__ import annotations

import math

import numpy as np

from skelprune.graph import BranchGraph


def objective(lost: int, area: int, na: int, nd: int, alpha: float, lbar: float) -> float:
    """docs/algorithm.md: ``λ = α·AR + log(Γ + 1)``, ``AR = lost / area``, ``Γ = L / ℓ̄``, where the
    length ``L`` counts ``na`` axial steps of 1 and ``nd`` diagonal steps of √2."""
    length = na + nd * math.sqrt(2.0)
    return alpha * lost / area + math.log(length / lbar + 1.0)


def candidate_key(graph: BranchGraph, b: int, lam: float, d_area: int) -> tuple:
    """docs/algorithm.md's order of candidates: smallest λ, then smaller lost area, then shorter,
    then smaller endpoint (row, col)."""
    br = graph.branches[b]
    p = graph.endpoint(b)
    return (lam, d_area, br.na + br.nd * math.sqrt(2.0), int(graph.rows[p]), int(graph.cols[p]))


def disk_pixels(rows, cols, r2, shape) -> list[np.ndarray]:
    """Flat pixel indices of each point's disk ``|p - s|^2 < r2``, by brute force."""
    w = shape[1]
    out = []
    for r, c, v in zip(rows, cols, r2, strict=True):
        rad = int(np.ceil(np.sqrt(v)))
        yy, xx = np.mgrid[r - rad : r + rad + 1, c - rad : c + rad + 1]
        inside = (yy - r) ** 2 + (xx - c) ** 2 < v
        out.append((yy[inside] * w + xx[inside]).astype(np.int64))
    return out


def uncovered(mask_flat: np.ndarray, disks: list[np.ndarray], points) -> int:
    covered = np.zeros(mask_flat.size, bool)
    if len(points):
        covered[np.concatenate([disks[p] for p in points])] = True
    return int((mask_flat & ~covered).sum())


def naive_sequence(
    graph: BranchGraph, mask: np.ndarray, r2: np.ndarray, alpha: float, lbar: float
) -> tuple[list[int], list[float]]:
    """Removal order and the λ of every skeleton S(0..n), recomputed from scratch."""
    flat = mask.ravel()
    area = int(flat.sum())
    disks = disk_pixels(graph.rows, graph.cols, r2, mask.shape)

    def current_points(skip=None):
        pts = []
        for b, br in enumerate(graph.branches):
            if br.alive and b != skip:
                pts.extend(br.points)
        for j in graph.junctions:
            if j.alive:
                pts.extend(j.points)
        return pts

    def total_length(skip=None):
        na = sum(br.na for b, br in enumerate(graph.branches) if br.alive and b != skip)
        nd = sum(br.nd for b, br in enumerate(graph.branches) if br.alive and b != skip)
        return na, nd

    lost = uncovered(flat, disks, current_points())
    lams = [objective(lost, area, *total_length(), alpha, lbar)]
    removed = []
    while True:
        cands = [b for b in range(len(graph.branches)) if graph.is_end_branch(b)]
        if not cands:
            break
        best = None
        for b in cands:
            lost_b = uncovered(flat, disks, current_points(skip=b))
            lam = objective(lost_b, area, *total_length(skip=b), alpha, lbar)
            key = candidate_key(graph, b, lam, lost_b - lost)
            if best is None or key < best:
                best, pick, pick_lost = key, b, lost_b
        graph.remove_end_branch(pick)
        removed.append(pick)
        lost = pick_lost
        lams.append(objective(lost, area, *total_length(), alpha, lbar))
    return removed, lams
