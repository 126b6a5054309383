"""Network rows of ``python -m benchmarks default``: real vessel and crack masks, drawn
networks.

On every mask, skelprune (at the run's options) and skan (``skeletonize`` +
``prune_paths`` of the end branches under 5 and 10 px) are read the same way
(:mod:`benchmarks.default_metrics`): the share of the raw centre line kept (min and
median over the masks; targets ≥ 98 % each, median ≥ 99 %) and the end branches under
10 px a mask (max; target ≤ 5). The drawn networks also count the dead ends found of
the drawing's true ones (:func:`testkit.networks.truth_counts`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .default_metrics import (
    answer_skan,
    answer_skelprune,
    centre_line_kept,
    raw_centre_line,
    short_end_branches,
)
from .default_suite import Context, Group, Job, Row

__all__ = ["GROUPS", "measure_network"]

#: The peers of the network rows: name -> end-branch cut (px).
SKAN = {"skan 5": 5.0, "skan 10": 10.0}
#: Real-networks folders: group -> (subfolder, what it holds).
REAL = {"vessels": ("drive-test", "DRIVE vessels"), "cracks": ("crackforest", "CrackForest")}
#: Drawn networks: (kind, size); quick: the first of each kind at one seed.
DRAWN = (("vessel", 1024), ("crack", 1024), ("road", 1024))
SEEDS = (1, 2, 3)


def measure_network(
    mask: np.ndarray, options: dict[str, Any], truth: Any = None
) -> dict[str, dict[str, float]]:
    """Every method's centre line kept and short end branches on one mask (and, given a
    :class:`testkit.networks.Network`, its dead ends found)."""
    raw = raw_centre_line(mask)
    answers = {"skelprune": answer_skelprune(mask, options)}
    answers.update({name: answer_skan(mask, cut) for name, cut in SKAN.items()})
    out: dict[str, dict[str, float]] = {}
    for name, answer in answers.items():
        got = {"kept": centre_line_kept(raw, answer), "short": short_end_branches(answer)}
        if truth is not None:
            got.update(_dead_ends(truth, answer))
        out[name] = got
    return out


def _dead_ends(truth: Any, answer: np.ndarray) -> dict[str, float]:
    from testkit.networks import truth_counts

    from .default_metrics import _free_ends

    rows, cols = np.nonzero(answer)
    er, ec = np.nonzero(_free_ends(answer))
    counts = truth_counts(truth, rows, cols, er, ec)
    return {"dead_ends": counts["dead_ends"], "dead_ends_found": counts["dead_ends_found"]}


def _real_job(path: str, options: dict[str, Any]) -> dict[str, dict[str, float]]:
    from PIL import Image

    mask = np.asarray(Image.open(path).convert("L")) >= 128
    return measure_network(mask, options)


def _drawn_job(kind: str, size: int, seed: int, options: dict[str, Any]) -> Any:
    from testkit.networks import network

    net = network(kind, size, seed=seed)
    return kind, measure_network(net.mask, options, truth=net)


def _real_files(ctx: Context, group: str) -> list[Path]:
    assert ctx.data is not None
    files = sorted((ctx.data / REAL[group][0]).glob("*.png"))
    return files[::4] if ctx.quick else files


def _real_available(group: str) -> Any:
    def check(ctx: Context) -> str | None:
        if ctx.data is None:
            return "needs --data DIR holding drive-test/ and crackforest/"
        if not (ctx.data / REAL[group][0]).is_dir():
            return f"no {REAL[group][0]}/ in --data"
        return None

    return check


def _real_jobs(group: str) -> Any:
    def jobs(ctx: Context) -> list[Job]:
        return [(_real_job, (str(p), ctx.options)) for p in _real_files(ctx, group)]

    return jobs


def network_rows(dataset: str, results: list[dict[str, dict[str, float]]]) -> list[Row]:
    """The three network rows of one data set (``results``: :func:`measure_network`'s)."""
    methods = list(results[0])

    def kept(m: str) -> np.ndarray:
        return np.array([r[m]["kept"] for r in results])

    def short(m: str) -> int:
        return int(max(r[m]["short"] for r in results))

    def peers(fn: Any) -> str:
        return " · ".join(f"{m} {fn(m)}" for m in methods[1:])

    def pct(x: float) -> str:
        return f"{100 * x:.1f} %"

    ours = kept("skelprune")
    n = f"{dataset} ({len(results)})"
    rows = [
        Row(
            n,
            "centre line kept, min",
            pct(ours.min()),
            peers(lambda m: pct(kept(m).min())),
            "≥ 98 %",
            bool(ours.min() >= 0.98),
            {m: float(kept(m).min()) for m in methods},
        ),
        Row(
            n,
            "centre line kept, median",
            pct(float(np.median(ours))),
            peers(lambda m: pct(float(np.median(kept(m))))),
            "≥ 99 %",
            bool(np.median(ours) >= 0.99),
            {m: float(np.median(kept(m))) for m in methods},
        ),
        Row(
            n,
            "end branches < 10 px a mask, max",
            str(short("skelprune")),
            peers(short),
            "≤ 5",
            short("skelprune") <= 5,
            {m: float(short(m)) for m in methods},
        ),
    ]
    if "dead_ends" in results[0]["skelprune"]:

        def found(m: str) -> str:
            got = sum(int(r[m]["dead_ends_found"]) for r in results)
            return f"{got}/{sum(int(r[m]['dead_ends']) for r in results)}"

        rows.append(
            Row(
                n,
                "dead ends found",
                found("skelprune"),
                peers(found),
                "-",
                None,
                {m: sum(r[m]["dead_ends_found"] for r in results) for m in methods},
            )
        )
    return rows


def _real_rows(group: str) -> Any:
    def rows(ctx: Context, results: list[Any]) -> list[Row]:
        return network_rows(REAL[group][1], results) if results else []

    return rows


def _drawn_jobs(ctx: Context) -> list[Job]:
    seeds = SEEDS[:1] if ctx.quick else SEEDS
    return [(_drawn_job, (k, s, seed, ctx.options)) for k, s in DRAWN for seed in seeds]


def _drawn_rows(ctx: Context, results: list[Any]) -> list[Row]:
    out = []
    for kind, size in DRAWN:
        got = [r for k, r in results if k == kind]
        out += network_rows(f"drawn {kind}s {size}²", got)
    return out


GROUPS = (
    *(Group(g, _real_jobs(g), _real_rows(g), _real_available(g)) for g in ("vessels", "cracks")),
    Group("networks", _drawn_jobs, _drawn_rows),
)
