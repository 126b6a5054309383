"""Endpoint stability over noise models and shape sizes at once.

Every shape (dataset silhouettes, and round-ended shapes drawn in ``testkit.shapes``) is
brought to each size band by scaling its contour and filling it again (not by repeating
pixels), then perturbed by every model of :data:`MODELS`: per-point contour-normal
noise N(0, 1) and U(±1.2) (every crack-contour vertex moved along its normal, filled at
sub-pixel precision), the resampled-contour noise, pixel flips, turns by 15° and 30°,
scalings by 0.5 and 1.5. For each pruning variant the perturbed copy's endpoint count is
compared with the clean copy's of the same size: equal (exact), within one (±1), more
(a gained branch) or fewer (a lost one). The six perturbations of the authors'
comparison are pooled as :data:`SIX`.
"""

from __future__ import annotations

import multiprocessing
import statistics
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import ndimage as ndi

from .perturb import PERTURBATIONS, _canvas, _clean, _fill, _hole_seeds, _rings, rescale

__all__ = ["MODELS", "SIX", "SIZE_VARIANTS", "SizeRecord", "run_sizes", "sizes_markdown"]

#: Perturbation models measured, by the names of :data:`~.perturb.PERTURBATIONS`.
MODELS = (
    "gaussian-1",
    "uniform-1.2",
    "resampled-1",
    "flips-0.5",
    "rotate-15",
    "rotate-30",
    "scale-0.5",
    "scale-1.5",
)
#: The six perturbations of the comparison with the authors' code, pooled.
SIX = ("gaussian-1", "uniform-1.2", "rotate-15", "rotate-30", "scale-0.5", "scale-1.5")
#: Longest side of the shape in each size band (pixels).
BANDS = (128, 256, 512)
#: Pruning variants measured: name -> options of :func:`skelprune.prune` (``argmin``:
#: ``min_margin=0``, the paper's answer; ``argmin/trim=false``: the paper's answer with
#: its branches whole).
SIZE_VARIANTS: dict[str, dict[str, Any]] = {
    "default": {},
    "argmin": {"min_margin": 0.0},
    "argmin/trim=false": {"min_margin": 0.0, "trim": False},
    "coarse=none": {"coarse": None},
    "noise-floor": {"choice": "noise-floor", "min_margin": 0.0},
    "min_margin=0.005": {"min_margin": 0.005},
    "min_margin=0.02": {"min_margin": 0.02},
    "min_margin=0.03": {"min_margin": 0.03},
    "min_margin=0.1": {"min_margin": 0.1},
}


@dataclass(frozen=True)
class SizeRecord:
    """Endpoint counts of one variant on one shape at one size: clean and perturbed."""

    shape: str
    band: int
    variant: str
    clean: int
    rer: float
    perturbed: tuple[tuple[str, int, int], ...]  # (model, seed, endpoints)


def at_size(mask: np.ndarray, side: int) -> np.ndarray:
    """The shape with its longer side ``side`` pixels: its contour scaled and filled again.

    Scaling up, the contour is first smoothed along itself (Gaussian of one source pixel),
    so that the source's pixel staircase does not become bumps of several pixels: the
    larger copy is the shape, not its digitisation blown up.
    """
    rows, cols = np.nonzero(mask)
    factor = side / (max(np.ptp(rows), np.ptp(cols)) + 1)
    if factor <= 1:
        return rescale(mask, factor, margin=2)
    rings = _rings(mask)
    seeds = _hole_seeds(rings, mask.shape)
    moved = [factor * ndi.gaussian_filter1d(r, 1.0, axis=0, mode="wrap") for r in rings]
    n = len(moved)
    shifted, shape = _canvas([*moved, *(factor * s.reshape(1, 2) for _, s in seeds)], 2)
    holes = [(shifted[k], shifted[n + j][0]) for j, (k, _) in enumerate(seeds)]
    return _clean(_fill(shifted[:n], shape), holes)


