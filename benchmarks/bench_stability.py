"""Stability benchmark: which pruning variant keeps its endpoints.

On kimia216 and kimia99, every perturbation of ``evaluation.perturb.PERTURBATIONS``: share
of shapes whose endpoint count is unchanged, for ``coarse=None``, ``coarse="dce"``,
``method="dce"`` and the ``skeletonize`` + branch-cut baseline; the noisy rectangles of
the paper's Table 2; median RER and ms a shape; how far the skeleton moves (skeleton
distance); and the comparison with the authors' code on the masks of ``data/anchors``
(``evaluation.anchors``). The computation lives in
``evaluation.stability`` (``python -m evaluation`` reports the same numbers).

``python -m benchmarks stability`` runs everything (2 worker processes) and rewrites
``docs/stability.md``; ``python -m benchmarks.bench_stability --quick`` runs 20 shapes a
dataset and 3 rectangles a noise kind and only prints.

``python -m benchmarks.bench_stability --sizes [--quick]`` measures over noise models and
size bands at once (``evaluation.sizes``): dataset shapes and round-ended
shapes drawn in ``testkit.shapes``, scaled by their contour to 128, 256 and 512 px,
every variant of ``SIZE_VARIANTS``, one noisy copy a model (every 24th shape of each
dataset: 27 shapes, about 11 minutes a variant pair on two shared cores); ``--quick``
(a few minutes) takes every 48th, for the default and the paper's untrimmed answer.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from evaluation.anchors import anchors_markdown, run_anchors
from evaluation.report import (
    agreement_table,
    clean_table,
    distance_table,
    rectangle_table,
    stability_markdown,
    targets_table,
)
from evaluation.stability import load_dataset, run_stability

from .common import DATA

DOCS = Path(__file__).resolve().parents[1] / "docs"
COMMAND = "python -m benchmarks stability"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.bench_stability")
    parser.add_argument(
        "--quick", action="store_true", help="20 shapes a dataset, 3 rectangles a kind; print only"
    )
    parser.add_argument("--limit", type=int, default=None, help="shapes per dataset")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument(
        "--sizes", action="store_true", help="noise models and size bands at once; print only"
    )
    parser.add_argument("--variants", default=None, help="comma-separated, for --sizes")
    args = parser.parse_args(argv or [])
    if args.sizes:
        sizes(args)
        return
    limit = 20 if args.quick and args.limit is None else args.limit
    sets = {name: load_dataset(DATA / name, limit) for name in ("kimia216", "kimia99")}
    run = run_stability(sets, rect_seeds=3 if args.quick else 10, workers=args.workers)
    anchors = run_anchors(DATA / "anchors", workers=args.workers, limit=limit)
    print(targets_table(run, anchors))
    for d in run.datasets:
        print(f"\nendpoint agreement, {d}\n")
        print(agreement_table(run, d))
        print(f"\nendpoint count within ±1 / ±2 (not a target), {d}\n")
        print(agreement_table(run, d, within=(1, 2)))
        print(f"\nskeleton distance (not a target), {d}\n")
        print(distance_table(run, d))
    print("\nnoisy rectangles\n")
    print(rectangle_table(run))
    print()
    print(clean_table(run))
    print(f"\n{run.seconds:.0f} s")
    print("\n" + anchors_markdown(anchors))
    if not args.quick and args.limit is None:
        (DOCS / "stability.md").write_text(stability_markdown(run, COMMAND, anchors))
        print(f"wrote {DOCS / 'stability.md'}")


def sizes(args: argparse.Namespace) -> None:
    """The size-band stability table (:mod:`evaluation.sizes`)."""
    import time

    from evaluation.sizes import SIZE_VARIANTS, run_sizes, sizes_markdown
    from testkit.shapes import DRAWN

    step = 48 if args.quick else 24
    shapes = []
    for name in ("kimia216", "kimia99", "skelneton-dev/shapes"):
        shapes += load_dataset(DATA / name, None)[step // 2 :: step]
    if args.limit:
        shapes = shapes[: args.limit]
    shapes += [(name, draw()) for name, draw in DRAWN.items()]
    if args.variants:
        variants = args.variants.split(",")
    else:
        variants = ["default", "argmin/trim=false"] if args.quick else list(SIZE_VARIANTS)
    t = time.perf_counter()
    records = run_sizes(shapes, variants, seeds=1, workers=args.workers)
    print(f"{len(shapes)} shapes; exact / within ±1 (%), gains and losses over the six pooled\n")
    print(sizes_markdown(records))
    print(f"\n{time.perf_counter() - t:.0f} s")


if __name__ == "__main__":
    main(sys.argv[1:])
