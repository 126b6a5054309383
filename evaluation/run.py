"""``python -m evaluation``: the paper's evaluation, regenerated from the data.

Writes ``evaluation.md``, ``stability.md`` and ``figures/*.png`` into one folder:

1. Table 1: RER and SS (mean, standard deviation) on kimia216 and kimia99, for the
   Bayesian method, DCE pruning ([10]) and the ``skeletonize`` + cut baseline.
2. Table 2: the noisy rectangles (eq. 13 error, share with 4 endpoints).
3. Stability (Figs. 6–7): endpoint agreement under noise, rotation and scaling.
4. Fig. 3: AR, LR and λ over the pruning steps.
5. Fig. 11: every kimia216 skeleton.
6. Speed: ms a shape per method and the ratio to bare ``skeletonize`` + EDT.
7. The baseline users would otherwise pick, in the same tables.
8. Skeleton pixels against the SkelNetOn ground truth (precision, recall, F1 at 0-3 px)
   and a figure of the largest misses, when ``data/skelneton-dev`` is there.
9. Table 3: retrieval by path similarity matching (``retrieval.md``,
   :mod:`evaluation.retrieval`).

Numbers 1–3 come from one :func:`evaluation.stability.run_stability` run (the same
computation as ``benchmarks/bench_stability.py``). matplotlib is needed only here.
"""

from __future__ import annotations

import os
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .perturb import PERTURBATIONS, noisy_rectangle
from .report import (
    agreement_table,
    clean_table,
    markdown_table,
    pct,
    stability_markdown,
    targets_table,
)
from .stability import (
    NOISE_KINDS,
    RECTANGLE,
    VARIANTS,
    StabilityRun,
    load_dataset,
    measure,
    run_stability,
)

if TYPE_CHECKING:
    from .anchors import AnchorRun

__all__ = ["DATASETS", "default_data_dir", "run_evaluation"]

DATASETS = ("kimia216", "kimia99")
#: Shapes of the per-shape figures (the first of each is used when a name is missing).
FIGURE_SHAPES = ("bird-2", "camel-12", "elephant-1", "fork-1")
STABILITY_SHAPES = ("bone-1", "hammer-1", "children-1")
#: Variants of Table 1, 2 and the speed table, in order (the default first).
TABLE_VARIANTS = tuple(VARIANTS)


def default_data_dir() -> Path:
    """``$SKELPRUNE_DATA``, else the repository's own ``data/`` folder."""
    env = os.environ.get("SKELPRUNE_DATA")
    return Path(env) if env else Path(__file__).resolve().parents[1] / "data"


@dataclass(frozen=True)
class SpeedRow:
    """Median ms a shape of one method on one dataset, and its ratio to the reference."""

    method: str
    ms: float
    ratio: float


def _bare(mask: np.ndarray) -> float:
    from scipy import ndimage
    from skimage.morphology import skeletonize

    t = time.perf_counter()
    skeletonize(mask)
    ndimage.distance_transform_edt(mask)
    return 1000 * (time.perf_counter() - t)


def speed(
    shapes: Sequence[tuple[str, np.ndarray]], repeat: int = 3, progress: bool = True
) -> list[SpeedRow]:
    """One core, this process: min over ``repeat`` runs a shape, median over shapes.

    The reference, bare ``skeletonize`` + ``distance_transform_edt``, is timed on the same
    shapes in the same loop, so that machine load affects both alike.
    """
    from tqdm import tqdm

    for v in TABLE_VARIANTS:  # numba caches loaded before anything is timed
        measure(VARIANTS[v], shapes[0][1])
    times: dict[str, list[float]] = {v: [] for v in ("bare", *TABLE_VARIANTS)}
    for _name, m in tqdm(shapes, desc="speed", unit="shape", disable=not progress):
        times["bare"].append(min(_bare(m) for _ in range(repeat)))
        for v in TABLE_VARIANTS:
            times[v].append(min(measure(VARIANTS[v], m).ms for _ in range(repeat)))
    ref = float(np.median(times["bare"]))
    rows = [SpeedRow("skeletonize + EDT (reference)", ref, 1.0)]
    rows += [
        SpeedRow(v, float(np.median(times[v])), float(np.median(times[v])) / ref)
        for v in TABLE_VARIANTS
    ]
    return rows


