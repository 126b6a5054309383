"""What branch margins are worth: flips by margin quantile, and the ``min_margin`` option.

Over the shapes and perturbations of the stability benchmark (the same seeded noise
draws as :mod:`evaluation.stability`), with the library's default pruning:

* **Flip table.** A clean end branch is *lost* under a perturbation when no end branch of
  the perturbed skeleton ends near its endpoint; a perturbed end branch is *gained* when
  no clean one ends near it. "Near": within :data:`MATCH_RADIUS` pixels (times the scale
  factor) after mapping the clean endpoint by the perturbation (its rotation or scale
  about the shape's centroid, onto the perturbed shape's centroid), matched one to one,
  nearest pairs first. Branches are grouped by the quartile of their margin (lost: the
  clean margin; gained: the perturbed one), quartile edges taken over all clean end
  branches.
* **min_margin.** For each value, the median RER of the clean shapes and the endpoint
  agreement (perturbed count equal to the clean count, both with that ``min_margin``).
"""

from __future__ import annotations

import math
import multiprocessing
from collections.abc import Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass

import numpy as np

from .perturb import PERTURBATIONS, Perturbation
from .stability import _rng

__all__ = [
    "MATCH_RADIUS",
    "MIN_MARGINS",
    "MarginRun",
    "end_branches",
    "margin_markdown",
    "run_margins",
]

#: Endpoints this close (pixels of the clean shape) are the same branch's.
MATCH_RADIUS = 5.0
#: ``min_margin`` values measured (a fixed log-spaced grid, not fitted to any data).
MIN_MARGINS: tuple[float, ...] = (0.01, 0.03, 0.1, 0.3)


def end_branches(res) -> list[tuple[float, float, float]]:
    """``(row, col, margin)`` of the free end of every end branch of a result."""
    out = []
    for comp in res.components:
        g = comp.graph
        for b in g.end_branches():
            br = g.branches[b]
            path = br.path()
            p = path[0] if br.node[0] is None else path[-1]
            r, c = comp.image_coordinates(g.rows[[p]], g.cols[[p]])
            m = comp.margins.margin.get(b)
            out.append((float(r[0]), float(c[0]), math.nan if m is None else float(m)))
    return out


def _centroid(mask: np.ndarray) -> np.ndarray:
    rows, cols = np.nonzero(mask)
    return np.array([rows.mean(), cols.mean()])


def _linear(p: Perturbation) -> tuple[np.ndarray, float]:
    """The perturbation's linear map on (row, col) and its scale factor."""
    if p.kind == "rotate":
        a = np.deg2rad(p.param)
        return np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]]), 1.0
    if p.kind == "scale":
        return np.eye(2) * p.param, p.param
    return np.eye(2), 1.0


