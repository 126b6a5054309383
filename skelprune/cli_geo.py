"""``skelprune centerlines IN OUT``: map centre lines of a file of polygon features.

Each feature is pruned on its own (:func:`skelprune.geo.centerlines`), in ``--jobs``
worker processes, with a progress bar on stderr; a feature that fails is named on stderr
with its reason, kept in the output as a row without geometry whose ``error`` says why,
and the others are written. The formats come from the file names' endings (GeoPackage,
Shapefile, GeoJSON, GeoParquet). Exit status 1 when a feature failed, 0 otherwise.
"""

from __future__ import annotations

import logging
from dataclasses import fields
from pathlib import Path
from typing import Annotated, Any

import typer

from .cli_options import _options_or_exit, with_options
from .errors import SkelpruneError
from .options import PruneOptions, RasterOptions

__all__ = ["register"]


@with_options(PruneOptions, RasterOptions)
def centerlines_command(
    source: Annotated[Path, typer.Argument(metavar="IN", help="Polygon features (any GDAL file).")],
    target: Annotated[
        Path,
        typer.Argument(metavar="OUT", help="Lines: .gpkg, .shp, .geojson, .json or .parquet."),
    ],
    jobs: Annotated[int, typer.Option(help="Worker processes, >= 1.")] = 1,
    main_path: Annotated[
        bool, typer.Option(help="One line per connected network: its longest path.")
    ] = False,
    layer: Annotated[
        str | None, typer.Option(help="The input's layer (default: the first).")
    ] = None,
    progress: Annotated[bool, typer.Option(help="A progress bar on stderr.")] = True,
    *,
    options: dict[str, Any],
) -> None:
    """Map centre lines of every polygon feature of IN, written to OUT."""
    from .geo import centerlines, log, read_frame, write_frame

    log.addHandler(logging.NullHandler())  # the failures are reported here, once
    if jobs < 1:
        typer.echo(f"error: --jobs must be >= 1, got {jobs}", err=True)
        raise typer.Exit(2)
    prune_opts, raster = _options_or_exit(options, PruneOptions, RasterOptions)
    # the options given (their defaults are centerlines' own); the CRS by its name
    given = {
        f.name: getattr(value, f.name)
        for value in (prune_opts, raster)
        for f in fields(value)
        if getattr(value, f.name) != getattr(type(value)(), f.name)
    }
    crs = given.pop("crs", None)
    try:
        frame = read_frame(source, layer=layer)
    except Exception as exc:  # GDAL's errors are its own classes: say what and where
        typer.echo(f"error: {source}: cannot read: {exc}", err=True)
        raise typer.Exit(1) from None

    def report(index: Any, error: str | None) -> None:
        if error is not None:
            typer.echo(f"error: {source}: feature {index}: {error}", err=True)

    try:
        lines = centerlines(
            frame,
            jobs=jobs,
            progress=progress,
            main_path=main_path,
            crs=crs,
            on_feature=report,
            **given,
        )
        write_frame(lines, target)
    except SkelpruneError as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(1) from None
    failed = int(lines["error"].notna().sum())
    typer.echo(
        f"{source}: {len(frame)} features, {len(lines) - failed} lines and points, "
        f"{failed} failed -> {target}",
        err=True,
    )
    if failed:
        raise typer.Exit(1)


def register(app: typer.Typer) -> None:
    """Add the command to the command line's app."""
    app.command("centerlines")(centerlines_command)