def table1(run: StabilityRun) -> str:
    """The paper's Table 1: RER and SS, mean and standard deviation, per dataset."""
    header = ["method"]
    for d in run.datasets:
        header += [f"{d} RER mean", "std", f"{d} SS mean", "std"]
    rows = []
    for v in run.variants:
        row: list[object] = [v]
        for d in run.datasets:
            recs = run.clean(d, v)
            rer = np.array([r.rer for r in recs])
            ss = np.array([r.ss for r in recs if r.ss is not None])
            row += [
                f"{100 * rer.mean():.2f} %",
                f"{100 * rer.std():.2f} %",
                f"{ss.mean():.3f}",
                f"{ss.std():.3f}",
            ]
        rows.append(row)
    return markdown_table(header, rows)


def table2(run: StabilityRun) -> str:
    """The paper's Table 2: mean eq. 13 error per noise kind, and the average of the five."""
    noisy = [n for n, _, _ in NOISE_KINDS if n in run.rect_noises()]
    rows = []
    for n in run.rect_noises():
        rows.append(
            [
                n,
                *(
                    f"{run.rect_error(n, v):.2f} ({pct(run.rect_share4(n, v))})"
                    for v in run.variants
                ),
            ]
        )
    rows.append(
        [
            "**average of the noisy kinds**",
            *(
                f"{np.mean([run.rect_error(n, v) for n in noisy]):.2f}"
                f" ({pct(float(np.mean([run.rect_share4(n, v) for n in noisy])))})"
                for v in run.variants
            ),
        ]
    )
    return markdown_table(["noise: error px² (share with 4 endpoints)", *run.variants], rows)


def speed_table(rows: Sequence[SpeedRow], n: int) -> str:
    return markdown_table(
        ["method", f"median ms a shape (kimia216, {n} shapes)", "× skeletonize + EDT"],
        [[r.method, f"{r.ms:.2f}", f"{r.ratio:.1f}"] for r in rows],
    )


def _pick(
    shapes: Sequence[tuple[str, np.ndarray]], names: Sequence[str], k: int
) -> list[tuple[str, np.ndarray]]:
    by = dict(shapes)
    chosen = [(n, by[n]) for n in names if n in by]
    for item in shapes:  # fill up from the start when a named shape is not in the subset
        if len(chosen) >= k:
            break
        if all(item[0] != c[0] for c in chosen):
            chosen.append(item)
    return chosen[:k]


def figures(
    sets: dict[str, list[tuple[str, np.ndarray]]],
    out: Path,
    seed: int,
    progress: bool = True,
    small: bool = False,
) -> dict[str, str]:
    """Write every figure under ``out/figures``; returns {key: relative path}.

    ``small`` (with ``--limit``): fewer rows in the per-shape figures, for quick runs.
    """
    from tqdm import tqdm

    from . import figures as ef
    from .stability import _rng

    fig_dir = out / "figures"
    fig_dir.mkdir(parents=True, exist_ok=True)
    k216 = sets[DATASETS[0]]
    paths: dict[str, str] = {}
    steps = ["curves", "stability", "methods", "rectangles", "montage"]
    bar = tqdm(steps, desc="figures", unit="figure", disable=not progress)
    for step in bar:
        if step == "curves":
            ef.curves_figure(_pick(k216, FIGURE_SHAPES, 4), fig_dir / "fig3_curves.png")
            paths[step] = "figures/fig3_curves.png"
        elif step == "stability":
            names = [n for n, _ in k216]
            shapes = _pick(k216, STABILITY_SHAPES, 1 if small else 3)
            perturbed = [
                [
                    (p.name, p.apply(m, _rng(seed, names.index(n), p.name)))
                    for p in PERTURBATIONS.values()
                ]
                for n, m in shapes
            ]
            ef.perturbation_figure(
                shapes, perturbed, VARIANTS["bayesian+dce"], fig_dir / "fig6_7_stability.png"
            )
            paths[step] = "figures/fig6_7_stability.png"
        elif step == "methods":
            ef.methods_figure(
                _pick(k216, FIGURE_SHAPES, 4), TABLE_VARIANTS, fig_dir / "methods.png"
            )
            paths[step] = "figures/methods.png"
        elif step == "rectangles":
            rects = [("none", noisy_rectangle(*RECTANGLE, "uniform", 0.0)[0])]
            rects += [
                (
                    n,
                    noisy_rectangle(
                        *RECTANGLE,
                        kind,
                        scale,  # type: ignore[arg-type]
                        _rng(seed, 0, n),
                    )[0],
                )
                for n, kind, scale in NOISE_KINDS[: 1 if small else None]
            ]
            ef.rectangles_figure(rects, TABLE_VARIANTS, fig_dir / "fig9_rectangles.png")
            paths[step] = "figures/fig9_rectangles.png"
        else:
            ef.montage_figure(k216, fig_dir / "fig11_kimia216.png")
            paths[step] = "figures/fig11_kimia216.png"
    return paths


