"""Stability measurements shared by ``benchmarks/bench_stability.py`` and ``python -m evaluation``.

One module computes, both report:

* **Endpoint agreement** (the paper's Figs. 6–7): for every shape of a dataset and
  every perturbation of :data:`evaluation.perturb.PERTURBATIONS`, is the number
  of skeleton endpoints of the perturbed shape the clean shape's (same method)?
* **Noisy rectangles** (the paper's Table 2 and Fig. 9): share of rectangles with 4
  endpoints, and the eq. 13 error of the skeleton against the exact medial axis.
* On the clean shapes: RER, SS and milliseconds a shape of every variant.

Work is spread over a process pool, one task per shape (each task runs every perturbation
and every variant of its shape), so both cores stay busy and the numbers do not depend on
scheduling: every noise draw is seeded from (seed, shape index, perturbation name).
"""

from __future__ import annotations

import math
import multiprocessing
import time
import zlib
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .perturb import (
    PERTURBATIONS,
    Perturbation,
    noisy_rectangle,
    skeleton_distance,
    skeleton_error,
)

__all__ = [
    "CUT_LENGTHS",
    "NOISE_KINDS",
    "VARIANTS",
    "Measurement",
    "RectRecord",
    "ShapeRecord",
    "StabilityRun",
    "Variant",
    "load_dataset",
    "measure",
    "run_stability",
]

#: Branch-length thresholds (pixels) of the ``skeletonize`` + cut baseline.
CUT_LENGTHS: tuple[float, ...] = (5.0, 15.0, 30.0)

#: The noise of the paper's Table 2 / Fig. 9 (b)–(f): (name, kind, scale).
NOISE_KINDS: tuple[tuple[str, str, float], ...] = (
    ("gaussian-1", "gaussian", 1.0),
    ("gaussian-1.5", "gaussian", 1.5),
    ("uniform-1", "uniform", 1.0),
    ("uniform-1.2", "uniform", 1.2),
    ("uniform-1.5", "uniform", 1.5),
)

#: Rectangle of the noisy-rectangle experiment, (height, width), like the paper's Fig. 9.
RECTANGLE = (60, 160)


@dataclass(frozen=True)
class Variant:
    """One skeleton method under evaluation.

    ``kind`` is ``"prune"`` (``options`` go to :func:`skelprune.prune`) or ``"cut"``
    (``skeletonize`` + branch-length cut at ``options["min_length"]`` pixels).
    """

    name: str
    label: str
    kind: str
    options: tuple[tuple[str, Any], ...] = ()

    @property
    def kwargs(self) -> dict[str, Any]:
        return dict(self.options)


#: Every variant, in report order: the three pruning variants of docs/algorithm.md (the
#: library's default first), then the baseline at each threshold.
VARIANTS: dict[str, Variant] = {
    v.name: v
    for v in (
        Variant(
            "bayesian+dce", 'Bayesian, coarse="dce" (the default)', "prune", (("coarse", "dce"),)
        ),
        Variant(
            "bayesian",
            "Bayesian, coarse=None (from the full medial axis)",
            "prune",
            (("coarse", None),),
        ),
        Variant("dce", 'DCE pruning [10] (method="dce")', "prune", (("method", "dce"),)),
        *(
            Variant(f"cut-{L:g}", f"skeletonize + cut < {L:g} px", "cut", (("min_length", L),))
            for L in CUT_LENGTHS
        ),
    )
}


@dataclass(frozen=True)
class Measurement:
    """What one variant gives on one mask.

    ``rer`` is the area-weighted reconstruction error over all components; ``ss`` the
    ``LR`` of the largest component (``None`` when not asked for); ``ms`` the wall time of
    the method alone (metrics excluded). ``points`` are (row, col) of the skeleton when
    asked for.
    """

    endpoints: int
    rer: float
    ss: float | None
    ms: float
    points: np.ndarray | None = None


