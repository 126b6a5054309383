"""How flat is λ where the Bayesian pruning chooses? (docs/stability-findings.md)

On every second kimia216 shape and four perturbations, with the default pipeline:

* how often the coarse skeleton alone (before the Bayesian stage) keeps the clean shape's
  endpoint count, beside the final skeleton;
* for the disagreeing cases, how far above the minimum λ is the best skeleton of the
  noisy sequence that has the clean count;
* the agreement under the smallest perturbations there are: the grid's own symmetries
  (a turn by 90°, a mirror), which change no pixel, and turns by 1° or 2° and a 2 %
  rescaling, which move a few boundary pixels;
* the agreement a different choice rule would reach: the simplest skeleton whose λ is
  within a margin of the minimum. docs/algorithm.md fixes the answer as ``argmin λ``; the margin
  rows are a measurement, not an option of the library.

``python -m benchmarks choice`` (about half a minute on one core).
"""

from __future__ import annotations

import importlib

import numpy as np

from evaluation.perturb import rescale, rotate
from evaluation.stability import PERTURBATIONS, _rng, load_dataset
from skelprune import prune
from skelprune.api import components
from skelprune.grid._orientation import oriented
from skelprune.grid.coarse import coarse_removals
from skelprune.grid.graph import BranchGraph

from .common import DATA, table

medial_axis_module = importlib.import_module("skelprune.grid.medial_axis")
MARGINS = (0.0, 0.005, 0.01, 0.02, 0.05)
KINDS = ("gaussian-1", "uniform-1.5", "rotate-30", "scale-0.5")
SMALLEST = {
    "turn by 90°": lambda m: np.ascontiguousarray(np.rot90(m)),
    "mirror": lambda m: np.ascontiguousarray(m[:, ::-1]),
    "turn by 1°": lambda m: rotate(m, 1.0),
    "turn by 2°": lambda m: rotate(m, 2.0),
    "rescale by 1.02": lambda m: rescale(m, 1.02),
}


def _smallest(shapes: list[tuple[str, np.ndarray]]) -> None:
    """Agreement under the smallest perturbations, and how often they change the area."""
    clean = [prune(m).n_endpoints() for _, m in shapes]
    rows = []
    for name, perturb in SMALLEST.items():
        ok = changed = 0
        for (_, mask), k0 in zip(shapes, clean, strict=True):
            p = perturb(mask)
            ok += prune(p).n_endpoints() == k0
            changed += p.sum() != mask.sum()  # a turn by 90° or a mirror: never
        rows.append(
            [
                name,
                len(shapes),
                f"{100 * changed / len(shapes):.0f} %",
                f"{100 * ok / len(shapes):.0f} %",
            ]
        )
    print(table(["perturbation", "shapes", "area changed", "same endpoint count"], rows))


def _choices(mask: np.ndarray) -> tuple[int, np.ndarray, list[tuple[np.ndarray, np.ndarray]]]:
    """Coarse endpoint count; count chosen under each margin; per component (λ, counts)."""
    result = prune(mask)
    coarse = 0
    chosen = np.zeros(len(MARGINS), int)
    curves = []
    for (raw, _), comp in zip(components(mask != 0), result.components, strict=True):
        crop, _ = oriented(raw)  # the frame of the result's branch ids
        ma = medial_axis_module.medial_axis(crop, medial_axis_module.squared_distance(crop))
        graph = BranchGraph(ma.rows, ma.cols, crop.shape)
        if graph.ends:
            coarse_removals(graph, crop, ma.r2)
        counts = [graph.n_endpoints()]
        coarse += counts[0]
        for b in comp.sequence.removed:
            graph.remove_end_branch(b)
            counts.append(graph.n_endpoints())
        lam = np.asarray(comp.sequence.objective, float)
        if comp.sequence.alpha is None or len(lam) != len(counts):
            chosen += comp.graph.n_endpoints()  # degenerate: nothing was chosen
            continue
        low = lam.min()
        for k, margin in enumerate(MARGINS):
            chosen[k] += counts[np.flatnonzero(lam <= low + margin * abs(low))[-1]]
        curves.append((lam, np.asarray(counts)))
    return coarse, chosen, curves


def main() -> None:
    shapes = load_dataset(DATA / "kimia216")[::2]
    rows_agree, gaps = [], []
    for kind in KINDS:
        coarse_ok = 0
        ok = np.zeros(len(MARGINS), int)
        for i, (_, mask) in enumerate(shapes):
            c0, k0, _ = _choices(mask)
            c1, k1, curves = _choices(PERTURBATIONS[kind].apply(mask, _rng(0, i, kind)))
            coarse_ok += c0 == c1
            ok += k0 == k1
            if k0[0] != k1[0] and len(curves) == 1:
                lam, counts = curves[0]
                same = counts == k0[0]
                if same.any():
                    gaps.append((lam[same].min() - lam.min()) / abs(lam.min()))
        n = len(shapes)
        rows_agree.append(
            [kind, n, f"{100 * coarse_ok / n:.0f} %"] + [f"{100 * a / n:.0f} %" for a in ok]
        )
    print(
        table(
            ["perturbation", "shapes", "coarse skeleton agrees", "argmin λ (shipped)"]
            + [f"simplest within {100 * m:g} %" for m in MARGINS[1:]],
            rows_agree,
        )
    )
    q = np.percentile(gaps, [25, 50, 75]) if gaps else [np.nan] * 3
    print()
    print(
        table(
            [
                "disagreeing cases where the clean count is in the sequence",
                "λ above the minimum: p25",
                "median",
                "p75",
            ],
            [[len(gaps), f"{100 * q[0]:.2f} %", f"{100 * q[1]:.2f} %", f"{100 * q[2]:.2f} %"]],
        )
    )
    print()
    _smallest(shapes)


if __name__ == "__main__":
    main()
