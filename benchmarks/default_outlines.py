"""Rough-outline rows of ``python -m benchmarks default``: pixel flips and resampled noise.

The anchor masks hold the authors' answers under six perturbations; the two noise models
they lack (:data:`evaluation.perturb.PERTURBATIONS`' ``flips-0.5``: every boundary pixel
flipped with probability 0.5, and ``resampled-1``: the contour resampled with noise of
σ 1) are read here on kimia216 and kimia99, against skan cut at 5 and 10 px: the share of
shapes whose endpoint count on the rough copy equals the clean shape's (exact) or is
within one (±1). Each method's endpoints as it reports them: skelprune's
``n_endpoints()``, the free ends of skan's pruned ``skeletonize`` image.
"""

from __future__ import annotations

import zlib
from typing import Any

import numpy as np

from testkit import DATA

from .default_suite import Context, Group, Job, Row

__all__ = ["GROUPS", "free_end_count"]

PERTURBATIONS = ("flips-0.5", "resampled-1")
CHUNK = 24


def free_end_count(answer: np.ndarray) -> int:
    """Free ends of a one-pixel-wide answer (pixels with one 8-neighbour).

    >>> m = np.zeros((9, 20), bool); m[4, 2:18] = True; m[5:8, 9] = True
    >>> free_end_count(m)
    3
    """
    from .default_metrics import _free_ends

    return int(_free_ends(answer).sum())


def _outline_job(paths: list[str], options: dict[str, Any]) -> list[dict[str, list[int]]]:
    from PIL import Image

    import skelprune
    from evaluation.perturb import PERTURBATIONS as ALL

    from .default_metrics import answer_skan

    def counts(mask: np.ndarray) -> dict[str, int]:
        got = {"skelprune": skelprune.prune(mask, **options).n_endpoints()}
        for cut in (5.0, 10.0):
            got[f"skan {cut:g}"] = free_end_count(answer_skan(mask, cut))
        return got

    out = []
    for path in paths:
        mask = np.asarray(Image.open(path)) != 0
        clean = counts(mask)
        shape: dict[str, list[int]] = {m: [n] for m, n in clean.items()}
        for name in PERTURBATIONS:
            rng = np.random.default_rng([7, zlib.crc32(f"{path}:{name}".encode())])
            for m, n in counts(ALL[name].apply(mask, rng)).items():
                shape[m].append(n)
        out.append(shape)
    return out


def _paths(ctx: Context) -> list[str]:
    paths = sorted(str(p) for d in ("kimia216", "kimia99") for p in (DATA / d).glob("*.png"))
    return paths[::4] if ctx.quick else paths


def _outline_jobs(ctx: Context) -> list[Job]:
    paths = _paths(ctx)
    return [
        (_outline_job, (paths[i : i + CHUNK], ctx.options)) for i in range(0, len(paths), CHUNK)
    ]


def _outline_rows(ctx: Context, results: list[Any]) -> list[Row]:
    shapes = [s for chunk in results for s in chunk]
    methods = list(shapes[0])
    rows = []
    for k, name in enumerate(PERTURBATIONS, start=1):
        got = {
            m: [float(np.mean([abs(s[m][k] - s[m][0]) <= w for s in shapes])) for w in (0, 1)]
            for m in methods
        }
        best = [max(got[m][w] for m in methods[1:]) for w in (0, 1)]
        rows.append(
            Row(
                f"kimia216 + kimia99 ({len(shapes)})",
                f"endpoints as clean, {name}: exact / ±1",
                " / ".join(f"{100 * x:.1f} %" for x in got["skelprune"]),
                " · ".join(
                    f"{m} " + " / ".join(f"{100 * x:.1f} %" for x in got[m]) for m in methods[1:]
                ),
                "≥ best peer",
                all(got["skelprune"][w] >= best[w] for w in (0, 1)),
                {f"{m} {('exact', '±1')[w]}": got[m][w] for m in methods for w in (0, 1)},
            )
        )
    return rows


GROUPS = (Group("outlines", _outline_jobs, _outline_rows),)
