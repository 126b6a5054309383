"""Skeleton pixels against the hand-checked ground truth of ``data/skelneton-dev``.

A second external reference beside the authors' code: for every shape of the SkelNetOn
training shapes kept in ``data/skelneton-dev`` (shape = grey ≥ 128; ground-truth skeleton
= white pixels of ``skeletons/NAME.png``, same grid), and every variant of
:data:`evaluation.stability.VARIANTS`, the precision, recall and F1 of skeleton pixels
within a tolerance of ``t`` pixels (Euclidean, ``t`` = 0, 1, 2, 3):

* precision: share of our skeleton pixels at distance ``≤ t`` from a ground-truth pixel;
* recall: share of ground-truth pixels at distance ``≤ t`` from one of ours;
* F1: their harmonic mean, per shape; the tables give the mean over shapes.

The ground truth stops end branches short of the boundary and is someone else's choice
of which branches matter, so none of the variants can reach 1; the comparison between
variants (and the baseline) on the same shapes is the point.
"""

from __future__ import annotations

import multiprocessing
from collections.abc import Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .stability import VARIANTS, measure

__all__ = [
    "TOLERANCES",
    "GroundTruthRun",
    "groundtruth_markdown",
    "misses_figure",
    "pixel_scores",
    "run_groundtruth",
]

#: Pixel tolerances of the comparison.
TOLERANCES: tuple[int, ...] = (0, 1, 2, 3)


def pixel_scores(
    ours: np.ndarray, truth: np.ndarray, tolerances: Sequence[int] = TOLERANCES
) -> np.ndarray:
    """``(len(tolerances), 3)`` precision, recall, F1 of two skeleton masks (same grid).

    Examples
    --------
    >>> a = np.zeros((5, 9), bool); a[2, 1:8] = True
    >>> b = np.zeros((5, 9), bool); b[3, 1:8] = True
    >>> pixel_scores(a, b, (0, 1)).tolist()
    [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]]
    """
    from scipy import ndimage

    out = np.zeros((len(tolerances), 3))
    if not ours.any() or not truth.any():
        return out
    to_truth = ndimage.distance_transform_edt(~truth)
    to_ours = ndimage.distance_transform_edt(~ours)
    for k, t in enumerate(tolerances):
        p = float(np.mean(to_truth[ours] <= t))
        r = float(np.mean(to_ours[truth] <= t))
        out[k] = p, r, (2 * p * r / (p + r) if p + r > 0 else 0.0)
    return out


def _load(folder: Path, name: str) -> tuple[np.ndarray, np.ndarray]:
    from PIL import Image

    shape = np.asarray(Image.open(folder / "shapes" / f"{name}.png").convert("L")) >= 128
    gt = np.asarray(Image.open(folder / "skeletons" / f"{name}.png").convert("L")) >= 128
    return shape, gt


def _skeleton(variant: str, mask: np.ndarray) -> np.ndarray:
    r = measure(VARIANTS[variant], mask, with_points=True)
    assert r.points is not None
    sk = np.zeros(mask.shape, bool)
    sk[r.points[:, 0], r.points[:, 1]] = True
    return sk


def _task(args: tuple[Path, str, tuple[str, ...]]) -> tuple[str, dict[str, np.ndarray]]:
    folder, name, variants = args
    mask, gt = _load(folder, name)
    return name, {v: pixel_scores(_skeleton(v, mask), gt) for v in variants}


@dataclass
class GroundTruthRun:
    """Per shape and variant: the ``(len(TOLERANCES), 3)`` precision/recall/F1 array."""

    scores: dict[str, dict[str, np.ndarray]]
    variants: tuple[str, ...]
    folder: Path

    def mean(self, variant: str) -> np.ndarray:
        """Mean over shapes of precision, recall, F1 at each tolerance."""
        return np.mean([s[variant] for s in self.scores.values()], axis=0)

    def worst(self, variant: str, k: int, tolerance: int = 2) -> list[tuple[str, float]]:
        """The ``k`` shapes of lowest F1 at ``tolerance`` px, with that F1."""
        i = TOLERANCES.index(tolerance)
        f1 = sorted((float(s[variant][i, 2]), n) for n, s in self.scores.items())
        return [(n, f) for f, n in f1[:k]]


