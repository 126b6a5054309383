"""Branch margins: flips by margin quartile and the min_margin option (``docs/margin.md``).

``python -m benchmarks margin`` runs kimia216 and kimia99 under every perturbation of the
stability benchmark (2 worker processes), prints the tables of ``evaluation.margin``
and rewrites ``docs/margin.md`` (as ``python -m evaluation`` does); ``--limit N`` takes the
first N shapes of each dataset and only prints.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from evaluation.margin import flip_table, margin_markdown, min_margin_table, run_margins
from evaluation.stability import load_dataset

from .common import DATA

DOCS = Path(__file__).resolve().parents[1] / "docs"
COMMAND = "python -m benchmarks margin"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.bench_margin")
    parser.add_argument("--limit", type=int, default=None, help="shapes per dataset")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args(argv or [])
    sets = {name: load_dataset(DATA / name, args.limit) for name in ("kimia216", "kimia99")}
    run = run_margins(sets, workers=args.workers)
    print("flips by margin quartile\n")
    print(flip_table(run))
    print("\nmin_margin\n")
    print(min_margin_table(run))
    if args.limit is None:
        (DOCS / "margin.md").write_text(margin_markdown(run, COMMAND))
        print(f"wrote {DOCS / 'margin.md'}")


if __name__ == "__main__":
    main(sys.argv[1:])