def _lbar(mask: np.ndarray) -> float:
    """``ℓ̄`` of the largest component's medial axis: the length unit of SS (docs/algorithm.md),
    measured on the axis the pruning itself starts from (the canonical frame)."""
    from skelprune.api import components
    from skelprune.skeleton import Skeleton

    crop = max((c for c, _ in components(mask)), key=lambda c: int(c.sum()))
    return Skeleton.medial_axis(crop).normalisation(9.0).lbar


def measure(
    variant: Variant, mask: np.ndarray, with_ss: bool = False, with_points: bool = False
) -> Measurement:
    """Run one variant on one mask and measure it.

    Parameters
    ----------
    variant : Variant
    mask : (H, W) bool array
    with_ss : bool
        Also compute SS (for the baseline this costs a medial axis, for ``ℓ̄``).
    with_points : bool
        Also return the skeleton pixels (for eq. 13).

    Returns
    -------
    Measurement
    """
    from skelprune.grid.reconstruction import reconstruction_error

    if variant.kind == "prune":
        from skelprune.api import prune

        t = time.perf_counter()
        res = prune(mask, **variant.kwargs)
        ms = 1000 * (time.perf_counter() - t)
        comps = res.components
        endpoints = res.n_endpoints()
        area = sum(c.area for c in comps)
        rer = sum(c.rer * c.area for c in comps) / area
        ss = max(comps, key=lambda c: c.area).ss if with_ss else None
        rows, cols, _ = res.skeleton_points() if with_points else (None, None, None)
    else:
        from .baseline import skeletonize_cut

        t = time.perf_counter()
        sk = skeletonize_cut(mask, variant.kwargs["min_length"])
        ms = 1000 * (time.perf_counter() - t)
        endpoints = sk.endpoints
        rer = reconstruction_error(mask, sk.rows, sk.cols, sk.r2)
        ss = None
        if with_ss:
            lbar = _lbar(mask)
            ss = math.log(sk.length / lbar + 1.0) if lbar > 0 else 0.0
        rows, cols = sk.rows, sk.cols
    pts = np.stack([rows, cols], axis=1) if with_points else None
    return Measurement(int(endpoints), float(rer), None if ss is None else float(ss), ms, pts)


@dataclass(frozen=True)
class ShapeRecord:
    """One (shape, perturbation, variant) result; ``perturbation`` is ``"clean"`` or a name.

    ``distance`` is the skeleton distance (:func:`evaluation.perturb.skeleton_distance`)
    between the clean shape's skeleton and this one mapped back to the clean frame
    (``None`` for the clean shape itself).
    """

    dataset: str
    shape: str
    perturbation: str
    variant: str
    endpoints: int
    rer: float
    ss: float | None
    ms: float
    distance: float | None = None


@dataclass(frozen=True)
class RectRecord:
    """One noisy rectangle (``noise`` is a :data:`NOISE_KINDS` name or ``"none"``)."""

    noise: str
    seed: int
    variant: str
    endpoints: int
    error: float
    rer: float
    ms: float


def _rng(seed: int, index: int, name: str) -> np.random.Generator:
    # crc32, not hash(): str hashes are salted per process, and workers must agree.
    return np.random.default_rng([seed, index, zlib.crc32(name.encode())])


def _shape_task(
    args: tuple[str, str, int, np.ndarray, int, tuple[str, ...], tuple[Perturbation, ...]],
) -> list[ShapeRecord]:
    dataset, shape, index, mask, seed, variants, perts = args
    masks = [("clean", mask, None)] + [
        (p.name, *p.apply_mapped(mask, _rng(seed, index, p.name))) for p in perts
    ]
    area = float(np.count_nonzero(mask))
    clean_points: dict[str, np.ndarray] = {}
    out = []
    for pname, m, back in masks:
        for vname in variants:
            r = measure(VARIANTS[vname], m, with_ss=back is None, with_points=True)
            assert r.points is not None
            dist = None
            if back is None:
                clean_points[vname] = r.points
            else:
                dist = skeleton_distance(clean_points[vname], back(r.points), area)
            out.append(
                ShapeRecord(dataset, shape, pname, vname, r.endpoints, r.rer, r.ss, r.ms, dist)
            )
    return out


