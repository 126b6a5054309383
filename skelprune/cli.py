"""Command line: ``skelprune prune FILE.png [--beta B] [--overlay OUT.png]``, ``skelprune eval``.

One file prints the output document (SPEC §3) as JSON. Several files, or a folder,
are pruned in a pool of worker processes with a progress bar on stderr and print one
JSON line per file: ``{"file": ..., "result": {...}}`` or ``{"file": ..., "error": ...}``.

``skelprune eval --out docs`` regenerates the evaluation report, ``stability.md`` and the
figures from the benchmark data (``skelprune.evaluation``; needs the ``bench`` extra).
"""

from __future__ import annotations

import json
import os
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from .errors import SkelpruneError

if TYPE_CHECKING:
    from .result import PruneResult

app = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="Parameter-free Bayesian skeleton pruning.")


def _prune(path: str, beta: float, method: str, coarse: str | None,
           foreground: str, min_margin: float | None = None) -> PruneResult:
    from .api import prune
    from .io import read_shape

    mask, taken = read_shape(path, foreground=foreground)
    res = prune(mask, beta=beta, method=method, coarse=coarse, min_margin=min_margin)
    res.foreground = taken
    return res


def _prune_file(path: str, beta: float, method: str, coarse: str | None,
                curve: bool, foreground: str = "auto",
                min_margin: float | None = None) -> dict[str, Any]:
    try:
        doc = _prune(path, beta, method, coarse, foreground, min_margin).to_dict(curve=curve)
        return {"file": path, "result": doc}
    except (SkelpruneError, OSError) as exc:
        return {"file": path, "error": f"{type(exc).__name__}: {exc}"}


def _expand(paths: list[Path]) -> list[Path]:
    files: list[Path] = []
    for p in paths:
        files.extend(sorted(p.glob("*.png")) if p.is_dir() else [p])
    return files


@app.command("prune")
def prune_command(
    files: Annotated[list[Path], typer.Argument(help="PNG masks, or folders of them.")],
    beta: Annotated[float, typer.Option(help="Weight of the reconstruction term.")] = 9.0,
    method: Annotated[str, typer.Option(help="bayesian or dce.")] = "bayesian",
    coarse: Annotated[str, typer.Option(help="Coarse stage before the Bayesian pruning: "
                                        "dce, or none (the full medial axis).")] = "dce",
    overlay: Annotated[Path | None, typer.Option(help="Write the overlay PNG here "
                                                 "(one input file only).")] = None,
    curve: Annotated[bool, typer.Option(help="Include the pruning curve.")] = True,
    workers: Annotated[int, typer.Option(help="Worker processes for several files.")] = 0,
    foreground: Annotated[str, typer.Option(
        help="Which pixels are the shape: auto (the background is the grey level holding "
        "most of the border; opaque pixels if the image uses transparency), nonzero or "
        "zero.")] = "auto",
    min_margin: Annotated[float | None, typer.Option(
        help="Drop end branches whose margin is below this (bayesian only; default off: "
        "the paper's answer).")] = None,
) -> None:
    """Prune the skeleton of each shape and print the result as JSON."""
    from .foreground import FOREGROUND_RULES

    if foreground not in FOREGROUND_RULES:
        typer.echo(f"error: --foreground must be one of {', '.join(FOREGROUND_RULES)}, "
                   f"got {foreground!r}", err=True)
        raise typer.Exit(2)
    coarse = None if coarse in (None, "", "none", "null") else coarse
    inputs = _expand(files)
    if not inputs:
        typer.echo("error: no PNG file given", err=True)
        raise typer.Exit(2)
    if len(inputs) == 1 and not files[0].is_dir():
        try:
            res = _prune(str(inputs[0]), beta, method, coarse, foreground, min_margin)
        except (SkelpruneError, OSError) as exc:
            typer.echo(f"error: {inputs[0]}: {exc}", err=True)
            raise typer.Exit(1) from None
        if overlay is not None:
            overlay.write_bytes(res.overlay_png())
        json.dump(res.to_dict(curve=curve), sys.stdout)
        sys.stdout.write("\n")
        return
    if overlay is not None:
        typer.echo("error: --overlay takes one input file", err=True)
        raise typer.Exit(2)
    from tqdm import tqdm

    n = workers or os.cpu_count() or 1
    failed = 0
    with ProcessPoolExecutor(max_workers=n) as pool:
        jobs = pool.map(_prune_file, [str(p) for p in inputs], [beta] * len(inputs),
                        [method] * len(inputs), [coarse] * len(inputs), [curve] * len(inputs),
                        [foreground] * len(inputs), [min_margin] * len(inputs))
        for line in tqdm(jobs, total=len(inputs), file=sys.stderr, unit="shape"):
            failed += "error" in line
            sys.stdout.write(json.dumps(line) + "\n")
    if failed:
        raise typer.Exit(1)


@app.command("eval")
def eval_command(
    out: Annotated[Path, typer.Option(help="Folder for evaluation.md, stability.md "
                                      "and figures/.")] = Path("docs"),
    data: Annotated[Path | None, typer.Option(help="Folder with kimia216/ and kimia99/ "
                                              "(default: $SKELPRUNE_DATA or "
                                              "../shared/data).")] = None,
    workers: Annotated[int, typer.Option(help="Processes of the stability run.")] = 2,
    limit: Annotated[int | None, typer.Option(hidden=True,
                                              help="First N shapes a dataset.")] = None,
    rect_seeds: Annotated[int, typer.Option(hidden=True,
                                            help="Noisy rectangles a noise kind.")] = 10,
) -> None:
    """Regenerate the evaluation report and figures (needs the bench extra: matplotlib)."""
    from .evaluation import run_evaluation

    try:
        written = run_evaluation(out, data=data, limit=limit, workers=workers,
                                 rect_seeds=rect_seeds)
    except (FileNotFoundError, ImportError) as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(1) from None
    for path in written.values():
        typer.echo(str(path))


@app.command("version")
def version() -> None:
    """Print the version."""
    from . import __version__

    typer.echo(__version__)


def main() -> None:  # console-script entry point
    app()


if __name__ == "__main__":
    main()
