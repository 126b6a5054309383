"""One benchmark of what users send, read at once: every data set against its peer.

``python -m benchmarks default [--data DIR] [--options JSON] [--only GROUPS] [--quick]``
prints one table: a row a (data set, metric), with skelprune's value at the given
options, its peers' values on the same data, the target and whether skelprune meets it.
The groups (``--only`` takes a comma-separated list of their names):

- ``vessels``, ``cracks``: the real vessel (``DIR/drive-test``) and crack
  (``DIR/crackforest``) masks of ``--data``; left out with a note when it is not given;
- ``networks``: the drawn vessel, crack and road networks of :mod:`testkit.networks`;
- ``silhouettes``: SkelNetOn dev F1, median RER, limbs kept, round ends centred;
- ``stability``: the anchor masks against the authors' code, on two fixed halves;
- ``outlines``: kimia216 and kimia99 under pixel flips and resampled contour noise;
- ``trees``: random branching tubes (:mod:`testkit.volumes`), smooth and voxel-rough;
- ``neurons``: navis's example neurons voxelized from their radii (:mod:`testkit.neurons`).

Every job runs in a process pool of two; :func:`run` returns the rows for scripts::

    from benchmarks.default_suite import run
    rows = run({"coarse": None}, data=Path("real-networks"), quick=True)
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import sys
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Future, ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .common import table

__all__ = ["GROUPS", "Context", "Group", "Row", "main", "markdown", "run"]


@dataclass(frozen=True)
class Row:
    """One line of the table.

    ``ours`` and ``peers`` are the printed cells; ``numbers`` the raw values behind them
    (``"skelprune"`` and one key a peer), for scripts; ``passed`` is None where the row
    has no target.
    """

    dataset: str
    metric: str
    ours: str
    peers: str
    target: str
    passed: bool | None
    numbers: dict[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class Context:
    """What every group is run with: the pruning options, the real-networks folder, the
    quick flag."""

    options: dict[str, Any]
    data: Path | None
    quick: bool


#: A job: a module-level function and its arguments (picklable, run in a worker).
Job = tuple[Callable[..., Any], tuple[Any, ...]]


@dataclass(frozen=True)
class Group:
    """A set of rows: the jobs that measure them and how their results become rows.

    ``available`` says why the group cannot run (None: it can).
    """

    name: str
    jobs: Callable[[Context], list[Job]]
    rows: Callable[[Context, list[Any]], list[Row]]
    available: Callable[[Context], str | None] = lambda ctx: None


def _groups() -> dict[str, Group]:
    from . import default_outlines, default_planar, default_silhouettes, default_volumes

    parts = (default_planar, default_silhouettes, default_outlines, default_volumes)
    return {g.name: g for part in parts for g in part.GROUPS}


#: The groups, in table order (names: see the module docstring).
GROUPS: tuple[str, ...] = (
    "vessels",
    "cracks",
    "networks",
    "silhouettes",
    "stability",
    "outlines",
    "trees",
    "neurons",
)


def run(
    options: dict[str, Any] | None = None,
    data: Path | None = None,
    quick: bool = False,
    only: Sequence[str] | None = None,
    workers: int = 2,
    notes: list[str] | None = None,
) -> list[Row]:
    """Measure the groups ``only`` (default: all) at ``options`` and return their rows.

    ``options``: :class:`skelprune.options.PruneOptions` fields, passed to
    :func:`skelprune.prune` for every 2-D and 3-D input. ``data``: the folder holding
    ``drive-test/`` and ``crackforest/``; without it the rows that need it are left out
    and a note says so (in ``notes`` when given).
    """
    from skelprune.options import PruneOptions

    options = dict(options or {})
    try:  # a wrong field or value fails here, before any job runs
        PruneOptions(**options)
    except TypeError as e:
        raise ValueError(f"options: {e}") from None
    ctx = Context(options, None if data is None else Path(data), quick)
    groups = _groups()
    chosen = list(only or GROUPS)
    unknown = [g for g in chosen if g not in groups]
    if unknown:
        raise ValueError(f"unknown group(s) {', '.join(unknown)}; known: {', '.join(GROUPS)}")
    runnable = []
    for name in GROUPS:
        if name not in chosen:
            continue
        why = groups[name].available(ctx)
        if why is None:
            runnable.append(groups[name])
        elif notes is not None:
            notes.append(f"{name}: left out ({why})")
    jobs = {g.name: g.jobs(ctx) for g in runnable}
    results: dict[str, list[Any]] = {}
    if workers > 1:
        mp = multiprocessing.get_context("forkserver")
        with ProcessPoolExecutor(max_workers=workers, mp_context=mp) as pool:
            # the slowest groups (volumes) first, so the pool's tail is short
            futures: dict[str, list[Future[Any]]] = {}
            for g in sorted(runnable, key=lambda g: g.name not in ("neurons", "trees")):
                futures[g.name] = [pool.submit(fn, *args) for fn, args in jobs[g.name]]
            for name, fs in futures.items():
                results[name] = [f.result() for f in fs]
    else:
        for g in runnable:
            results[g.name] = [fn(*args) for fn, args in jobs[g.name]]
    rows: list[Row] = []
    for g in runnable:
        rows += g.rows(ctx, results[g.name])
    return rows


HEADER = ["data set", "metric", "skelprune", "peers", "target", "pass"]


def _cells(rows: Sequence[Row]) -> list[list[object]]:
    verdict = {True: "yes", False: "**no**", None: "-"}
    return [[r.dataset, r.metric, r.ours, r.peers, r.target, verdict[r.passed]] for r in rows]


def markdown(rows: Sequence[Row]) -> str:
    """The rows as one Markdown table."""
    return table(HEADER, _cells(rows))


def _plain(value: Any) -> Any:
    """numpy scalars as plain numbers, for JSON."""
    return value.item() if hasattr(value, "item") else str(value)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks default",
        description="Every kind of input users send, against its peers, in one table.",
    )
    parser.add_argument(
        "--data",
        type=Path,
        default=None,
        help="folder holding drive-test/ and crackforest/ (real vessel and crack masks); "
        "without it those rows are left out",
    )
    parser.add_argument(
        "--options",
        default="{}",
        help="pruning options as JSON, e.g. '{\"coarse\": null}' (PruneOptions fields), "
        "for every 2-D and 3-D input",
    )
    parser.add_argument(
        "--only", default=None, help=f"comma-separated groups of: {', '.join(GROUPS)}"
    )
    parser.add_argument(
        "--quick", action="store_true", help="a subset of each group (a few minutes)"
    )
    parser.add_argument("--workers", type=int, default=2, help="worker processes (default 2)")
    parser.add_argument("--json", type=Path, default=None, help="also write the rows as JSON")
    args = parser.parse_args(argv or [])
    try:
        options = json.loads(args.options)
    except json.JSONDecodeError as e:
        parser.error(f"--options is not JSON: {e}")
    if not isinstance(options, dict):
        parser.error("--options must be a JSON object of option names and values")
    if args.data is not None and not args.data.is_dir():
        parser.error(f"--data {args.data} is not a folder")
    only = [s.strip() for s in args.only.split(",") if s.strip()] if args.only else None
    notes: list[str] = []
    t = time.perf_counter()
    try:
        rows = run(options, args.data, args.quick, only, args.workers, notes)
    except ValueError as e:  # a wrong option or group, named by the error
        parser.error(str(e))
    print(f"options: {json.dumps(options)}{' (quick)' if args.quick else ''}\n")
    print(markdown(rows))
    for note in notes:
        print(f"\nnote: {note}")
    print(f"\n{time.perf_counter() - t:.0f} s")
    if args.json is not None:
        args.json.write_text(json.dumps([r.__dict__ for r in rows], indent=1, default=_plain))


if __name__ == "__main__":
    main(sys.argv[1:])
