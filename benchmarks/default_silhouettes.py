"""Silhouette and stability rows of ``python -m benchmarks default``.

- **ground truth**: mean F1 of skeleton pixels at 2 px on ``data/skelneton-dev``
  (:func:`evaluation.groundtruth.pixel_scores`), beside skan cut at 5 and 10 px;
- **RER**: the median area-weighted reconstruction error on kimia216 and kimia99,
  beside ``skeletonize`` cut at 5 and 10 px (:mod:`evaluation.baseline`);
- **limbs kept** and **round ends centred**: :mod:`benchmarks.bench_limbs`' measures on
  the blobs of :mod:`testkit.limbs` and the round-ended shapes;
- **stability** on ``data/anchors`` against the authors' code on the same masks: the
  share of shapes whose endpoint count under each of the six perturbations equals the
  clean mask's (exact) or is within one (±1), on two fixed halves of the 48 shapes
  (A: every other shape of each batch, by name, from the first; B: the rest), so that a
  default chosen on half A is read on half B.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from testkit import DATA

from .default_suite import Context, Group, Job, Row

__all__ = ["GROUPS", "anchor_halves"]

CHUNK = 24  # masks a job
LIMB_SHAPES = 300


def _chunks(items: Sequence[Any], size: int = CHUNK) -> list[list[Any]]:
    return [list(items[i : i + size]) for i in range(0, len(items), size)]


def _pct(x: float) -> str:
    return f"{100 * x:.1f} %"


# --- jobs (run in the workers) ------------------------------------------------------


def _groundtruth_job(names: list[str], options: dict[str, Any]) -> tuple[str, Any]:
    from evaluation.groundtruth import TOLERANCES, _load, pixel_scores

    from .default_metrics import answer_skan, answer_skelprune

    i = TOLERANCES.index(2)
    folder = DATA / "skelneton-dev"
    out = []
    for name in names:
        mask, gt = _load(folder, name)
        answers = {"skelprune": answer_skelprune(mask, options)}
        answers.update({f"skan {c:g}": answer_skan(mask, c) for c in (5.0, 10.0)})
        out.append({m: float(pixel_scores(a, gt)[i, 2]) for m, a in answers.items()})
    return "gt", out


def _rer_job(paths: list[str], options: dict[str, Any]) -> tuple[str, Any]:
    from PIL import Image

    import skelprune
    from evaluation.baseline import skeletonize_cut
    from skelprune.grid.reconstruction import reconstruction_error

    out = []
    for path in paths:
        mask = np.asarray(Image.open(path)) != 0
        res = skelprune.prune(mask, **options)
        area = sum(c.area for c in res.components)
        got = {"skelprune": sum(c.rer * c.area for c in res.components) / area}
        for cut in (5.0, 10.0):
            sk = skeletonize_cut(mask, cut)
            got[f"cut {cut:g}"] = float(reconstruction_error(mask, sk.rows, sk.cols, sk.r2))
        out.append(got)
    return "rer", out


def _limbs_job(first: int, count: int, options: dict[str, Any]) -> tuple[str, Any]:
    from testkit.limbs import BODIES, limb_shape

    from .bench_limbs import _limbs

    shapes = [limb_shape(i, BODIES[i % len(BODIES)]) for i in range(first, first + count)]
    return "limbs", [bool(k) for k in _limbs(shapes, options)["kept"]]


def _round_ends_job(options: dict[str, Any]) -> tuple[str, Any]:
    from .bench_limbs import _round_ends

    return "ends", _round_ends(options)


def _anchor_job(rows: list[tuple[str, str, str, str]], options: dict[str, Any]) -> list[Any]:
    from PIL import Image

    import skelprune

    out = []
    for batch, shape, pert, path in rows:
        mask = np.asarray(Image.open(path)) != 0
        res = skelprune.prune(mask, **options)
        area = sum(c.area for c in res.components)
        rer = sum(c.rer * c.area for c in res.components) / area
        out.append((batch, shape, pert, res.n_endpoints(), rer))
    return out


# --- silhouettes --------------------------------------------------------------------


def _every(items: list[Any], quick: bool) -> list[Any]:
    return items[::4] if quick else items


def _silhouette_jobs(ctx: Context) -> list[Job]:
    names = _every(sorted(p.stem for p in (DATA / "skelneton-dev/shapes").glob("*.png")), ctx.quick)
    paths = sorted(str(p) for d in ("kimia216", "kimia99") for p in (DATA / d).glob("*.png"))
    paths = _every(paths, ctx.quick)
    n_limbs = LIMB_SHAPES // 5 if ctx.quick else LIMB_SHAPES
    jobs: list[Job] = [(_groundtruth_job, (c, ctx.options)) for c in _chunks(names)]
    jobs += [(_rer_job, (c, ctx.options)) for c in _chunks(paths)]
    jobs += [(_limbs_job, (i, min(30, n_limbs - i), ctx.options)) for i in range(0, n_limbs, 30)]
    jobs.append((_round_ends_job, (ctx.options,)))
    return jobs


def _silhouette_rows(ctx: Context, results: list[Any]) -> list[Row]:
    got: dict[str, list[Any]] = {"gt": [], "rer": [], "limbs": [], "ends": []}
    for kind, part in results:
        got[kind] += part if kind != "ends" else [part]
    gt, rer, limbs, ends = got["gt"], got["rer"], got["limbs"], got["ends"][0]

    def mean(rs: list[dict[str, float]], m: str) -> float:
        return float(np.mean([r[m] for r in rs]))

    def median(rs: list[dict[str, float]], m: str) -> float:
        return float(np.median([r[m] for r in rs]))

    f1 = {m: mean(gt, m) for m in gt[0]}
    rers = {m: median(rer, m) for m in rer[0]}
    kept = float(np.mean(limbs))
    return [
        Row(
            f"SkelNetOn dev ({len(gt)})",
            "F1 at 2 px vs ground truth, mean",
            f"{f1['skelprune']:.3f}",
            " · ".join(f"{m} {v:.3f}" for m, v in f1.items() if m != "skelprune"),
            "≥ 0.95",
            f1["skelprune"] >= 0.95,
            f1,
        ),
        Row(
            f"kimia216 + kimia99 ({len(rer)})",
            "RER, median",
            f"{100 * rers['skelprune']:.2f} %",
            " · ".join(
                f"skeletonize {m} {100 * v:.2f} %" for m, v in rers.items() if m != "skelprune"
            ),
            "≤ 1 %",
            rers["skelprune"] <= 0.01,
            rers,
        ),
        Row(
            f"blobs with limbs ({len(limbs)} limbs)",
            "limbs kept",
            _pct(kept),
            "-",
            "≥ 99 %",
            kept >= 0.99,
            {"skelprune": kept},
        ),
        Row(
            "round ends (lollipops, dumbbells, stick figures)",
            "ends at the disc's centre",
            f"{ends[0]}/{ends[1]}",
            "-",
            "all",
            bool(ends[0] == ends[1]),
            {"skelprune": ends[0] / max(ends[1], 1)},
        ),
    ]


# --- stability ----------------------------------------------------------------------


def anchor_halves(shapes_by_batch: dict[str, list[str]]) -> dict[tuple[str, str], str]:
    """``(batch, shape) -> "A" | "B"``: every other shape of each batch by name, from the
    first, is in half A.

    >>> anchor_halves({"k": ["b", "a", "c"]})
    {('k', 'a'): 'A', ('k', 'b'): 'B', ('k', 'c'): 'A'}
    """
    return {
        (batch, s): "AB"[i % 2]
        for batch, shapes in shapes_by_batch.items()
        for i, s in enumerate(sorted(shapes))
    }


def _anchor_rows_in(ctx: Context) -> list[tuple[str, str, str, Path, int | None, float | None]]:
    from evaluation.anchors import BATCHES, load_anchors

    rows = load_anchors(DATA / "anchors")
    if ctx.quick:  # the first 8 shapes (by name) of each batch: 4 in each half
        keep = {(b, s) for b in BATCHES for s in sorted({r[1] for r in rows if r[0] == b})[:8]}
        rows = [r for r in rows if (r[0], r[1]) in keep]
    return rows


def _stability_jobs(ctx: Context) -> list[Job]:
    rows = [(b, s, p, str(path)) for b, s, p, path, _, _ in _anchor_rows_in(ctx)]
    return [(_anchor_job, (c, ctx.options)) for c in _chunks(rows, 12)]


def agreement(
    counts: dict[tuple[str, str, str], int | None],
    shapes: Sequence[tuple[str, str]],
    perturbation: str,
    within: int,
) -> float:
    """Share of ``shapes`` whose endpoint count under ``perturbation`` is within ``within``
    of the clean one's (a failed run disagrees)."""
    got = []
    for b, s in shapes:
        c, p = counts.get((b, s, "clean")), counts.get((b, s, perturbation))
        got.append(c is not None and p is not None and abs(p - c) <= within)
    return float(np.mean(got)) if got else float("nan")


