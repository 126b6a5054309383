"""Markdown tables of a stability run, shared by ``bench_stability`` and ``skelprune eval``."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from .eval_stability import RECTANGLE, VARIANTS, StabilityRun

if TYPE_CHECKING:
    from .eval_anchors import AnchorRun

__all__ = [
    "agreement_table",
    "clean_table",
    "distance_table",
    "markdown_table",
    "pct",
    "rectangle_table",
    "stability_markdown",
    "targets_table",
]


def markdown_table(header: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
    """A markdown table; floats are printed with 3 significant digits."""
    cells = [[str(h) for h in header]]
    cells += [[f"{c:.3g}" if isinstance(c, float) else str(c) for c in r] for r in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(header))]
    lines = ["| " + " | ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)) + " |"
             for r in cells]
    lines.insert(1, "|" + "|".join("-" * (w + 2) for w in widths) + "|")
    return "\n".join(lines)


def pct(x: float) -> str:
    """A share as a percentage with one decimal."""
    return "–" if math.isnan(x) else f"{100 * x:.1f} %"


def agreement_table(run: StabilityRun, dataset: str, within: tuple[int, ...] = (0,)) -> str:
    """Endpoint agreement (%) per perturbation (rows) and variant (columns).

    ``within``: the endpoint differences allowed, one share per entry in each cell
    (``(0,)``, the exact count, is the SPEC §5 measure; ``(1, 2)`` the loose reading).
    """
    def cell(v: str, perturbations: tuple[str, ...]) -> str:
        return " / ".join(pct(min(run.agreement(dataset, v, p, k) for p in perturbations))
                          for k in within)

    rows = [[p, *(cell(v, (p,)) for v in run.variants)] for p in run.perturbations]
    rows.append(["**min**", *(cell(v, run.perturbations) for v in run.variants)])
    head = "perturbation"
    if within != (0,):
        head += f" ({' / '.join(f'±{k}' for k in within)})"
    return markdown_table([head, *run.variants], rows)


def distance_table(run: StabilityRun, dataset: str) -> str:
    """Median skeleton distance (% of √area) per perturbation (rows) and variant (columns)."""
    def cell(v: str, p: str) -> str:
        d = run.distance(dataset, v, p)
        return "–" if math.isnan(d) else f"{100 * d:.2f}"

    rows = [[p, *(cell(v, p) for v in run.variants)] for p in run.perturbations]
    return markdown_table(["perturbation (median distance, % of √area)", *run.variants], rows)


def rectangle_table(run: StabilityRun) -> str:
    """Per noise kind and variant: share with 4 endpoints and mean eq. 13 error (px²)."""
    rows = []
    for n in run.rect_noises():
        cells = [f"{pct(run.rect_share4(n, v))} / {run.rect_error(n, v):.2f}"
                 for v in run.variants]
        rows.append([n, *cells])
    return markdown_table(["noise (4 endpoints / mean error px²)", *run.variants], rows)


def clean_table(run: StabilityRun) -> str:
    """Median RER (%) and median ms a shape, per dataset and variant (clean shapes)."""
    rows = []
    for d in run.datasets:
        rer = [np.median([r.rer for r in run.clean(d, v)]) for v in run.variants]
        ms = [np.median([r.ms for r in run.clean(d, v)]) for v in run.variants]
        rows.append([f"{d}: median RER", *(f"{100 * x:.2f} %" for x in rer)])
        rows.append([f"{d}: median ms a shape", *(f"{x:.1f}" for x in ms)])
    return markdown_table(["clean shapes", *run.variants], rows)


def targets_table(run: StabilityRun, anchors: AnchorRun | None = None) -> str:
    """Which variant meets which SPEC §5 target.

    The agreement target is relative to the authors' code on the masks of
    ``data/anchors`` (``anchors``, when run); the 90 % share is kept as a reading.
    """
    rows = []
    for v in run.variants:
        t = run.meets_targets(v)
        row = [v, pct(run.min_agreement(v)), "yes" if t["agreement"] else "no"]
        if anchors is not None:
            known = v in anchors.methods
            t["agreement"] = known and anchors.meets(v)
            row.append(("yes" if t["agreement"] else "no") if known else "–")
        row += ["yes" if t["rectangles"] else "no", "yes" if t["rer"] else "no",
                "**yes**" if all(t.values()) else "no"]
        rows.append(row)
    head = ["variant", "min agreement", "≥ 90 % everywhere (a reading)"]
    if anchors is not None:
        head.append("≥ the authors' code on the anchors (exact and ±1)")
    return markdown_table([*head, "rectangles: 4 endpoints, error ≤ 1 px²",
                           "median RER ≤ 1 %", "all targets"], rows)


def stability_markdown(run: StabilityRun, command: str,
                       anchors: AnchorRun | None = None) -> str:
    """The whole ``docs/stability.md`` report; ``anchors``: the comparison with the
    authors' code (:func:`skelprune.eval_anchors.run_anchors`), if run."""
    n = {d: len({r.shape for r in run.shapes if r.dataset == d}) for d in run.datasets}
    labels = "\n".join(f"- `{v}`: {VARIANTS[v].label}" for v in run.variants)
    parts = [
        "# Stability benchmark (SPEC §5)",
        "",
        f"Generated by `{command}`; do not edit by hand. "
        f"Shapes: {', '.join(f'{d} ({n[d]})' for d in run.datasets)}; "
        f"one noise draw per shape and perturbation (seeded); {run.seeds} noisy "
        f"{RECTANGLE[0]}×{RECTANGLE[1]} rectangles per noise kind. "
        f"Run time {run.seconds / 60:.1f} min.",
        "",
        "Variants:",
        "",
        labels,
        "",
        "## Targets",
        "",
        targets_table(run, anchors),
        "",
        "## Endpoint agreement",
        "",
        "Share of shapes whose number of skeleton endpoints after the perturbation equals "
        "the clean shape's (same variant). The target is at least the authors' code's share on "
        "the same masks (section \"Against the authors' code\" below); 90 % is a reading.",
    ]
    for d in run.datasets:
        parts += ["", f"### {d}", "", agreement_table(run, d)]
    parts += ["", "### Off by at most one or two endpoints (not a target)", "",
              "The same cases read loosely: the share of shapes whose endpoint count after "
              "the perturbation is within ±1 / ±2 of the clean shape's. Reported so that a "
              "missed agreement can be told apart from a different skeleton; the target "
              "above is the exact count."]
    for d in run.datasets:
        parts += ["", f"#### {d}", "", agreement_table(run, d, within=(1, 2))]
    parts += ["", "### Skeleton distance (not a target)", "",
              "How far the skeleton moves, not only its endpoint count: the symmetric mean "
              "distance between the clean shape's skeleton and the perturbed shape's, mapped "
              "back to the clean frame (the perturbation's own transform undone), over the "
              "square root of the clean shape's area; median over the shapes, in % (0.5 on a "
              "100 × 100 shape is half a pixel)."]
    for d in run.datasets:
        parts += ["", f"#### {d}", "", distance_table(run, d)]
    if run.rects:
        parts += ["", "## Noisy rectangles (the paper's Table 2)", "",
                  "Share of rectangles whose skeleton has 4 endpoints / mean eq. 13 error "
                  "(px², mean squared distance of the skeleton pixels to the exact medial "
                  "axis), per noise kind. Target: 4 endpoints, error ≤ 1 px².", "",
                  rectangle_table(run)]
    if anchors is not None:
        from .eval_anchors import anchors_markdown

        parts += ["", anchors_markdown(anchors)]
    parts += ["", "## Clean shapes: reconstruction error and speed", "",
              "Median RER (target ≤ 1 %) and median wall time a shape, measured in the "
              "worker processes of this run (2 running at once), so the ratios between "
              "variants are fair, the absolute values pessimistic.", "", clean_table(run), ""]
    return "\n".join(parts)
