"""``skelprune prune-many``'s run: a progress bar while the results come in, each failed
input named on stderr as it fails, and a summary at the end."""

from __future__ import annotations

import sys
import time
from collections import Counter
from pathlib import Path
from typing import Any

from ..errors import SkelpruneError
from .store import PROBLEMS_FILE

__all__ = ["run_command"]


def _duration(seconds: float) -> str:
    minutes, s = divmod(round(seconds), 60)
    return f"{seconds:.1f} s" if seconds < 60 else f"{minutes} min {s:02d} s"


def run_command(inputs: list[str], out: Path, **run: Any) -> int:
    """Run :func:`~skelprune.parallel.iter_prune_many` on ``inputs`` into ``out`` with a
    progress bar on stderr; the exit status: 0, or 1 when an input failed."""
    from tqdm import tqdm

    from .run import iter_prune_many

    t0 = time.perf_counter()
    counts: Counter[str] = Counter()
    outcomes = iter_prune_many(inputs, out=out, **run)
    try:
        total = next(outcomes)
    except SkelpruneError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    # count, rate and time left: tqdm's own "n/total [elapsed<left, rate]"
    with tqdm(total=total, file=sys.stderr, unit="input", smoothing=0.1) as bar:
        try:
            for outcome in outcomes:
                counts[outcome.status] += 1
                if outcome.problem is not None:
                    p = outcome.problem
                    bar.write(f"failed: {p['input']}: {p['kind']}: {p['detail']}", file=sys.stderr)
                bar.update()
        except OSError as exc:  # the scheduler cannot be reached, or went away
            bar.close()
            print(f"error: the Dask cluster: {exc}", file=sys.stderr)
            return 2
    took = time.perf_counter() - t0
    summary = (
        f"done {counts['done']}, failed {counts['failed']}, skipped {counts['skipped']} "
        f"of {total} in {_duration(took)}; results in {out}"
    )
    if counts["failed"]:
        summary += f", problems in {out / PROBLEMS_FILE}"
    print(summary, file=sys.stderr)
    return 1 if counts["failed"] else 0
