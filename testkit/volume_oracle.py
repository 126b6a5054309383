"""Naive references for the volume grid, from scratch and slow: what the compiled
kernels of :mod:`skelprune.grid3d` must equal on small volumes.

Distances and balls use the expression of docs/volumes.md, ``(a·dz)² + (b·dy)² + (c·dx)²``
for integer offsets ``(a, b, c)``, evaluated in that order, so equality is exact.
"""

from __future__ import annotations

import numpy as np

__all__ = ["ball_counts", "lost_volume", "naive_sequence", "naive_trim", "squared_distance"]


def _squared(offsets: np.ndarray, spacing) -> np.ndarray:
    a = offsets[..., 0] * float(spacing[0])
    b = offsets[..., 1] * float(spacing[1])
    c = offsets[..., 2] * float(spacing[2])
    return a * a + b * b + c * c


def squared_distance(volume: np.ndarray, spacing=(1.0, 1.0, 1.0)) -> np.ndarray:
    """Brute force: for every voxel inside, the least squared distance to a background
    voxel of the volume padded by one background voxel."""
    padded = np.pad(np.asarray(volume) != 0, 1)
    background = np.argwhere(~padded)
    out = np.zeros(padded.shape, dtype=np.float64)
    for p in np.argwhere(padded):
        out[tuple(p)] = _squared(background - p, spacing).min()
    return out[1:-1, 1:-1, 1:-1]


def ball_counts(shape, z, y, x, r2, spacing=(1.0, 1.0, 1.0)) -> np.ndarray:
    """Paint every ball ``|p − s|² < r2(s)`` over the whole array and add them up."""
    grid = np.indices(shape).transpose(1, 2, 3, 0)
    out = np.zeros(shape, dtype=np.int64)
    for s in zip(z, y, x, r2, strict=True):
        out += _squared(grid - np.array(s[:3]), spacing) < s[3]
    return out


def lost_volume(volume, z, y, x, r2, spacing=(1.0, 1.0, 1.0)) -> int:
    """Voxels inside that no ball covers, from :func:`ball_counts`."""
    volume = np.asarray(volume) != 0
    return int((volume & (ball_counts(volume.shape, z, y, x, r2, spacing) == 0)).sum())


def naive_sequence(graph, volume, z, y, x, r2, spacing, alpha: float, lbar: float):
    """The greedy pruning on a volume, every candidate's lost volume repainted from
    scratch at every step: the removal order and ``λ`` of every skeleton ``S(0..n)``.

    Topology comes from the same :class:`~skelprune.grid3d.graph.VolumeBranchGraph` as
    the fast code (its rules are the model); ``λ``, the length (steps of each kind times
    their physical length, summed in the kinds' order) and the tie order (``λ``, lost
    volume, length, free end's ``(z, y, x)``) are written here again from
    docs/algorithm.md.
    """
    import math

    volume = np.asarray(volume) != 0
    area = int(volume.sum())
    sp = np.asarray(spacing, float)
    kinds = [((k + 1) >> 2 & 1, (k + 1) >> 1 & 1, (k + 1) & 1) for k in range(7)]
    weights = [math.sqrt(float(((np.array(k) * sp) ** 2).sum())) for k in kinds]

    def length(steps) -> float:
        total = 0.0
        for c, w in zip(steps, weights, strict=True):
            total += c * w
        return total

    def lam(lost: int, steps) -> float:
        return alpha * lost / area + math.log(length(steps) / lbar + 1.0)

    def lost_without(skip=None) -> int:
        pts = []
        for b, br in enumerate(graph.branches):
            if br.alive and b != skip:
                pts.extend(br.points)
        for j in graph.junctions:
            if j.alive:
                pts.extend(j.points)
        pts = np.asarray(sorted(pts), np.int64)
        return lost_volume(volume, z[pts], y[pts], x[pts], r2[pts], spacing)

    def total(skip=None):
        out = [0] * 7
        for b, br in enumerate(graph.branches):
            if br.alive and b != skip:
                out = [u + v for u, v in zip(out, br.steps, strict=True)]
        return out

    balls = [
        ball_counts(volume.shape, [z[p]], [y[p]], [x[p]], [r2[p]], spacing) > 0
        for p in range(len(z))
    ]
    rim = float(sp[0] ** 2 + sp[1] ** 2 + sp[2] ** 2)

    def is_limb(b: int) -> bool:
        # docs/volumes.md, "Limbs": at least 2·r / h voxels deeper than the rim whose
        # whole ball no other voxel's ball touches, r the largest of them.
        others = np.zeros(volume.shape, bool)
        for c, br in enumerate(graph.branches):
            if br.alive and c != b:
                for p in br.points:
                    others |= balls[p]
        for j in graph.junctions:
            if j.alive:
                for p in j.points:
                    others |= balls[p]
        whole = [
            float(r2[p])
            for p in graph.branches[b].points
            if r2[p] > rim and not (others & balls[p]).any()
        ]
        return bool(whole) and len(whole) * float(sp.min()) >= 2.0 * math.sqrt(max(whole))

    lost = lost_without()
    lams = [lam(lost, graph.total_steps())]
    order = []
    limbs: set[int] = set()  # found once, kept for good
    while True:
        ends = [b for b in range(len(graph.branches)) if graph.is_end_branch(b)]
        ends = [b for b in ends if b not in limbs]
        if not ends:
            break
        keys = []
        for b in ends:
            lost_b = lost_without(skip=b)
            rest = [u - v for u, v in zip(total(), graph.branches[b].steps, strict=True)]
            p = graph.endpoint(b)
            keys.append(
                (
                    lam(lost_b, rest),
                    lost_b - lost,
                    length(graph.branches[b].steps),
                    int(z[p]),
                    int(y[p]),
                    int(x[p]),
                    b,
                )
            )
        pick = None
        for key in sorted(keys):  # the best that is not a limb
            if is_limb(key[-1]):
                limbs.add(key[-1])
                continue
            pick = key[-1]
            break
        if pick is None:
            break
        merged = graph.remove_end_branch(pick)
        if merged is not None and merged[1] in limbs:
            limbs.add(merged[0])
        order.append(pick)
        lost = lost_without()
        lams.append(lam(lost, graph.total_steps()))
    return order, lams


