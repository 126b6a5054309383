"""Command line: ``skelprune prune FILE [--beta B] [--overlay OUT.png]``, ``skelprune
match A.png B.png``, ``skelprune retrieve FOLDER``.

A FILE is a PNG mask or a GeoJSON polygon (``.geojson``/``.json``: a Polygon,
MultiPolygon, Feature or FeatureCollection, rasterised as the service does it).
One file prints the output document as JSON. Several files, or a folder,
are pruned in a pool of worker processes with a progress bar on stderr and print one
JSON line per file: ``{"file": ..., "result": {...}}`` or ``{"file": ..., "error": ...}``.

``skelprune match A.png B.png`` prints the path similarity of two shapes' skeletons
(:func:`skelprune.match`); ``skelprune retrieve FOLDER [--top K]`` matches every shape with
every other and prints one JSON line per shape with its ``K`` closest.
"""

from __future__ import annotations

import importlib.util
import json
import os
import sys
from pathlib import Path
from typing import Annotated, Any

import typer
from typer.exceptions import TyperException

from .cli_files import PROGRESS_AFTER as PROGRESS_AFTER  # importable from here too
from .cli_files import _expand, _prune, _prune_file
from .cli_geo import register as register_geo
from .cli_match import match_command as match_command  # importable from here too
from .cli_match import register as register_match
from .cli_match import retrieve_command as retrieve_command  # importable from here too
from .cli_options import (
    AS_FILES,
    PRUNE_GROUPS,
    _CleanCommand,
    _options_or_exit,
    _usage,
    with_options,
)
from .errors import SkelpruneError
from .io.folder import FOLDER_SUFFIXES as FOLDER_SUFFIXES  # importable from here too
from .io.zarr import is_zarr
from .options import VolumeOptions

# A command imports what it uses, in its own body: `--help` and `--version` load typer and
# the option definitions only (numpy, numba and the pipeline come with `prune` and co.).

# rich_markup_mode=None: click's plain help, without importing rich (0.4 s of `--help`)
app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    rich_markup_mode=None,
    help="Parameter-free Bayesian skeleton pruning.",
)


def _print_version(value: bool) -> None:
    if value:
        from . import __version__

        typer.echo(__version__)
        raise typer.Exit()


@app.callback()
def _main(
    version: Annotated[
        bool,
        typer.Option(
            "--version", is_eager=True, callback=_print_version, help="Print the version and exit."
        ),
    ] = False,
) -> None:
    """Parameter-free Bayesian skeleton pruning."""


#: The flags that write an answer to a file, by answer.
FILE_FLAGS = {"png": "--overlay", "csv": "--csv", "graphml": "--graphml", "swc": "--swc"}


@app.command("prune", cls=_CleanCommand)
@with_options(*PRUNE_GROUPS, skip=AS_FILES)
def prune_command(
    files: Annotated[
        list[Path],
        typer.Argument(
            metavar="FILE",
            help="PNG or TIFF images, GeoJSON polygons (.geojson, .json), volumes (.npy, "
            "TIFF stacks), or folders of them (*.png, *.tif, *.tiff, *.geojson, *.npy, any "
            "case).",
        ),
    ],
    csv: Annotated[
        Path | None,
        typer.Option(
            help="Write the table (--table: branch or component rows; docs/tables.md) here "
            "as CSV (one input file only)."
        ),
    ] = None,
    overlay: Annotated[
        Path | None, typer.Option(help="Write the overlay PNG here (one input file only).")
    ] = None,
    graphml: Annotated[
        Path | None,
        typer.Option(help="Write the skeleton as GraphML here (one input file only)."),
    ] = None,
    swc: Annotated[
        Path | None,
        typer.Option(help="Write a volume's skeleton as SWC here (one input file only)."),
    ] = None,
    geojson: Annotated[
        bool,
        typer.Option(
            "--geojson",
            help="Print the skeleton as a GeoJSON FeatureCollection (lines for maps) "
            "instead of the document.",
        ),
    ] = False,
    workers: Annotated[
        int, typer.Option(help="Worker processes for several files, >= 0 (0: one a CPU core).")
    ] = 0,
    *,
    options: dict[str, Any],
) -> None:
    """Prune the skeleton of each shape (or volume) and print the result as JSON."""
    # checked once, before any file is read
    prune_opts, read, raster, volume, output = _options_or_exit(options, *PRUNE_GROUPS)
    if workers < 0:
        raise _usage(f"--workers must be >= 0 (0: one a CPU core), got {workers}")
    files_asked = {"png": overlay, "csv": csv, "graphml": graphml, "swc": swc}
    for asked, out in files_asked.items():
        if out is not None and not out.parent.is_dir():
            raise _usage(f"{FILE_FLAGS[asked]}: folder {str(out.parent)!r} does not exist")
    inputs = _expand(files)
    if not inputs:
        raise _usage("no PNG, TIFF, GeoJSON or .npy file given")
    spacing = None if volume == VolumeOptions() else volume
    if len(inputs) == 1 and not (files[0].is_dir() and not is_zarr(files[0])):
        answers = tuple(a for a, out in files_asked.items() if out is not None)
        try:
            res, answer = _prune(
                str(inputs[0]), prune_opts, read, raster, output, geojson, spacing, answers
            )
        except (SkelpruneError, OSError) as exc:
            typer.echo(f"error: {inputs[0]}: {exc}", err=True)
            raise typer.Exit(1) from None
        for warning in res.warnings:  # also in the document; here for the reader
            typer.echo(f"warning: {inputs[0]}: {warning['message']}", err=True)
        if getattr(getattr(res, "input", None), "hint", None):  # a label image, labels off
            typer.echo(f"warning: {inputs[0]}: {res.input.hint}", err=True)
        from .output.encode import encode

        for kind, out in files_asked.items():
            if out is None:
                continue
            try:
                out.write_bytes(encode(res, kind))
            except OSError as exc:
                typer.echo(f"error: {FILE_FLAGS[kind]} {out}: {exc.strerror or exc}", err=True)
                raise typer.Exit(1) from None
        sys.stdout.buffer.write(answer + b"\n")
        sys.stdout.flush()
        return
    for asked, out in files_asked.items():
        if out is not None:
            raise _usage(f"{FILE_FLAGS[asked]} takes one input file")
    from concurrent.futures import ProcessPoolExecutor

    from tqdm import tqdm

    n = workers or os.cpu_count() or 1
    failed = 0
    with ProcessPoolExecutor(max_workers=n) as pool:
        k = len(inputs)
        jobs = pool.map(
            _prune_file,
            [str(p) for p in inputs],
            [prune_opts] * k,
            [read] * k,
            [raster] * k,
            [output] * k,
            [geojson] * k,
            [spacing] * k,
        )
        for line in tqdm(jobs, total=len(inputs), file=sys.stderr, unit="shape"):
            failed += "error" in line
            sys.stdout.write(json.dumps(line) + "\n")
    if failed:
        raise typer.Exit(1)