def _stability_rows(ctx: Context, results: list[Any]) -> list[Row]:
    rows = _anchor_rows_in(ctx)
    authors = {(b, s, p): e for b, s, p, _, e, _ in rows}
    ours = {(b, s, p): e for chunk in results for b, s, p, e, _ in chunk}
    our_rer = {(b, s, p): r for chunk in results for b, s, p, _, r in chunk}
    perts = list(dict.fromkeys(p for _, _, p, _, _, _ in rows if p != "clean"))
    shapes: dict[str, list[str]] = {}
    for b, s, *_ in rows:
        shapes.setdefault(b, [])
        if s not in shapes[b]:
            shapes[b].append(s)
    half = anchor_halves(shapes)
    out = []
    for h in "AB":
        members = sorted(k for k, v in half.items() if v == h)
        for p in [*perts, "pooled"]:
            ps = perts if p == "pooled" else [p]
            got = {
                who: [float(np.mean([agreement(c, members, q, k) for q in ps])) for k in (0, 1)]
                for who, c in (("skelprune", ours), ("authors", authors))
            }
            ok = all(got["skelprune"][k] >= got["authors"][k] for k in (0, 1))
            out.append(
                Row(
                    f"anchors half {h} ({len(members)} shapes)",
                    f"endpoints as clean, {p}: exact / ±1",
                    " / ".join(_pct(x) for x in got["skelprune"]),
                    "authors " + " / ".join(_pct(x) for x in got["authors"]),
                    "≥ the authors'",
                    ok,
                    {
                        "skelprune exact": got["skelprune"][0],
                        "skelprune ±1": got["skelprune"][1],
                        "authors exact": got["authors"][0],
                        "authors ±1": got["authors"][1],
                    },
                )
            )
    clean = [k for k in authors if k[2] == "clean"]
    a_rer = float(np.median([r[5] for r in rows if r[2] == "clean" and r[5] is not None]))
    o_rer = float(np.median([our_rer[k] for k in clean if k in our_rer]))
    out.append(
        Row(
            f"anchors, clean masks ({len(clean)})",
            "RER, median",
            f"{100 * o_rer:.2f} %",
            f"authors {100 * a_rer:.2f} %",
            "≤ 1 %",
            o_rer <= 0.01,
            {"skelprune": o_rer, "authors": a_rer},
        )
    )
    return out


GROUPS = (
    Group("silhouettes", _silhouette_jobs, _silhouette_rows),
    Group("stability", _stability_jobs, _stability_rows),
)
