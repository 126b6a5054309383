"""Command line: ``skelprune prune FILE.png [--beta B] [--overlay OUT.png]``, ``skelprune eval``.

One file prints the output document (SPEC §3) as JSON. Several files, or a folder,
are pruned in a pool of worker processes with a progress bar on stderr and print one
JSON line per file: ``{"file": ..., "result": {...}}`` or ``{"file": ..., "error": ...}``.

``skelprune eval --out docs`` regenerates the evaluation report, ``stability.md`` and the
figures from the benchmark data (``skelprune.evaluation``; needs the ``bench`` extra).
"""

from __future__ import annotations

import enum
import json
import os
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Annotated, Any

import typer

from .errors import SkelpruneError
from .options import COARSE, METHODS, OutputOptions, PruneOptions, option_fields

app = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="Parameter-free Bayesian skeleton pruning.")


def _prune_file(path: str, options: PruneOptions, curve: bool) -> dict[str, Any]:
    from .api import prune
    from .io.png import read_mask

    try:
        doc = prune(read_mask(path), **options.kwargs()).to_dict(curve=curve)
        return {"file": path, "result": doc}
    except (SkelpruneError, OSError) as exc:
        return {"file": path, "error": f"{type(exc).__name__}: {exc}"}


def _expand(paths: list[Path]) -> list[Path]:
    files: list[Path] = []
    for p in paths:
        files.extend(sorted(p.glob("*.png")) if p.is_dir() else [p])
    return files


HELP = {name: text for name, _, text, _ in option_fields(PruneOptions, OutputOptions)}
# the choices as typer shows them (it lists an Enum's values in --help)
Method = enum.Enum("Method", {name: name for name in METHODS}, type=str)
Coarse = enum.Enum("Coarse", {name: name for name in COARSE}, type=str)


@app.command("prune")
def prune_command(
    files: Annotated[list[Path], typer.Argument(help="PNG masks, or folders of them.")],
    beta: Annotated[float, typer.Option(help=HELP["beta"])] = PruneOptions.beta,
    method: Annotated[Method, typer.Option(help=HELP["method"])] = Method(PruneOptions.method),
    coarse: Annotated[Coarse, typer.Option(help=HELP["coarse"])] = Coarse("dce"),
    dce_threshold: Annotated[float | None, typer.Option(help=HELP["dce_threshold"])] = None,
    overlay: Annotated[Path | None, typer.Option(help="Write the overlay PNG here "
                                                 "(one input file only).")] = None,
    curve: Annotated[bool, typer.Option(help=HELP["curve"])] = OutputOptions.curve,
    workers: Annotated[int, typer.Option(help="Worker processes for several files.")] = 0,
) -> None:
    """Prune the skeleton of each shape and print the result as JSON."""
    from .api import prune
    from .io.png import read_mask

    try:  # checked once, before any file is read
        options = PruneOptions(beta=beta, method=method.value, coarse=coarse.value,
                               dce_threshold=dce_threshold)
    except SkelpruneError as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(2) from None
    inputs = _expand(files)
    if not inputs:
        typer.echo("error: no PNG file given", err=True)
        raise typer.Exit(2)
    if len(inputs) == 1 and not files[0].is_dir():
        try:
            res = prune(read_mask(str(inputs[0])), **options.kwargs())
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
        jobs = pool.map(_prune_file, [str(p) for p in inputs], [options] * len(inputs),
                        [curve] * len(inputs))
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
    from .evaluation.run import run_evaluation

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