def _match(a: np.ndarray, b: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """One-to-one matching, nearest pairs first: which rows of ``a`` and ``b`` matched."""
    ma, mb = np.zeros(len(a), bool), np.zeros(len(b), bool)
    if len(a) and len(b):
        d = np.hypot(a[:, None, 0] - b[None, :, 0], a[:, None, 1] - b[None, :, 1])
        for i, j in zip(*np.unravel_index(np.argsort(d, axis=None), d.shape), strict=True):
            if d[i, j] > radius:
                break
            if not ma[i] and not mb[j]:
                ma[i] = mb[j] = True
    return ma, mb


@dataclass(frozen=True)
class _ShapeResult:
    dataset: str
    clean: list[float]  # margin of each clean end branch
    lost: dict[str, list[tuple[float, bool]]]  # perturbation -> (clean margin, lost)
    gained: dict[str, list[tuple[float, bool]]]  # perturbation -> (perturbed margin, gained)
    rer: dict[float | None, float]  # min_margin -> clean RER (area-weighted)
    endpoints: dict[float | None, dict[str, int]]  # min_margin -> {"clean"|pert: count}


def _rer(res) -> float:
    area = sum(c.area for c in res.components)
    return sum(c.rer * c.area for c in res.components) / area


def _task(
    args: tuple[str, int, np.ndarray, int, tuple[Perturbation, ...], tuple[float, ...]],
) -> _ShapeResult:
    from skelprune.api import prune

    dataset, index, mask, seed, perts, mins = args
    clean = prune(mask, min_margin=0.0)  # the paper's argmin
    ends = end_branches(clean)
    c_pos = np.array([e[:2] for e in ends]).reshape(-1, 2)
    centre = _centroid(mask)
    lost: dict[str, list[tuple[float, bool]]] = {}
    gained: dict[str, list[tuple[float, bool]]] = {}
    rer: dict[float | None, float] = {None: _rer(clean)}
    counts: dict[float | None, dict[str, int]] = {None: {"clean": clean.n_endpoints()}}
    for m in mins:
        res = prune(mask, min_margin=m)
        rer[m] = _rer(res)
        counts[m] = {"clean": res.n_endpoints()}
    for p in perts:
        pm = p.apply(mask, _rng(seed, index, p.name))
        res = prune(pm, min_margin=0.0)
        counts[None][p.name] = res.n_endpoints()
        for m in mins:
            counts[m][p.name] = prune(pm, min_margin=m).n_endpoints()
        pends = end_branches(res)
        matrix, factor = _linear(p)
        mapped = (c_pos - centre) @ matrix.T + _centroid(pm)
        p_pos = np.array([e[:2] for e in pends]).reshape(-1, 2)
        ma, mb = _match(mapped, p_pos, MATCH_RADIUS * factor)
        lost[p.name] = [(e[2], not k) for e, k in zip(ends, ma, strict=True)]
        gained[p.name] = [(e[2], not k) for e, k in zip(pends, mb, strict=True)]
    return _ShapeResult(dataset, [e[2] for e in ends], lost, gained, rer, counts)


@dataclass
class MarginRun:
    """Per-shape results of :func:`run_margins`, with the tables' aggregations."""

    results: list[_ShapeResult]
    perturbations: tuple[str, ...]
    datasets: tuple[str, ...]
    min_margins: tuple[float, ...]

    def edges(self) -> np.ndarray:
        """Quartile edges of the margins of all clean end branches (NaN-free)."""
        m = np.array([c for r in self.results for c in r.clean])
        m = m[np.isfinite(m)]
        return np.quantile(m, [0.25, 0.5, 0.75]) if m.size else np.zeros(3)

    def flips(self, kind: str, perturbation: str) -> tuple[list[float], int, int]:
        """Share flipped per margin quartile, flips in all, branches in all."""
        edges = self.edges()
        rows = [
            x for r in self.results for x in getattr(r, kind)[perturbation] if math.isfinite(x[0])
        ]
        q = np.searchsorted(edges, [x[0] for x in rows], side="right")
        flipped = np.array([x[1] for x in rows], bool)
        shares = [float(flipped[q == k].mean()) if (q == k).any() else math.nan for k in range(4)]
        return shares, int(flipped.sum()), len(rows)

    def low_share(self, perturbation: str) -> float:
        """Of all flips (lost and gained), the share in the lowest margin quartile."""
        edges = self.edges()
        flips = [
            x[0]
            for r in self.results
            for kind in ("lost", "gained")
            for x in getattr(r, kind)[perturbation]
            if x[1] and math.isfinite(x[0])
        ]
        if not flips:
            return math.nan
        return float(np.mean(np.asarray(flips) <= edges[0]))

    def agreement(self, m: float | None, perturbation: str, within: int = 0) -> float:
        got = [
            abs(r.endpoints[m][perturbation] - r.endpoints[m]["clean"]) <= within
            for r in self.results
        ]
        return float(np.mean(got))

    def median_rer(self, m: float | None, dataset: str) -> float:
        return float(np.median([r.rer[m] for r in self.results if r.dataset == dataset]))

    def mean_endpoints(self, m: float | None) -> float:
        return float(np.mean([r.endpoints[m]["clean"] for r in self.results]))


def run_margins(
    datasets: dict[str, Sequence[tuple[str, np.ndarray]]],
    perturbations: Iterable[Perturbation] = tuple(PERTURBATIONS.values()),
    min_margins: Iterable[float] = MIN_MARGINS,
    seed: int = 7,
    workers: int = 2,
    progress: bool = True,
) -> MarginRun:
    """Run the flip and ``min_margin`` measurements (one task per shape)."""
    from tqdm import tqdm

    perts = tuple(perturbations)
    mins = tuple(min_margins)
    jobs = [
        (d, i, m, seed, perts, mins)
        for d, items in datasets.items()
        for i, (_, m) in enumerate(items)
    ]
    results: list[_ShapeResult] = []
    with tqdm(total=len(jobs), unit="shape", disable=not progress, desc="margins") as bar:
        if workers > 1:
            ctx = multiprocessing.get_context("forkserver")
            with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
                for r in pool.map(_task, jobs):
                    results.append(r)
                    bar.update()
        else:
            for job in jobs:
                results.append(_task(job))
                bar.update()
    return MarginRun(results, tuple(p.name for p in perts), tuple(datasets), mins)


def _pct(x: float) -> str:
    return "–" if math.isnan(x) else f"{100 * x:.0f} %"


def flip_table(run: MarginRun) -> str:
    """Markdown: lost and gained shares by margin quartile, per perturbation."""
    e = run.edges()
    head = (
        f"| perturbation | lost, all | lost Q1 (≤ {e[0]:.3g}) | lost Q2 | lost Q3 "
        f"| lost Q4 (> {e[2]:.3g}) | gained, all | gained Q1 | gained Q2 | gained Q3 "
        "| gained Q4 | flips in Q1 |"
    )
    lines = [head, "|---" * 12 + "|"]
    for p in run.perturbations:
        lost, nl, tl = run.flips("lost", p)
        gained, ng, tg = run.flips("gained", p)
        lines.append(
            f"| {p} | {nl}/{tl} | "
            + " | ".join(_pct(x) for x in lost)
            + f" | {ng}/{tg} | "
            + " | ".join(_pct(x) for x in gained)
            + f" | {_pct(run.low_share(p))} |"
        )
    return "\n".join(lines)


def min_margin_table(run: MarginRun) -> str:
    """Markdown: RER, endpoints and endpoint agreement for each ``min_margin``."""
    lines = [
        "| min_margin | "
        + " | ".join(f"median RER {d}" for d in run.datasets)
        + " | endpoints, mean | agreement, mean of perturbations | worst perturbation"
        " | within ±1, mean |",
        "|---" * (len(run.datasets) + 5) + "|",
    ]
    for m in (None, *run.min_margins):
        agree = [run.agreement(m, p) for p in run.perturbations]
        near = [run.agreement(m, p, within=1) for p in run.perturbations]
        worst = int(np.argmin(agree))
        lines.append(
            f"| {'off (default)' if m is None else f'{m:g}'} | "
            + " | ".join(f"{100 * run.median_rer(m, d):.2f} %" for d in run.datasets)
            + f" | {run.mean_endpoints(m):.2f} | {_pct(float(np.mean(agree)))} | "
            f"{_pct(agree[worst])} ({run.perturbations[worst]}) | {_pct(float(np.mean(near)))} |"
        )
    return "\n".join(lines)


def margin_markdown(run: MarginRun, command: str) -> str:
    """The generated report ``docs/margin.md``."""
    n = len(run.results)
    return f"""# Branch margins: measured

Generated by `{command}`; the margin is defined in [graph.md](graph.md#branch-margins).
{n} shapes ({", ".join(run.datasets)}), the perturbations and seeded noise draws of the
stability benchmark, the library's default pruning.

## Flips by margin quartile

A clean end branch is *lost* when no perturbed end branch ends within
{MATCH_RADIUS:g} px (times the scale factor) of its mapped endpoint; a perturbed end
branch is *gained* when no clean one ends near it. Each cell is the share of the end
branches of that margin quartile (edges over all clean end branches) that flipped. The
last column: of all flips, the share whose margin is in the lowest quartile (25 % if the
margin said nothing).

{flip_table(run)}

## `min_margin`

Each row prunes the clean and the perturbed shapes with that `min_margin`; agreement is
the share of shapes whose perturbed endpoint count equals the clean one.

{min_margin_table(run)}
"""
