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

import enum
import importlib.util
import json
import os
import sys
from collections.abc import Callable
from dataclasses import fields
from pathlib import Path
from typing import Annotated, Any

import typer
import typer.core
from typer.exceptions import TyperException

from .cli_geo import register as register_geo
from .errors import SkelpruneError
from .options import (
    CHOICES,
    COARSE,
    FOREGROUND_RULES,
    METHODS,
    SCOPES,
    OutputOptions,
    PruneOptions,
    RasterOptions,
    ReadOptions,
    VolumeOptions,
    option_fields,
)

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


#: What a folder is searched for (any case).
FOLDER_SUFFIXES = (".png", ".geojson", ".tif", ".tiff", ".npy")


def _prune(
    path: str,
    options: PruneOptions,
    read: ReadOptions,
    raster: RasterOptions,
    output: OutputOptions,
    geojson: bool = False,
    volume: VolumeOptions | None = None,
) -> tuple[Any, dict[str, Any]]:
    """The result and its document (a polygon's in the polygon's own coordinates), or its
    GeoJSON: the library's one pipeline (``.geojson``/``.json`` files are polygons,
    ``.npy`` files volumes, pruned with ``volume``'s spacing)."""
    from .api import prune
    from .volume import is_volume

    if is_volume(path):
        res: Any = prune(Path(path), options, output=output, volume=volume or VolumeOptions())
    else:
        res = prune(
            Path(path), options, read=read, raster=raster, output=output, progress=_progress(path)
        )
    return res, res.to_geojson() if geojson else res.to_dict()


#: A run shows its progress on a terminal once it has taken this long (s): a large image.
PROGRESS_AFTER = 1.0


def _progress(path: str) -> Any:
    """``progress(done, total)`` drawing a bar on stderr when it is a terminal and the
    run has taken over :data:`PROGRESS_AFTER` seconds (None otherwise: nothing shown)."""
    if not sys.stderr.isatty():
        return None
    import time

    start = time.monotonic()
    shown = [False]

    def show(done: int, total: int) -> None:
        if time.monotonic() - start < PROGRESS_AFTER and not shown[0]:
            return
        shown[0] = True
        filled = 30 * done // max(total, 1)
        sys.stderr.write(
            f"\r{Path(path).name}: [{'#' * filled}{'.' * (30 - filled)}] {done}/{total}"
        )
        if done == total:
            sys.stderr.write("\n")
        sys.stderr.flush()

    return show


def _prune_file(
    path: str,
    options: PruneOptions,
    read: ReadOptions,
    raster: RasterOptions,
    output: OutputOptions,
    geojson: bool = False,
    volume: VolumeOptions | None = None,
) -> dict[str, Any]:
    try:
        res, doc = _prune(path, options, read, raster, output, geojson, volume)
        line = {"file": path, "result": doc}
        if res.warnings:
            line["warnings"] = [w["message"] for w in res.warnings]
        return line
    except (SkelpruneError, OSError) as exc:
        return {"file": path, "error": f"{type(exc).__name__}: {exc}"}


def _expand(paths: list[Path]) -> list[Path]:
    files: list[Path] = []
    for p in paths:
        if p.is_dir():  # shape.PNG counts as much as shape.png
            files.extend(
                sorted(
                    f for f in p.iterdir() if f.suffix.lower() in FOLDER_SUFFIXES and f.is_file()
                )
            )
        else:
            files.append(p)
    return files


def _usage(message: str) -> typer.Exit:
    """A usage error: one line on stderr, exit status 2."""
    typer.echo(f"error: {message}", err=True)
    return typer.Exit(2)


def _no_type(ctx: Any) -> str:
    """A parameter's type as --help shows it: not at all."""
    return ""