def _task(args: tuple[str, np.ndarray, int, tuple[str, ...], int]) -> list[SizeRecord]:
    from skelprune.api import prune

    name, mask, side, variants, seeds = args
    clean = at_size(mask, side)
    copies = []
    for model in MODELS:
        pert = PERTURBATIONS[model]
        n = 1 if pert.kind in ("rotate", "scale") else seeds
        for s in range(n):
            rng = np.random.default_rng([side, s, sum(map(ord, name + model))])
            copies.append((model, s, pert.apply(clean, rng)))
    out = []
    for v in variants:
        opts = SIZE_VARIANTS[v]
        res = prune(clean, **opts)
        area = sum(c.area for c in res.components)
        rer = sum(c.rer * c.area for c in res.components) / area
        counts = tuple((m, s, prune(p, **opts).n_endpoints()) for m, s, p in copies)
        out.append(SizeRecord(name, side, v, res.n_endpoints(), float(rer), counts))
    return out


def run_sizes(
    shapes: Sequence[tuple[str, np.ndarray]],
    variants: Sequence[str] = tuple(SIZE_VARIANTS),
    bands: Sequence[int] = BANDS,
    seeds: int = 2,
    workers: int = 2,
) -> list[SizeRecord]:
    """Measure every variant on every shape at every size band (one task each)."""
    tasks = [(n, m, side, tuple(variants), seeds) for side in bands for n, m in shapes]
    if workers <= 1:
        return [r for t in tasks for r in _task(t)]
    ctx = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
        return [r for rs in pool.map(_task, tasks) for r in rs]


def _share(pairs: list[tuple[int, int]], within: int) -> float:
    return 100.0 * sum(abs(p - c) <= within for c, p in pairs) / max(len(pairs), 1)


def sizes_markdown(records: list[SizeRecord]) -> str:
    """Tables: per variant and size band, exact / ±1 per model and pooled over the six,
    gains and losses apart, and the median clean RER."""
    variants = list(dict.fromkeys(r.variant for r in records))
    bands = sorted({r.band for r in records})
    lines = []
    head = "| variant | size | " + " | ".join(MODELS) + " | **six pooled** | gained | lost | RER |"
    lines += [head, "|" + "---|" * (len(MODELS) + 6)]
    for v in variants:
        for band in [*bands, 0]:
            rs = [r for r in records if r.variant == v and (band == 0 or r.band == band)]
            if not rs:
                continue
            cells = []
            for model in MODELS:
                pairs = [(r.clean, n) for r in rs for m, _, n in r.perturbed if m == model]
                cells.append(f"{_share(pairs, 0):.0f}/{_share(pairs, 1):.0f}")
            six = [(r.clean, n) for r in rs for m, _, n in r.perturbed if m in SIX]
            gained = 100.0 * sum(p > c for c, p in six) / max(len(six), 1)
            lost = 100.0 * sum(p < c for c, p in six) / max(len(six), 1)
            rer = 100.0 * statistics.median(r.rer for r in rs)
            size = "all" if band == 0 else f"{band} px"
            lines.append(
                f"| {v} | {size} | "
                + " | ".join(cells)
                + f" | **{_share(six, 0):.0f}/{_share(six, 1):.0f}** | {gained:.0f} % | "
                f"{lost:.0f} % | {rer:.2f} % |"
            )
    return "\n".join(lines)


def _anchor_task(args: tuple[str, str, str, Any, tuple[str, ...]]) -> list[tuple]:
    from PIL import Image

    from skelprune.api import prune

    batch, shape, pert, path, variants = args
    mask = np.asarray(Image.open(path)) != 0
    out = []
    for v in variants:
        res = prune(mask, **SIZE_VARIANTS[v])
        area = sum(c.area for c in res.components)
        rer = sum(c.rer * c.area for c in res.components) / area
        out.append((batch, shape, pert, v, res.n_endpoints(), float(rer)))
    return out


def run_anchor_variants(
    folder: Any, variants: Sequence[str], workers: int = 2
) -> list[tuple[str, str, str, str, int | None, float | None]]:
    """``(batch, shape, perturbation, method, endpoints, rer)`` of the authors' code
    (method ``"authors"``, from ``data/anchors``) and of ``variants`` on the same masks."""
    from .anchors import ANCHOR, load_anchors

    rows = load_anchors(folder)
    out: list[tuple[str, str, str, str, int | None, float | None]] = [
        (b, s, p, ANCHOR, e, rer) for b, s, p, _, e, rer in rows
    ]
    jobs = [(b, s, p, path, tuple(variants)) for b, s, p, path, _, _ in rows]
    if workers <= 1:
        out += [r for j in jobs for r in _anchor_task(j)]
    else:
        ctx = multiprocessing.get_context("spawn")
        with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
            out += [r for rs in pool.map(_anchor_task, jobs, chunksize=8) for r in rs]
    return out


