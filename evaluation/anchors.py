"""Comparison with the authors' own implementation on the same masks (``data/anchors``).

``data/anchors`` holds 336 masks (24 kimia216 and 24 SkelNetOn shapes, each clean and under
six perturbations made with :mod:`evaluation.perturb`) with the endpoint count and RER of
the authors' MATLAB code on each (see its README). This module runs our variants on
exactly those masks and reads both the same way: per perturbation, the share of shapes
whose endpoint count equals the clean mask's (exact) or is within one of it (±1), and the
median RER. The stability target is relative to these anchors.
"""

from __future__ import annotations

import csv
import math
import multiprocessing
from collections.abc import Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .stability import VARIANTS, measure

__all__ = [
    "ANCHOR",
    "AnchorRecord",
    "AnchorRun",
    "anchor_table",
    "load_anchors",
    "run_anchors",
]

#: The name of the authors' code in the tables.
ANCHOR = "authors"
#: The two batches of ``data/anchors``, in report order.
BATCHES = ("kimia216", "skelneton-dev")


@dataclass(frozen=True)
class AnchorRecord:
    """Endpoints and RER of one method (a variant name or :data:`ANCHOR`) on one mask."""

    batch: str
    shape: str
    perturbation: str
    method: str
    endpoints: int | None  # None: the method failed on this mask
    rer: float | None


def load_anchors(folder: Path) -> list[tuple[str, str, str, Path, int | None, float | None]]:
    """``(batch, shape, perturbation, mask path, authors' endpoints, authors' RER)`` rows."""
    rows = []
    for batch in BATCHES:
        table = Path(folder) / f"authors-matlab-{batch}.csv"
        with table.open(newline="") as f:
            for r in csv.DictReader(f):
                ok = not r["matlab_error"]
                rows.append(
                    (
                        batch,
                        r["shape"],
                        r["perturbation"],
                        Path(folder) / "masks" / batch / r["file"],
                        int(r["matlab_endpoints"]) if ok else None,
                        float(r["matlab_rer"]) if ok else None,
                    )
                )
    return rows


def _task(args: tuple[str, str, str, Path, tuple[str, ...]]) -> list[AnchorRecord]:
    from PIL import Image

    batch, shape, pert, path, variants = args
    mask = np.asarray(Image.open(path)) != 0
    out = []
    for v in variants:
        r = measure(VARIANTS[v], mask)
        out.append(AnchorRecord(batch, shape, pert, v, r.endpoints, r.rer))
    return out


@dataclass
class AnchorRun:
    """Every method's records on the anchor masks."""

    records: list[AnchorRecord]
    methods: tuple[str, ...]
    perturbations: tuple[str, ...]

    def _counts(self, method: str, batches: Sequence[str]) -> dict[tuple[str, str, str], int]:
        return {
            (r.batch, r.shape, r.perturbation): r.endpoints
            for r in self.records
            if r.method == method and r.batch in batches and r.endpoints is not None
        }

    def agreement(
        self, method: str, perturbation: str, within: int = 0, batches: Sequence[str] = BATCHES
    ) -> float:
        """Share of shapes (of ``batches``) whose count is within ``within`` of the clean one.

        A failed run (clean or perturbed) counts as a disagreement.
        """
        counts = self._counts(method, batches)
        shapes = {(r.batch, r.shape) for r in self.records if r.batch in batches}
        got = []
        for b, s in shapes:
            c, p = counts.get((b, s, "clean")), counts.get((b, s, perturbation))
            got.append(c is not None and p is not None and abs(p - c) <= within)
        return float(np.mean(got)) if got else math.nan

    def median_rer(self, method: str, perturbation: str, batches: Sequence[str] = BATCHES) -> float:
        got = [
            r.rer
            for r in self.records
            if r.method == method
            and r.batch in batches
            and r.perturbation == perturbation
            and r.rer is not None
        ]
        return float(np.median(got)) if got else math.nan

    def n_shapes(self, batches: Sequence[str] = BATCHES) -> int:
        return len({(r.batch, r.shape) for r in self.records if r.batch in batches})

    def meets(self, method: str) -> bool:
        """At least the authors' exact and ±1 share under every perturbation (pooled and
        per batch)."""
        groups = [BATCHES, *((b,) for b in BATCHES)]
        return all(
            self.agreement(method, p, k, g) >= self.agreement(ANCHOR, p, k, g)
            for p in self.perturbations
            for k in (0, 1)
            for g in groups
        )


