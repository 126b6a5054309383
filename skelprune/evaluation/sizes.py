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
#: Pruning variants measured: name -> options of :func:`skelprune.prune`.
SIZE_VARIANTS: dict[str, dict[str, Any]] = {
    "default": {},
    "trim=false": {"trim": False},
    "coarse=none": {"coarse": None},
    "noise-floor": {"choice": "noise-floor"},
    "noise-floor,trim=false": {"choice": "noise-floor", "trim": False},
    "min_margin=0.01": {"min_margin": 0.01},
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
    from ..api import prune

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