def naive_trim(graph, volume, z, y, x, r2, spacing, alpha: float, lbar: float):
    """The tips' cuts of docs/volumes.md ("Tips"), every candidate repainted from
    scratch: the cuts ``(branch, end, k)`` in the order made, the lost voxels after them
    and ``λ``. ``graph`` (a copy of the answer's graph) is cut in place; which points a
    cut drops comes from its ``tip`` (the model), everything else is written again here.
    """
    import math

    volume = np.asarray(volume) != 0
    area = int(volume.sum())
    sp = [float(s) for s in spacing]
    h = min(sp)
    kinds = [((k + 1) >> 2 & 1, (k + 1) >> 1 & 1, (k + 1) & 1) for k in range(7)]
    weights = [math.sqrt(float(((np.array(k) * np.array(sp)) ** 2).sum())) for k in kinds]
    balls = {}

    def ball(p: int) -> np.ndarray:
        if p not in balls:
            balls[p] = ball_counts(volume.shape, [z[p]], [y[p]], [x[p]], [r2[p]], spacing) > 0
        return balls[p]

    def points_now() -> set[int]:
        pts = set()
        for br in graph.branches:
            if br.alive:
                pts.update(br.points)
        for j in graph.junctions:
            if j.alive:
                pts.update(j.points)
        return pts

    def lost_of(pts) -> int:
        covered = np.zeros(volume.shape, bool)
        for p in pts:
            covered |= ball(p)
        return int((volume & ~covered).sum())

    def length(steps) -> float:
        total = 0.0
        for c, w in zip(steps, weights, strict=True):
            total += c * w
        return total

    def distance(p: int, s: int) -> float:
        a = float(z[p] - z[s]) * sp[0]
        b = float(y[p] - y[s]) * sp[1]
        c = float(x[p] - x[s]) * sp[2]
        return math.sqrt(a * a + b * b + c * c)

    def candidates(b: int, e: int):
        points, drop, steps = graph.tip(b, e)
        m = len(steps) + (0 if graph.branches[b].node[1 - e] is None else 1)
        now = points_now()
        base = lost_of(now)
        out = []
        dropped = [0] * 7
        for k in range(m):
            if k:
                dropped[steps[k - 1]] += 1
            gone = {p for p, d in zip(points, drop, strict=True) if d < k}
            lost_k = lost_of(now - gone) - base
            s = points[k]
            remnant = k == 0 or (
                lost_k <= k and all(distance(p, s) < math.sqrt(float(r2[s])) + h for p in gone)
            )
            out.append((lost_k, tuple(dropped), remnant, gone))
        return out

    def best(cands, lost0: int) -> int:
        total = graph.total_steps()
        pick, pick_lam = 0, math.inf
        for k, (lost_k, st, remnant, _) in enumerate(cands):
            if not remnant:
                continue
            rest = [u - v for u, v in zip(total, st, strict=True)]
            lam = alpha * (lost0 + lost_k) / area + math.log(length(rest) / lbar + 1.0)
            if lam <= pick_lam:  # ties to the shorter tip
                pick, pick_lam = k, lam
        return pick

    lost = lost_of(points_now())
    keyed = []
    for b, e in graph.free_ends():
        cands = candidates(b, e)
        k = best(cands, lost)
        p = graph.free_end_point(b, e)
        keyed.append((-length(cands[k][1]), int(z[p]), int(y[p]), int(x[p]), b, e))
    cuts = []
    for *_, b, e in sorted(keyed):
        cands = candidates(b, e)
        k = best(cands, lost)
        cuts.append((b, e, k))
        if k:
            lost_k, st, _, gone = cands[k]
            graph.cut_tip(b, e, sorted(gone), st)
            lost += lost_k
    lam = alpha * lost / area + math.log(length(graph.total_steps()) / lbar + 1.0)
    return cuts, lost, lam