def _rect_task(args: tuple[str, str, float, int, tuple[str, ...]]) -> list[RectRecord]:
    noise, kind, scale, seed, variants = args
    mask, truth = noisy_rectangle(*RECTANGLE, kind, scale, _rng(seed, 0, noise))  # type: ignore[arg-type]
    out = []
    for vname in variants:
        r = measure(VARIANTS[vname], mask, with_points=True)
        assert r.points is not None
        out.append(
            RectRecord(
                noise, seed, vname, r.endpoints, skeleton_error(r.points, truth), r.rer, r.ms
            )
        )
    return out


def _warm_up() -> None:
    """Load the numba caches in each worker before it is timed."""
    m = np.zeros((24, 40), bool)
    m[4:20, 4:36] = True
    for v in VARIANTS.values():
        measure(v, m)


def load_dataset(folder: Path, limit: int | None = None) -> list[tuple[str, np.ndarray]]:
    """``(name, mask)`` of the PNG masks of a folder, sorted by name, at most ``limit``."""
    from PIL import Image

    files = sorted(Path(folder).glob("*.png"))[:limit]
    return [(p.stem, np.asarray(Image.open(p)) != 0) for p in files]


@dataclass
class StabilityRun:
    """All records of one run, with the aggregations both reports print."""

    shapes: list[ShapeRecord]
    rects: list[RectRecord]
    variants: tuple[str, ...]
    perturbations: tuple[str, ...]
    datasets: tuple[str, ...]
    seeds: int
    seconds: float = 0.0

    # -- aggregations ------------------------------------------------------------------
    def clean(self, dataset: str, variant: str) -> list[ShapeRecord]:
        return [
            r
            for r in self.shapes
            if r.dataset == dataset and r.variant == variant and r.perturbation == "clean"
        ]

    def agreement(self, dataset: str, variant: str, perturbation: str, within: int = 0) -> float:
        """Share of shapes whose endpoint count under ``perturbation`` is the clean one's.

        With ``within > 0``, the share whose count is off by at most that many endpoints:
        a looser reading, reported beside the exact measure (``within=0``), never
        instead of it.
        """
        ref = {r.shape: r.endpoints for r in self.clean(dataset, variant)}
        got = [
            abs(r.endpoints - ref[r.shape]) <= within
            for r in self.shapes
            if r.dataset == dataset and r.variant == variant and r.perturbation == perturbation
        ]
        return float(np.mean(got)) if got else math.nan

    def distance(self, dataset: str, variant: str, perturbation: str) -> float:
        """Median skeleton distance to the clean skeleton (``nan`` if none measured)."""
        got = [
            r.distance
            for r in self.shapes
            if r.dataset == dataset
            and r.variant == variant
            and r.perturbation == perturbation
            and r.distance is not None
        ]
        got = [d for d in got if not math.isnan(d)]
        return float(np.median(got)) if got else math.nan

    def min_agreement(self, variant: str) -> float:
        return min(self.agreement(d, variant, p) for d in self.datasets for p in self.perturbations)

    def disagreements(
        self, dataset: str, variant: str, perturbation: str
    ) -> list[tuple[str, int, int]]:
        """``(shape, clean endpoints, perturbed endpoints)`` where they differ."""
        ref = {r.shape: r.endpoints for r in self.clean(dataset, variant)}
        return [
            (r.shape, ref[r.shape], r.endpoints)
            for r in self.shapes
            if r.dataset == dataset
            and r.variant == variant
            and r.perturbation == perturbation
            and r.endpoints != ref[r.shape]
        ]

    def rect_share4(self, noise: str, variant: str) -> float:
        got = [r.endpoints == 4 for r in self.rects if r.noise == noise and r.variant == variant]
        return float(np.mean(got)) if got else math.nan

    def rect_error(self, noise: str, variant: str) -> float:
        got = [r.error for r in self.rects if r.noise == noise and r.variant == variant]
        return float(np.mean(got)) if got else math.nan

    def rect_noises(self) -> list[str]:
        return list(dict.fromkeys(r.noise for r in self.rects))

    def meets_targets(self, variant: str) -> dict[str, bool]:
        """The targets as this run can check them: the 90 % agreement reading (the target
        itself is relative to the anchors, see :func:`~evaluation.report.targets_table`),
        rectangles, median RER ≤ 1 %."""
        noisy = [n for n, _, _ in NOISE_KINDS if n in self.rect_noises()]
        return {
            "agreement": bool(self.min_agreement(variant) >= 0.9) if self.perturbations else False,
            "rectangles": bool(noisy)
            and all(
                self.rect_share4(n, variant) == 1.0 and self.rect_error(n, variant) <= 1.0
                for n in noisy
            ),
            "rer": all(
                float(np.median([r.rer for r in self.clean(d, variant)])) <= 0.01
                for d in self.datasets
            ),
        }