# skelprune match A B, skelprune retrieve FOLDER: here, for --help lists the commands in
# the order they are added
register_match(app)


@app.command("prune-many", cls=_CleanCommand)
@with_options(*PRUNE_GROUPS, skip=AS_FILES)
def prune_many_command(
    inputs: Annotated[
        list[str],
        typer.Argument(
            metavar="INPUTS",
            help="PNG or TIFF masks, GeoJSON polygons, volumes (.npy, TIFF stacks), folders "
            "of them (*.png, *.tif, *.tiff, *.geojson, *.json, *.npy) or globs "
            "('masks/**/*.png', quoted).",
        ),
    ],
    out: Annotated[
        Path,
        typer.Option(
            help="Folder for the results: NAME.json an input (NAME.png with --overlay, "
            "NAME.csv with --csv), problems.jsonl."
        ),
    ],
    overlay: Annotated[
        bool, typer.Option("--overlay", help="Also write each input's overlay as NAME.png.")
    ] = False,
    csv: Annotated[
        bool,
        typer.Option("--csv", help="Also write each input's table (--table) as NAME.csv."),
    ] = False,
    jobs: Annotated[
        int | None,
        typer.Option(help="Worker processes of a local Dask cluster (default: one a core)."),
    ] = None,
    scheduler: Annotated[
        str | None,
        typer.Option(help="Run on this Dask scheduler instead (tcp://HOST:8786)."),
    ] = None,
    *,
    options: dict[str, Any],
) -> None:
    """Prune a whole data set on Dask: one NAME.json an input under --out, written as each
    finishes; failed inputs on stderr and in problems.jsonl; a second run skips what is
    written. Needs the parallel extra (dask, distributed)."""
    prune_opts, read, raster, volume, output = _options_or_exit(options, *PRUNE_GROUPS)
    if jobs is not None and scheduler is not None:
        raise _usage("give --jobs (a local cluster) or --scheduler (a running one), not both")
    if jobs is not None and jobs < 1:
        raise _usage(f"--jobs must be >= 1, got {jobs}")
    if importlib.util.find_spec("distributed") is None:
        raise _usage("prune-many needs dask: pip install 'skelprune[parallel]'")
    from .parallel.console import run_command

    code = run_command(
        inputs,
        out,
        options=prune_opts,
        read=read,
        raster=raster,
        output=output,
        volume=None if volume == VolumeOptions() else volume,
        files=tuple(a for a, asked in (("png", overlay), ("csv", csv)) if asked),
        client=scheduler,
        jobs=jobs,
    )
    if code:
        raise typer.Exit(code)


@app.command("version")
def version() -> None:
    """Print the version."""
    from . import __version__

    typer.echo(__version__)


# skelprune centerlines IN OUT: files of polygon features (the geo extra)
register_geo(app)


def main() -> None:  # console-script entry point
    """Run the command line; a usage error is one line on stderr and exit status 2."""
    try:
        code = app(standalone_mode=False)
    except typer.Abort:
        code = 130
    except TyperException as exc:  # usage errors (status 2) and the like
        message = " ".join(exc.format_message().split())  # typer's wrapped text, one line
        if message:  # (no arguments at all: the help was shown instead)
            typer.echo(f"error: {message}", err=True)
        code = getattr(exc, "exit_code", 2)
    sys.exit(code or 0)


if __name__ == "__main__":
    main()