def _pairs(got: dict, shapes: Sequence[str], perts: Sequence[str]) -> list[tuple[int, int]]:
    """(clean, perturbed) endpoint counts; a failed run counts as a disagreement."""
    out = []
    for s in shapes:
        for p in perts:
            c, q = got.get((s, "clean")), got.get((s, p))
            out.append((-99, 99) if c is None or q is None else (c, q))
    return out


def anchor_variants_markdown(rows: list[tuple]) -> str:
    """Per batch and method: exact / ±1 per perturbation and pooled over the six, gains
    and losses, median clean RER."""
    methods = list(dict.fromkeys(r[3] for r in rows))
    batches = list(dict.fromkeys(r[0] for r in rows))
    perts = [p for p in SIX if any(r[2] == p for r in rows)]
    lines = [
        "| batch | method | " + " | ".join(perts) + " | **pooled** | gained | lost | RER |",
        "|" + "---|" * (len(perts) + 6),
    ]
    for b in batches:
        for m in methods:
            got = {(r[1], r[2]): r[4] for r in rows if r[0] == b and r[3] == m}
            shapes = sorted({r[1] for r in rows if r[0] == b})

            cells = []
            for p in perts:
                one = _pairs(got, shapes, [p])
                cells.append(f"{_share(one, 0):.0f}/{_share(one, 1):.0f}")
            six = _pairs(got, shapes, perts)
            gained = 100.0 * sum(q > c for c, q in six) / max(len(six), 1)
            lost = 100.0 * sum(q < c for c, q in six) / max(len(six), 1)
            rers = [r[5] for r in rows if r[0] == b and r[3] == m and r[2] == "clean" and r[5]]
            rer = 100.0 * statistics.median(rers) if rers else float("nan")
            lines.append(
                f"| {b} | {m} | "
                + " | ".join(cells)
                + f" | **{_share(six, 0):.0f}/{_share(six, 1):.0f}** | {gained:.0f} % | "
                f"{lost:.0f} % | {rer:.2f} % |"
            )
    return "\n".join(lines)


def _gt_task(args: tuple[Any, str, tuple[str, ...]]) -> dict[str, np.ndarray]:
    from skelprune.api import prune

    from .groundtruth import _load, pixel_scores

    folder, name, variants = args
    mask, gt = _load(folder, name)
    out = {}
    for v in variants:
        rows, cols, _ = prune(mask, **SIZE_VARIANTS[v]).skeleton_points()
        sk = np.zeros(mask.shape, bool)
        sk[rows, cols] = True
        out[v] = pixel_scores(sk, gt)
    return out


def groundtruth_variants_markdown(folder: Any, variants: Sequence[str], workers: int = 2) -> str:
    """Mean precision / recall / F1 at 0–3 px of ``variants`` against the ground-truth
    skeletons of ``folder`` (``shapes/``, ``skeletons/``)."""
    from pathlib import Path

    from .groundtruth import TOLERANCES

    names = sorted(p.stem for p in (Path(folder) / "shapes").glob("*.png"))
    jobs = [(Path(folder), n, tuple(variants)) for n in names]
    if workers <= 1:
        scores = [_gt_task(j) for j in jobs]
    else:
        ctx = multiprocessing.get_context("spawn")
        with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
            scores = list(pool.map(_gt_task, jobs, chunksize=8))
    head = " | ".join(f"{t} px P / R / **F1**" for t in TOLERANCES)
    lines = [f"| variant | {head} |", "|" + "---|" * (len(TOLERANCES) + 1)]
    for v in variants:
        m = np.mean([s[v] for s in scores], axis=0)
        cells = " | ".join(f"{p:.3f} / {r:.3f} / **{f:.3f}**" for p, r, f in m)
        lines.append(f"| {v} | {cells} |")
    return f"{len(names)} shapes\n\n" + "\n".join(lines)