def _pool(workers: int) -> ProcessPoolExecutor:
    # forkserver: the parent may already hold numba/OpenMP state that fork would copy.
    return ProcessPoolExecutor(
        max_workers=workers,
        initializer=_warm_up,
        mp_context=multiprocessing.get_context("forkserver"),
    )


def run_stability(
    datasets: dict[str, Sequence[tuple[str, np.ndarray]]],
    variants: Iterable[str] = tuple(VARIANTS),
    perturbations: Iterable[Perturbation] = tuple(PERTURBATIONS.values()),
    rect_seeds: int = 10,
    seed: int = 7,
    workers: int = 2,
    progress: bool = True,
    on_result: Callable[[], None] | None = None,
) -> StabilityRun:
    """Run the stability experiment over whole datasets and the noisy rectangles.

    Parameters
    ----------
    datasets : dict
        Dataset name -> list of ``(shape name, mask)``.
    variants : iterable of str
        Keys of :data:`VARIANTS`.
    perturbations : iterable of Perturbation
        Usually :data:`evaluation.perturb.PERTURBATIONS`; tests pass an identity one.
    rect_seeds : int
        Noisy rectangles per noise kind (0: skip the rectangles); one clean one besides.
    seed : int
        Base seed of every noise draw.
    workers : int
        Worker processes (0 or 1: run in this process, for tests and debugging).
    progress : bool
        Show a tqdm progress bar on stderr.
    on_result : callable, optional
        Called after each finished task (tests use it to count).

    Returns
    -------
    StabilityRun
    """
    from tqdm import tqdm

    variants = tuple(variants)
    perts = tuple(perturbations)
    shape_jobs = [
        (d, name, i, m, seed, variants, perts)
        for d, items in datasets.items()
        for i, (name, m) in enumerate(items)
    ]
    rect_jobs = []
    if rect_seeds:
        rect_jobs.append(("none", "uniform", 0.0, 0, variants))
        rect_jobs += [
            (noise, kind, scale, s, variants)
            for noise, kind, scale in NOISE_KINDS
            for s in range(rect_seeds)
        ]
    t0 = time.perf_counter()
    shapes: list[ShapeRecord] = []
    rects: list[RectRecord] = []
    bar = tqdm(
        total=len(shape_jobs) + len(rect_jobs), unit="shape", disable=not progress, desc="stability"
    )
    if workers > 1:
        with _pool(workers) as pool:
            # Rectangles first: they are short, and the big scale-2 shapes then finish last
            # in parallel instead of one worker idling.
            for recs in pool.map(_rect_task, rect_jobs):
                rects.extend(recs)
                bar.update()
            for srecs in pool.map(_shape_task, shape_jobs):
                shapes.extend(srecs)
                bar.update()
                if on_result:
                    on_result()
    else:
        _warm_up()
        for job in rect_jobs:
            rects.extend(_rect_task(job))
            bar.update()
        for sjob in shape_jobs:
            shapes.extend(_shape_task(sjob))
            bar.update()
            if on_result:
                on_result()
    bar.close()
    return StabilityRun(
        shapes,
        rects,
        variants,
        tuple(p.name for p in perts),
        tuple(datasets),
        rect_seeds,
        time.perf_counter() - t0,
    )