def run_groundtruth(
    folder: Path,
    variants: Iterable[str] = tuple(VARIANTS),
    workers: int = 2,
    progress: bool = True,
    limit: int | None = None,
) -> GroundTruthRun:
    """Score ``variants`` on every shape of ``folder`` (``shapes/``, ``skeletons/``)."""
    from tqdm import tqdm

    variants = tuple(variants)
    names = sorted(p.stem for p in (Path(folder) / "shapes").glob("*.png"))[:limit]
    jobs = [(Path(folder), n, variants) for n in names]
    scores: dict[str, dict[str, np.ndarray]] = {}
    bar = tqdm(total=len(jobs), unit="shape", desc="ground truth", disable=not progress)
    if workers > 1:
        ctx = multiprocessing.get_context("forkserver")
        with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
            for name, s in pool.map(_task, jobs, chunksize=4):
                scores[name] = s
                bar.update()
    else:
        for job in jobs:
            name, s = _task(job)
            scores[name] = s
            bar.update()
    bar.close()
    return GroundTruthRun(scores, variants, Path(folder))


def misses_figure(run: GroundTruthRun, variant: str, out: Path, k: int = 6) -> list[str]:
    """The ``k`` shapes of lowest F1 at 2 px: ground truth and ``variant`` side by side.

    Colours: shape light grey; pixels of both skeletons within 2 px black; our pixels
    farther than 2 px from the ground truth (precision misses) red; ground-truth pixels
    farther than 2 px from ours (recall misses) blue. Returns the shape names.
    """
    from PIL import Image
    from scipy import ndimage

    worst = run.worst(variant, k)
    tiles = []
    for name, _ in worst:
        mask, gt = _load(run.folder, name)
        ours = _skeleton(variant, mask)
        far_truth = ndimage.distance_transform_edt(~gt) > 2
        far_ours = ndimage.distance_transform_edt(~ours) > 2
        rgb = np.full((*mask.shape, 3), 255, np.uint8)
        rgb[mask] = (215, 215, 215)
        rgb[ours | gt] = (0, 0, 0)
        rgb[ours & far_truth] = (220, 30, 30)
        rgb[gt & far_ours] = (30, 80, 230)
        tiles.append(np.pad(rgb, ((4, 4), (4, 4), (0, 0)), constant_values=255))
    if not tiles:
        return []
    h = max(t.shape[0] for t in tiles)
    row = np.concatenate(
        [np.pad(t, ((0, h - t.shape[0]), (0, 0), (0, 0)), constant_values=255) for t in tiles],
        axis=1,
    )
    out.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(np.kron(row, np.ones((2, 2, 1), np.uint8))).save(out)
    return [n for n, _ in worst]


def groundtruth_markdown(
    run: GroundTruthRun, figure: str | None = None, figure_shapes: Sequence[str] = ()
) -> str:
    """The ground-truth section of the evaluation report."""
    from .tables import markdown_table

    rows = []
    for v in run.variants:
        m = run.mean(v)
        rows.append(
            [
                v,
                *(
                    f"{m[i, 0]:.3f} / {m[i, 1]:.3f} / **{m[i, 2]:.3f}**"
                    for i in range(len(TOLERANCES))
                ),
            ]
        )
    parts = [
        "## Skeleton pixels against the SkelNetOn ground truth",
        "",
        f"The {len(run.scores)} shapes of `data/skelneton-dev` with their hand-checked "
        "skeletons. Per shape: precision (our skeleton pixels within t px of a ground-truth "
        "pixel), recall (ground-truth pixels within t px of ours) and F1; mean over shapes. "
        "The project asks for the default's F1 at 2 px to be at least every alternative's.",
        "",
        markdown_table(
            ["variant (precision / recall / F1)", *(f"t = {t} px" for t in TOLERANCES)], rows
        ),
    ]
    if figure:
        best = run.worst(run.variants[0], len(figure_shapes))
        parts += [
            "",
            f"The {len(figure_shapes)} shapes where `{run.variants[0]}` scores "
            "lowest at 2 px (" + ", ".join(f"{n}: F1 {f:.2f}" for n, f in best) + "). "
            "Black: both skeletons within 2 px; red: our pixels farther than 2 px from "
            "the ground truth; blue: ground-truth pixels farther than 2 px from ours.",
            "",
            f"![ground truth misses]({figure})",
        ]
    return "\n".join(parts)
