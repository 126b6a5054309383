"""Path similarity matching: the all-pairs distance matrix of kimia216 (target ≤ 60 s).

``python -m benchmarks match`` prunes every kimia216 shape (default options), builds each
skeleton's path table once (:func:`skelprune.describe`) and matches all 204 × 203 / 2
pairs, in one process and split over 2 worker processes; it prints the seconds of each
stage and the median time of one pair. ``python -m benchmarks.bench_match --write`` also
runs the whole retrieval evaluation and rewrites ``docs/retrieval.md`` (as ``skelprune
eval`` does).
"""

from __future__ import annotations

import argparse
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from evaluation.retrieval import (
    all_pairs,
    class_of,
    descriptors,
    hits_at_rank,
    retrieval_markdown,
    run_retrieval,
)
from evaluation.stability import load_dataset
from skelprune.matching import _match

from .common import DATA, table

DOCS = Path(__file__).resolve().parents[1] / "docs"
COMMAND = "python -m benchmarks.bench_match --write"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.bench_match")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--write", action="store_true", help="also write docs/retrieval.md")
    args = parser.parse_args(argv or [])
    shapes = load_dataset(DATA / "kimia216")
    masks = [m for _, m in shapes]
    classes = [class_of(n) for n, _ in shapes]
    descriptors(masks[:2], {})  # compile (or load) the kernels outside the timings
    t = time.perf_counter()
    descs = descriptors(masks, {})
    t_desc = time.perf_counter() - t
    ok = [d for d in descs if d is not None]
    per_pair = []
    for i in range(0, len(ok), 17):  # a sample of single pairs, timed one by one
        for j in range(1, len(ok), 23):
            t = time.perf_counter()
            _match(ok[i], ok[j])
            per_pair.append(time.perf_counter() - t)
    t = time.perf_counter()
    one = all_pairs(descs)
    t_one = time.perf_counter() - t
    with ProcessPoolExecutor(args.workers) as pool:
        all_pairs(descs[:4], pool)  # start the workers and compile there
        t = time.perf_counter()
        two = all_pairs(descs, pool)
        t_two = time.perf_counter() - t
    assert np.array_equal(one, two)
    n = len(descs)
    ends = [d.n_endpoints for d in ok]
    hits = hits_at_rank(one, classes, 11)
    print(
        table(
            ["stage", "seconds"],
            [
                [f"prune + path tables, {n} shapes, 1 process", t_desc],
                [f"all pairs ({n}²), 1 process", t_one],
                [f"all pairs ({n}²), {args.workers} processes", t_two],
                ["ratio 1 / 2 processes", t_one / t_two],
                [f"one pair, median ms ({len(per_pair)} timed)", 1000 * float(np.median(per_pair))],
            ],
        )
    )
    print(
        f"\nendpoints per skeleton: median {np.median(ends):g}, max {max(ends)}; "
        f"hits at ranks 1..11 (default pruning): {' '.join(map(str, hits))}"
    )
    if args.write:
        sets = {name: load_dataset(DATA / name) for name in ("kimia216", "kimia99")}
        run = run_retrieval(sets, workers=args.workers)
        (DOCS / "retrieval.md").write_text(retrieval_markdown(run, COMMAND))
        print(f"wrote {DOCS / 'retrieval.md'}")


if __name__ == "__main__":
    main(sys.argv[1:])
