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

import itertools
import math

import numpy as np

from skelprune.grid.graph import BranchGraph


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
    return (
        lam,
        d_area,
        br.steps[0] + br.steps[1] * math.sqrt(2.0),
        int(graph.rows[p]),
        int(graph.cols[p]),
    )


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
        na = sum(br.steps[0] for b, br in enumerate(graph.branches) if br.alive and b != skip)
        nd = sum(br.steps[1] for b, br in enumerate(graph.branches) if br.alive and b != skip)
        return na, nd

    def is_limb(b: int) -> bool:
        # docs/algorithm.md, "Limbs": at least 2·r points deeper than the rim (r² > 2)
        # whose whole disk no other point's disk touches, r the largest of them.
        others = np.zeros(flat.size, bool)
        pts = current_points(skip=b)
        if pts:
            others[np.concatenate([disks[p] for p in pts])] = True
        whole = [
            int(r2[p]) for p in graph.branches[b].points if r2[p] > 2 and not others[disks[p]].any()
        ]
        return bool(whole) and len(whole) >= 2.0 * math.sqrt(max(whole))

    lost = uncovered(flat, disks, current_points())
    lams = [objective(lost, area, *total_length(), alpha, lbar)]
    removed = []
    limbs: set[int] = set()  # found once, kept for good
    while True:
        cands = [b for b in range(len(graph.branches)) if graph.is_end_branch(b)]
        ranked = []
        for b in cands:
            if b in limbs:
                continue
            lost_b = uncovered(flat, disks, current_points(skip=b))
            lam = objective(lost_b, area, *total_length(skip=b), alpha, lbar)
            ranked.append((candidate_key(graph, b, lam, lost_b - lost), b, lost_b))
        pick = None
        for _, b, lost_b in sorted(ranked):  # the best that is not a limb
            if is_limb(b):
                limbs.add(b)
                continue
            pick, pick_lost = b, lost_b
            break
        if pick is None:
            break
        merged = graph.remove_end_branch(pick)
        if merged is not None and merged[1] in limbs:
            limbs.add(merged[0])
        removed.append(pick)
        lost = pick_lost
        lams.append(objective(lost, area, *total_length(), alpha, lbar))
    return removed, lams


def is_remnant(
    graph: BranchGraph, r2: np.ndarray, path: list[int], gone: set[int], lost: int, rule: str
) -> bool:
    """docs/algorithm.md ("Tips"): may a cut that leaves ``path[k]`` as the end, dropping
    the points ``gone`` (``k`` of them on the path) and losing ``lost`` pixels, be taken?

    ``area``: at most one lost pixel per dropped path point; ``reach``: every dropped
    point lies inside the new end's disk (``|p − s|² < r(s)²``); ``either``: one of the
    two; ``none``: any cut.
    """
    k = sum(1 for p in path if p in gone)
    if rule == "none" or k == 0:
        return True
    end = path[k]
    ey, ex = int(graph.rows[end]), int(graph.cols[end])
    far = max(math.hypot(int(graph.rows[p]) - ey, int(graph.cols[p]) - ex) for p in gone)
    radius = math.sqrt(int(r2[end]))
    small = lost <= k
    return {
        "reach": far < radius + 1.0,
        "disk": far < radius,
        "area": small,
        "both": small and far < radius + 1.0,
    }[rule]


def naive_trim(
    graph: BranchGraph,
    mask: np.ndarray,
    r2: np.ndarray,
    alpha: float,
    lbar: float,
    rule: str = "both",
) -> tuple[list[tuple[int, int, int]], float]:
    """The tip cuts of docs/algorithm.md ("Tips") on the skeleton ``graph`` (changed in
    place), recomputed from scratch: every candidate cut's skeleton painted anew, and
    only the cuts the remnant ``rule`` allows (:func:`is_remnant`) taken.

    Which points a cut drops is the graph's model (:meth:`BranchGraph.tip`, as the
    topology is); lengths are counted again from the points' coordinates, areas painted
    again, λ written again. Returns ``(branch, end, k)`` of every end in the order cut,
    and the λ of the trimmed skeleton.
    """
    flat = mask.ravel()
    area = int(flat.sum())
    disks = disk_pixels(graph.rows, graph.cols, r2, mask.shape)
    sqrt2 = math.sqrt(2.0)
    na0 = sum(br.steps[0] for br in graph.branches if br.alive)
    nd0 = sum(br.steps[1] for br in graph.branches if br.alive)

    def points_now() -> set[int]:
        pts = {p for br in graph.branches if br.alive for p in br.points}
        return pts | {p for j in graph.junctions if j.alive for p in j.points}

    def cut_steps(path: list[int], k: int) -> tuple[int, int]:
        """Axial and diagonal steps among the first ``k`` points of a path."""
        na = nd = 0
        for p, q in itertools.pairwise(path[: k + 1]):
            dy, dx = abs(graph.rows[p] - graph.rows[q]), abs(graph.cols[p] - graph.cols[q])
            assert max(dy, dx) == 1  # consecutive 8-neighbours
            if dy and dx:
                nd += 1
            else:
                na += 1
        return na, nd

    def best_cut(b: int, e: int, na: int, nd: int) -> tuple[int, float, int, int, list[int]]:
        points, drop, steps = graph.tip(b, e)
        n_path = len(steps) + 1
        path = points[:n_path]
        single = graph.branches[b].node[1 - e] is None  # keeps two points, two endpoints

        assert drop[:n_path] == list(range(n_path))
        here = points_now()
        lost_now = uncovered(flat, disks, sorted(here))
        best = None
        for k in range(n_path - 1 if single else n_path):
            gone = {p for p, i in zip(points, drop, strict=True) if i < k}
            lost = uncovered(flat, disks, sorted(here - gone))
            if not is_remnant(graph, r2, path, gone, lost - lost_now, rule):
                continue
            ka, kd = cut_steps(path, k)
            lam = objective(lost, area, na - ka, nd - kd, alpha, lbar)
            if best is None or lam <= best[1]:  # ties: the shorter tip
                best = (k, lam, ka, kd, sorted(gone))
        assert best is not None
        return best

    order = []
    for b, e in graph.free_ends():
        k, _, ka, kd, _ = best_cut(b, e, na0, nd0)
        p = graph.tip(b, e)[0][0]
        order.append((-(ka + kd * sqrt2), int(graph.rows[p]), int(graph.cols[p]), b, e))
    order.sort()
    cuts = []
    na, nd = na0, nd0
    lam = objective(uncovered(flat, disks, sorted(points_now())), area, na, nd, alpha, lbar)
    for *_, b, e in order:
        k, lam_k, ka, kd, gone = best_cut(b, e, na, nd)
        cuts.append((b, e, k))
        if k:
            graph.cut_tip(b, e, gone, (ka, kd))
            na, nd, lam = na - ka, nd - kd, lam_k
    return cuts, lam