def _markdown(
    run: StabilityRun,
    spd: list[SpeedRow],
    n_speed: int,
    figs: dict[str, str],
    command: str,
    groundtruth: str | None = None,
    anchors: AnchorRun | None = None,
) -> str:
    counts = ", ".join(
        f"{d} ({len({r.shape for r in run.shapes if r.dataset == d})} shapes)" for d in run.datasets
    )
    labels = "\n".join(f"- `{v}`: {VARIANTS[v].label}" for v in run.variants)
    return "\n".join(
        [
            "# Evaluation (the paper's Section 7)",
            "",
            f"Generated by `{command}` from `data/`; do not edit by hand. Datasets: "
            f"{counts}. Stability run: {run.seconds / 60:.1f} min on 2 worker processes.",
            "",
            "Methods (columns of every table):",
            "",
            labels,
            "",
            "`skeletonize + cut` is what users would otherwise pick (the skan / PlantCV way): "
            "`skimage.morphology.skeletonize`, then end branches shorter than L pixels are "
            "removed, shortest first, until none is left; radii are the Euclidean distance "
            "transform at the skeleton pixels, so RER is measured exactly as for the others. "
            "SS of every method uses the same length unit per shape (ℓ̄ of the shape's "
            "medial axis, docs/algorithm.md, Length term).",
            "",
            "## Table 1: reconstruction error ratio and skeleton simplicity",
            "",
            "RER = AR(Ŝ), SS = LR(Ŝ) = log(Γ(Ŝ) + 1) on the clean shapes (the paper's Table 1; "
            "it reports RER < 1 % for its method). Lower is better for both; they trade off.",
            "",
            table1(run),
            "",
            "## Table 2: noisy rectangles",
            "",
            f"A {RECTANGLE[0]}×{RECTANGLE[1]} rectangle with boundary noise (the paper's Fig. 9 "
            f"and Table 2), {run.seeds} draws per noise kind plus the clean one. Mean eq. 13 "
            "error in px² (mean squared distance of the skeleton pixels to the exact medial "
            "axis) and, in brackets, the share of rectangles whose skeleton has 4 endpoints.",
            "",
            table2(run),
            "",
            f"![rectangles]({figs['rectangles']})",
            "",
            "## Stability under noise, rotation and scaling (Figs. 6–7)",
            "",
            "Share of shapes whose number of endpoints after the perturbation equals the clean "
            "shape's, same method. The target: at least the authors' code's share on the "
            "same masks (`data/anchors`, compared in [stability.md](stability.md)); 90 % is kept "
            "as a reading.",
            "",
            targets_table(run, anchors),
            "",
            *(line for d in run.datasets for line in (f"### {d}", "", agreement_table(run, d), "")),
            "Default method (`bayesian+dce`) on a few shapes under every perturbation; the row "
            "label lists the endpoint counts (clean first):",
            "",
            f"![stability]({figs['stability']})",
            "",
            "Every method on the same shapes:",
            "",
            f"![methods]({figs['methods']})",
            "",
            *([groundtruth, ""] if groundtruth else []),
            "## Table 3: retrieval",
            "",
            "Shape retrieval by path similarity skeleton matching on kimia216 (top 11) and "
            "kimia99 (top 10), every method, and with perturbed queries: "
            "[retrieval.md](retrieval.md).",
            "",
            "## Fig. 3: the pruning curve",
            "",
            "α·AR, LR and λ over the removal steps of the default method; the chosen skeleton "
            "(argmin λ, ties to the later step) is marked.",
            "",
            f"![curves]({figs['curves']})",
            "",
            "## Speed",
            "",
            "One core, this process, min of 3 runs a shape, median over shapes; the reference is "
            "bare `skeletonize` + `distance_transform_edt` timed in the same loop.",
            "",
            speed_table(spd, n_speed),
            "",
            "Clean shapes, timed in the stability run's workers (2 at once):",
            "",
            clean_table(run),
            "",
            "## Fig. 11: every kimia216 skeleton",
            "",
            "Default method; reconstruction error in red, RER in brackets.",
            "",
            f"![kimia216]({figs['montage']})",
            "",
        ]
    )


