"""``python -m evaluation [--out docs]``: regenerate the evaluation report and figures.

``make eval`` runs it. It reads the datasets in ``data/`` (or ``$SKELPRUNE_DATA``) and needs
the ``bench`` extra (matplotlib).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .run import run_evaluation


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m evaluation", description=__doc__.split("\n")[0]
    )
    parser.add_argument(
        "--out", type=Path, default=Path("docs"), help="folder for the reports and figures/"
    )
    parser.add_argument(
        "--data", type=Path, help="folder with kimia216/, kimia99/, skelneton-dev/, anchors/"
    )
    parser.add_argument("--workers", type=int, default=2, help="processes of the stability run")
    parser.add_argument("--limit", type=int, help=argparse.SUPPRESS)  # first N shapes a dataset
    parser.add_argument("--rect-seeds", type=int, default=10, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    try:
        written = run_evaluation(
            args.out,
            data=args.data,
            limit=args.limit,
            workers=args.workers,
            rect_seeds=args.rect_seeds,
        )
    except (FileNotFoundError, ImportError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    for path in written.values():
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