def run_anchors(
    folder: Path,
    variants: Iterable[str] = ("bayesian+dce", "bayesian", "dce"),
    workers: int = 2,
    progress: bool = True,
    limit: int | None = None,
) -> AnchorRun:
    """Run ``variants`` on every anchor mask (a process pool of ``workers``).

    ``limit``: only the first ``limit`` shapes of each batch (quick looks, tests).
    """
    from tqdm import tqdm

    variants = tuple(variants)
    rows = load_anchors(folder)
    if limit is not None:
        keep = {
            (b, s)
            for b in BATCHES
            for s in list(dict.fromkeys(r[1] for r in rows if r[0] == b))[:limit]
        }
        rows = [r for r in rows if (r[0], r[1]) in keep]
    records = [AnchorRecord(b, s, p, ANCHOR, e, rer) for b, s, p, _, e, rer in rows]
    jobs = [(b, s, p, path, variants) for b, s, p, path, _, _ in rows]
    bar = tqdm(total=len(jobs), unit="mask", desc="anchors", disable=not progress)
    if workers > 1:
        ctx = multiprocessing.get_context("forkserver")
        with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
            for recs in pool.map(_task, jobs, chunksize=8):
                records.extend(recs)
                bar.update()
    else:
        for job in jobs:
            records.extend(_task(job))
            bar.update()
    bar.close()
    perts = tuple(dict.fromkeys(p for _, _, p, _, _, _ in rows if p != "clean"))
    return AnchorRun(records, (ANCHOR, *variants), perts)


def anchor_table(run: AnchorRun, batches: Sequence[str] = BATCHES) -> str:
    """Per perturbation (rows): exact / ±1 agreement and median RER of every method."""
    from .tables import markdown_table, pct

    def cell(m: str, p: str) -> str:
        return (
            f"{pct(run.agreement(m, p, 0, batches))} / {pct(run.agreement(m, p, 1, batches))}"
            f" · {100 * run.median_rer(m, p, batches):.2f} %"
        )

    rows = [
        ["clean", *(f"· {100 * run.median_rer(m, 'clean', batches):.2f} %" for m in run.methods)]
    ]
    rows += [[p, *(cell(m, p) for m in run.methods)] for p in run.perturbations]
    return markdown_table(["perturbation (exact / ±1 · median RER)", *run.methods], rows)


def anchors_markdown(run: AnchorRun) -> str:
    """The anchors section of the stability report."""
    labels = ", ".join(f"`{m}`" for m in run.methods[1:])
    parts = [
        "## Against the authors' code, on the same masks (`data/anchors`)",
        "",
        f"The authors' MATLAB implementation (`{ANCHOR}`, `DSE(bw, 50, 9.0, 0.01)` under "
        f"GNU Octave; counts and RER from `data/anchors`) beside {labels}, run here on "
        "the same saved masks. Exact / ±1: share of shapes whose endpoint count under the "
        "perturbation equals / is within one of the same method's count on the clean "
        "mask; then the median RER. Target: exact and ±1 at least the authors' "
        "under every perturbation.",
        "",
        "| method | meets the target (pooled and per batch) |",
        "|---|---|",
        *(f"| {m} | {'yes' if run.meets(m) else 'no'} |" for m in run.methods[1:]),
    ]
    for title, b in (("both batches", BATCHES), *((x, (x,)) for x in BATCHES)):
        parts += ["", f"### {title} ({run.n_shapes(b)} shapes)", "", anchor_table(run, b)]
    return "\n".join(parts)