class _CleanCommand(typer.core.TyperCommand):
    """``--help`` without typer's type labels where they say nothing: none for flags and
    for the file arguments (``<list[Path]>``), ``FILE...`` in the usage line."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        # typer has no setting for these: each parameter's own methods are replaced
        for param in self.params:
            if isinstance(param, typer.core.TyperArgument):
                setattr(param, "display_type", _no_type)  # noqa: B010
                name = f"{param.metavar or (param.name or '').upper()}..."
                setattr(param, "_usage_display_name", lambda name=name: name)  # noqa: B010
            elif getattr(param, "is_flag", False):
                setattr(param, "display_type", _no_type)  # noqa: B010

    def get_help_option(self, ctx: Any) -> Any:
        option = super().get_help_option(ctx)
        if option is not None:
            setattr(option, "display_type", _no_type)  # noqa: B010
        return option


HELP = {
    name: text
    for name, _, text, _ in option_fields(
        PruneOptions, OutputOptions, ReadOptions, RasterOptions, VolumeOptions
    )
}


def _geojson_only(name: str) -> str:
    return "GeoJSON input: " + HELP[name][0].lower() + HELP[name][1:]


# the choices as typer shows them (it lists an Enum's values in --help); made from the
# tuples of skelprune.options, where each is defined once, which mypy cannot read
Method = enum.Enum("Method", {name: name for name in METHODS}, type=str)  # type: ignore[misc]
Coarse = enum.Enum("Coarse", {name: name for name in COARSE}, type=str)  # type: ignore[misc]
Rule = enum.Enum("Rule", {n: n for n in FOREGROUND_RULES}, type=str)  # type: ignore[misc]
# the options every pruning command takes, declared once
BetaOption = Annotated[float, typer.Option(help=HELP["beta"])]
MethodOption = Annotated[Method, typer.Option(help=HELP["method"])]
CoarseOption = Annotated[Coarse, typer.Option(help=HELP["coarse"])]
ThresholdOption = Annotated[float | None, typer.Option(help=HELP["dce_threshold"])]
MarginOption = Annotated[float | None, typer.Option(help=HELP["min_margin"])]
TrimOption = Annotated[bool, typer.Option(help=HELP["trim"])]
Choice = enum.Enum("Choice", {name: name for name in CHOICES}, type=str)  # type: ignore[misc]
ChoiceOption = Annotated[Choice, typer.Option(help=HELP["choice"])]
ForegroundOption = Annotated[Rule, typer.Option(help=HELP["foreground"])]
LabelsOption = Annotated[bool, typer.Option(help=HELP["labels"])]
FillHolesOption = Annotated[int, typer.Option(help=HELP["fill_holes"])]
MinAreaOption = Annotated[int, typer.Option(help=HELP["min_area"])]
CurveOption = Annotated[bool, typer.Option(help=HELP["curve"])]
SequenceOption = Annotated[bool, typer.Option(help=HELP["sequence"])]
PixelSizeOption = Annotated[float | None, typer.Option(help=HELP["pixel_size"])]
LongestSideOption = Annotated[int | None, typer.Option(help=_geojson_only("longest_side"))]
PixelsPerWidthOption = Annotated[float, typer.Option(help=_geojson_only("pixels_per_width"))]
PixelBudgetOption = Annotated[int, typer.Option(help=_geojson_only("pixel_budget"))]
RepairOption = Annotated[bool, typer.Option(help=_geojson_only("repair"))]
CrsOption = Annotated[str | None, typer.Option(help=_geojson_only("crs"))]
SimplifyOption = Annotated[float, typer.Option(help=HELP["simplify"])]
CutEndsOption = Annotated[bool, typer.Option(help=HELP["cut_ends"])]
OverlayScaleOption = Annotated[int | None, typer.Option(help=HELP["overlay_scale"])]
Scope = enum.Enum("Scope", {name: name for name in SCOPES}, type=str)  # type: ignore[misc]
ScopeOption = Annotated[Scope, typer.Option(help=HELP["scope"])]
WindowOption = Annotated[int | None, typer.Option(help=HELP["window"])]


@app.command("prune", cls=_CleanCommand)
def prune_command(
    files: Annotated[
        list[Path],
        typer.Argument(
            metavar="FILE",
            help="PNG or TIFF images, GeoJSON polygons (.geojson, .json), or folders "
            "of them (*.png, *.tif, *.tiff, *.geojson, any case).",
        ),
    ],
    beta: BetaOption = PruneOptions.beta,
    method: MethodOption = Method(PruneOptions.method),
    coarse: CoarseOption = Coarse("dce"),
    dce_threshold: ThresholdOption = None,
    min_margin: MarginOption = None,
    choice: ChoiceOption = Choice(PruneOptions.choice),
    trim: TrimOption = PruneOptions.trim,
    scope: ScopeOption = Scope(PruneOptions.scope),
    window: WindowOption = None,
    foreground: ForegroundOption = Rule(ReadOptions.foreground),
    labels: LabelsOption = ReadOptions.labels,
    fill_holes: FillHolesOption = ReadOptions.fill_holes,
    min_area: MinAreaOption = ReadOptions.min_area,
    csv: Annotated[
        Path | None,
        typer.Option(
            help="Write the branch table (docs/tables.md) here as CSV (one input file only)."
        ),
    ] = None,
    overlay: Annotated[
        Path | None, typer.Option(help="Write the overlay PNG here (one input file only).")
    ] = None,
    overlay_scale: OverlayScaleOption = None,
    overlay_legend: Annotated[
        bool, typer.Option(help=HELP["overlay_legend"])
    ] = OutputOptions.overlay_legend,
    curve: CurveOption = OutputOptions.curve,
    sequence: SequenceOption = OutputOptions.sequence,
    pixel_size: PixelSizeOption = None,
    longest_side: LongestSideOption = None,
    pixels_per_width: PixelsPerWidthOption = RasterOptions.pixels_per_width,
    pixel_budget: PixelBudgetOption = RasterOptions.pixel_budget,
    repair: RepairOption = RasterOptions.repair,
    crs: CrsOption = None,
    geojson: Annotated[
        bool,
        typer.Option(
            "--geojson",
            help="Print the skeleton as a GeoJSON FeatureCollection (lines for maps) "
            "instead of the document.",
        ),
    ] = False,
    simplify: SimplifyOption = OutputOptions.simplify,
    cut_ends: CutEndsOption = OutputOptions.cut_ends,
    workers: Annotated[
        int, typer.Option(help="Worker processes for several files, >= 0 (0: one a CPU core).")
    ] = 0,
    spacing: Annotated[
        str | None, typer.Option(help=HELP["spacing"] + " Written DZ,DY,DX.")
    ] = None,
) -> None:
    """Prune the skeleton of each shape (or volume, from a .npy file) and print the result
    as JSON."""
    # checked once, before any file is read; the JSON document holds no overlay image
    options, read, raster, output = _options_or_exit(
        {**locals(), "overlay": False, "csv": None},
        PruneOptions,
        ReadOptions,
        RasterOptions,
        OutputOptions,
    )
    volume = _volume_or_exit(spacing)
    if workers < 0:
        raise _usage(f"--workers must be >= 0 (0: one a CPU core), got {workers}")
    for flag, out in (("--overlay", overlay), ("--csv", csv)):
        if out is not None and not out.parent.is_dir():
            raise _usage(f"{flag}: folder {str(out.parent)!r} does not exist")
    inputs = _expand(files)
    if not inputs:
        raise _usage("no PNG, TIFF, GeoJSON or .npy file given")
    if len(inputs) == 1 and not files[0].is_dir():
        try:
            res, doc = _prune(str(inputs[0]), options, read, raster, output, geojson, volume)
        except (SkelpruneError, OSError) as exc:
            typer.echo(f"error: {inputs[0]}: {exc}", err=True)
            raise typer.Exit(1) from None
        for warning in res.warnings:  # also in the document; here for the reader
            typer.echo(f"warning: {inputs[0]}: {warning['message']}", err=True)
        written: tuple[tuple[str, Path | None, Callable[[], bytes]], ...] = (
            ("--overlay", overlay, res.overlay_png),
            ("--csv", csv, lambda: res.to_csv().encode()),
        )
        for flag, out, what in written:
            if out is None:
                continue
            try:
                out.write_bytes(what())
            except OSError as exc:
                typer.echo(f"error: {flag} {out}: {exc.strerror or exc}", err=True)
                raise typer.Exit(1) from None
        json.dump(doc, sys.stdout)
        sys.stdout.write("\n")
        return
    if overlay is not None or csv is not None:
        raise _usage(f"{'--overlay' if overlay is not None else '--csv'} takes one input file")
    from concurrent.futures import ProcessPoolExecutor

    from tqdm import tqdm

    n = workers or os.cpu_count() or 1
    failed = 0
    with ProcessPoolExecutor(max_workers=n) as pool:
        k = len(inputs)
        jobs = pool.map(
            _prune_file,
            [str(p) for p in inputs],
            [options] * k,
            [read] * k,
            [raster] * k,
            [output] * k,
            [geojson] * k,
            [volume] * k,
        )
        for line in tqdm(jobs, total=len(inputs), file=sys.stderr, unit="shape"):
            failed += "error" in line
            sys.stdout.write(json.dumps(line) + "\n")
    if failed:
        raise typer.Exit(1)


def _describe_file(path: str, options: PruneOptions, read: ReadOptions) -> Any:
    from .matching import describe

    try:
        return describe(_prune(path, options, read, RasterOptions(), OutputOptions())[0])
    except (SkelpruneError, OSError) as exc:
        return f"{type(exc).__name__}: {exc}"


def _volume_or_exit(spacing: str | None) -> VolumeOptions:
    """``--spacing DZ,DY,DX`` as volume options (checked by their class)."""
    if spacing is None:
        return VolumeOptions()
    try:
        values = tuple(float(v) for v in spacing.split(","))
    except ValueError:
        raise _usage(f"--spacing is three numbers DZ,DY,DX, got {spacing!r}") from None
    try:
        return VolumeOptions(spacing=values)  # type: ignore[arg-type]
    except SkelpruneError as exc:
        raise _usage(str(exc)) from None


def _options_or_exit(params: dict[str, Any], *groups: type) -> tuple[Any, ...]:
    """One value of each options class, from the command's parameters of its fields'
    names (a choice's Enum read as its value): the classes check them, once."""
    values = {k: v.value if isinstance(v, enum.Enum) else v for k, v in params.items()}
    try:
        return tuple(
            group(**{f.name: values[f.name] for f in fields(group) if f.name in values})
            for group in groups
        )
    except SkelpruneError as exc:
        raise _usage(str(exc)) from None


@app.command("match")
def match_command(
    a: Annotated[Path, typer.Argument(help="PNG mask a.")],
    b: Annotated[Path, typer.Argument(help="PNG mask b.")],
    beta: BetaOption = PruneOptions.beta,
    method: MethodOption = Method(PruneOptions.method),
    coarse: CoarseOption = Coarse("dce"),
    dce_threshold: ThresholdOption = None,
    min_margin: MarginOption = None,
    choice: ChoiceOption = Choice(PruneOptions.choice),
    trim: TrimOption = PruneOptions.trim,
    foreground: ForegroundOption = Rule(ReadOptions.foreground),
) -> None:
    """Match the skeletons of two shapes (path similarity) and print distance and
    endpoint correspondence as JSON."""
    from .matching import match

    options, read = _options_or_exit(locals(), PruneOptions, ReadOptions)
    try:
        shapes = [
            _prune(str(p), options, read, RasterOptions(), OutputOptions())[0] for p in (a, b)
        ]
        res = match(*shapes)
    except (SkelpruneError, OSError) as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(1) from None
    json.dump(res.to_dict(), sys.stdout)
    sys.stdout.write("\n")


@app.command("retrieve")
def retrieve_command(
    folder: Annotated[list[Path], typer.Argument(help="Folders of PNG masks, or PNG files.")],
    top: Annotated[int, typer.Option(min=1, help="Closest shapes listed per shape.")] = 10,
    beta: BetaOption = PruneOptions.beta,
    method: MethodOption = Method(PruneOptions.method),
    coarse: CoarseOption = Coarse("dce"),
    dce_threshold: ThresholdOption = None,
    min_margin: MarginOption = None,
    choice: ChoiceOption = Choice(PruneOptions.choice),
    trim: TrimOption = PruneOptions.trim,
    foreground: ForegroundOption = Rule(ReadOptions.foreground),
    workers: Annotated[int, typer.Option(help="Worker processes (0: one a core).")] = 0,
) -> None:
    """Match every shape with every other and print, per shape, its closest ones as JSON
    lines: {"file", "top": [{"file", "distance"}, ...]} (or {"file", "error"})."""
    from concurrent.futures import ProcessPoolExecutor

    import numpy as np
    from tqdm import tqdm

    from .matching import distance_matrix

    options, read = _options_or_exit(locals(), PruneOptions, ReadOptions)
    inputs = _expand(folder)
    if not inputs:
        typer.echo("error: no PNG file given", err=True)
        raise typer.Exit(2)
    n = workers or os.cpu_count() or 1
    k = len(inputs)
    with ProcessPoolExecutor(max_workers=n) as pool:
        described = list(
            tqdm(
                pool.map(_describe_file, [str(p) for p in inputs], [options] * k, [read] * k),
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


@app.command("prune-many", cls=_CleanCommand)
def prune_many_command(
    inputs: Annotated[
        list[str],
        typer.Argument(
            metavar="INPUTS",
            help="PNG masks or GeoJSON polygons, folders of them (*.png, *.geojson, *.json) "
            "or globs ('masks/**/*.png', quoted).",
        ),
    ],
    out: Annotated[
        Path, typer.Option(help="Folder for the results: NAME.json an input, problems.jsonl.")
    ],
    jobs: Annotated[
        int | None,
        typer.Option(help="Worker processes of a local Dask cluster (default: one a core)."),
    ] = None,
    scheduler: Annotated[
        str | None,
        typer.Option(help="Run on this Dask scheduler instead (tcp://HOST:8786)."),
    ] = None,
    beta: BetaOption = PruneOptions.beta,
    method: MethodOption = Method(PruneOptions.method),
    coarse: CoarseOption = Coarse("dce"),
    dce_threshold: ThresholdOption = None,
    min_margin: MarginOption = None,
    choice: ChoiceOption = Choice(PruneOptions.choice),
    trim: TrimOption = PruneOptions.trim,
    scope: ScopeOption = Scope(PruneOptions.scope),
    window: WindowOption = None,
    fill_holes: FillHolesOption = ReadOptions.fill_holes,
    min_area: MinAreaOption = ReadOptions.min_area,
    foreground: ForegroundOption = Rule(ReadOptions.foreground),
    curve: CurveOption = OutputOptions.curve,
    sequence: SequenceOption = OutputOptions.sequence,
    pixel_size: PixelSizeOption = None,
    longest_side: LongestSideOption = None,
    pixels_per_width: PixelsPerWidthOption = RasterOptions.pixels_per_width,
    pixel_budget: PixelBudgetOption = RasterOptions.pixel_budget,
    repair: RepairOption = RasterOptions.repair,
) -> None:
    """Prune a whole data set on Dask: one NAME.json an input under --out, written as each
    finishes; failed inputs on stderr and in problems.jsonl; a second run skips what is
    written. Needs the parallel extra (dask, distributed)."""
    options, read, raster, output = _options_or_exit(
        locals(), PruneOptions, ReadOptions, RasterOptions, OutputOptions
    )
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
        options=options,
        read=read,
        raster=raster,
        output=output,
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
