"""``skelprune match A.png B.png`` and ``skelprune retrieve FOLDER``: the path similarity
of two shapes' skeletons (:func:`skelprune.match`), and every shape matched with every
other, each printed with its closest ones.
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path
from typing import Annotated, Any

import typer

from .cli_files import _expand, _prune
from .cli_options import _options_or_exit, with_options
from .errors import SkelpruneError
from .options import OutputOptions, PruneOptions, RasterOptions, ReadOptions

__all__ = ["match_command", "register", "retrieve_command"]


def _describe_file(path: str, options: PruneOptions, read: ReadOptions) -> Any:
    from .matching import describe

    try:
        return describe(_prune(path, options, read, RasterOptions(), OutputOptions())[0])
    except (SkelpruneError, OSError) as exc:
        return f"{type(exc).__name__}: {exc}"


@with_options(PruneOptions, ReadOptions)
def match_command(
    a: Annotated[Path, typer.Argument(help="PNG mask a.")],
    b: Annotated[Path, typer.Argument(help="PNG mask b.")],
    *,
    options: dict[str, Any],
) -> None:
    """Match the skeletons of two shapes (path similarity) and print distance and
    endpoint correspondence as JSON."""
    from .matching import match

    prune_opts, read = _options_or_exit(options, PruneOptions, ReadOptions)
    try:
        shapes = [
            _prune(str(p), prune_opts, read, RasterOptions(), OutputOptions())[0] for p in (a, b)
        ]
        res = match(*shapes)
    except (SkelpruneError, OSError) as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(1) from None
    json.dump(res.to_dict(), sys.stdout)
    sys.stdout.write("\n")


@with_options(PruneOptions, ReadOptions)
def retrieve_command(
    folder: Annotated[list[Path], typer.Argument(help="Folders of PNG masks, or PNG files.")],
    top: Annotated[int, typer.Option(min=1, help="Closest shapes listed per shape.")] = 10,
    workers: Annotated[int, typer.Option(help="Worker processes (0: one a core).")] = 0,
    *,
    options: dict[str, Any],
) -> None:
    """Match every shape with every other and print, per shape, its closest ones as JSON
    lines: {"file", "top": [{"file", "distance"}, ...]} (or {"file", "error"})."""
    from concurrent.futures import ProcessPoolExecutor

    import numpy as np
    from tqdm import tqdm

    from .matching import distance_matrix

    prune_opts, read = _options_or_exit(options, PruneOptions, ReadOptions)
    inputs = _expand(folder)
    if not inputs:
        typer.echo("error: no PNG file given", err=True)
        raise typer.Exit(2)
    n = workers or os.cpu_count() or 1
    k = len(inputs)
    with ProcessPoolExecutor(max_workers=n) as pool:
        described = list(
            tqdm(
                pool.map(_describe_file, [str(p) for p in inputs], [prune_opts] * k, [read] * k),
                total=k,
                file=sys.stderr,
                unit="shape",
            )
        )
    good = [i for i, d in enumerate(described) if not isinstance(d, str)]
    dist = distance_matrix([described[i] for i in good], workers=n)
    np.fill_diagonal(dist, np.inf)
    failed = 0
    row = {i: r for r, i in enumerate(good)}
    for i, path in enumerate(inputs):
        if i not in row:
            failed += 1
            sys.stdout.write(json.dumps({"file": str(path), "error": described[i]}) + "\n")
            continue
        d = dist[row[i]]
        order = np.argsort(d, kind="stable")[: min(top, len(good) - 1)]
        sys.stdout.write(
            json.dumps(
                {
                    "file": str(path),
                    "top": [{"file": str(inputs[good[j]]), "distance": float(d[j])} for j in order],
                }
            )
            + "\n"
        )
    if failed:
        raise typer.Exit(1)


def register(app: typer.Typer) -> None:
    """Add the commands to the command line's app."""
    app.command("match")(match_command)
    app.command("retrieve")(retrieve_command)