def run_evaluation(
    out: Path,
    data: Path | None = None,
    limit: int | None = None,
    workers: int = 2,
    rect_seeds: int = 10,
    seed: int = 7,
    progress: bool = True,
) -> dict[str, Path]:
    """Compute the whole evaluation and write its reports and figures into ``out``.

    Parameters
    ----------
    out : Path
        Output folder (``docs`` in the repository); created if missing.
    data : Path, optional
        Folder holding ``kimia216/`` and ``kimia99/``; default :func:`default_data_dir`.
    limit : int, optional
        Only the first ``limit`` shapes of each dataset (tests, quick looks).
    workers : int
        Processes of the stability run.
    rect_seeds : int
        Noisy rectangles per noise kind.
    seed : int
        Base seed of every noise draw.
    progress : bool
        tqdm progress bars on stderr.

    Returns
    -------
    dict
        ``{"evaluation": path, "stability": path, "margin": path, "retrieval": path,
        <figure key>: path, ...}``.
    """
    data = default_data_dir() if data is None else Path(data)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    sets = {d: load_dataset(data / d, limit) for d in DATASETS}
    missing = [d for d, items in sets.items() if not items]
    if missing:
        raise FileNotFoundError(f"no PNG masks in {', '.join(str(data / d) for d in missing)}")
    run = run_stability(
        sets, TABLE_VARIANTS, rect_seeds=rect_seeds, seed=seed, workers=workers, progress=progress
    )
    anchors = None
    if (data / "anchors").is_dir():
        from .anchors import run_anchors

        anchors = run_anchors(data / "anchors", workers=workers, progress=progress, limit=limit)
    spd = speed(sets[DATASETS[0]], progress=progress)
    figs = figures(sets, out, seed, progress=progress, small=limit is not None)
    command = "python -m evaluation --out docs" + ("" if limit is None else f" --limit {limit}")
    groundtruth = None
    if (data / "skelneton-dev" / "skeletons").is_dir():
        from .groundtruth import groundtruth_markdown, misses_figure, run_groundtruth

        gt = run_groundtruth(
            data / "skelneton-dev", TABLE_VARIANTS, workers=workers, progress=progress, limit=limit
        )
        names = misses_figure(
            gt,
            TABLE_VARIANTS[0],
            out / "figures" / "groundtruth_misses.png",
            k=2 if limit is not None else 6,
        )
        figs["groundtruth"] = "figures/groundtruth_misses.png"
        groundtruth = groundtruth_markdown(gt, figs["groundtruth"], names)
    (out / "evaluation.md").write_text(
        _markdown(run, spd, len(sets[DATASETS[0]]), figs, command, groundtruth, anchors)
    )
    (out / "stability.md").write_text(stability_markdown(run, command, anchors))
    from .margin import margin_markdown, run_margins

    margins = run_margins(sets, seed=seed, workers=workers, progress=progress)
    (out / "margin.md").write_text(margin_markdown(margins, command))
    from .retrieval import retrieval_markdown, run_retrieval

    retrieval = run_retrieval(sets, workers=workers, seed=seed)
    (out / "retrieval.md").write_text(retrieval_markdown(retrieval, command))
    written = {
        "evaluation": out / "evaluation.md",
        "stability": out / "stability.md",
        "margin": out / "margin.md",
        "retrieval": out / "retrieval.md",
    }
    written.update({k: out / v for k, v in figs.items()})
    return written
