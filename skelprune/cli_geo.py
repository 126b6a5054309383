"""``skelprune centerlines IN OUT``: map centre lines of a file of polygon features.

Each feature is pruned on its own (:func:`skelprune.geo.centerlines`), in ``--jobs``
worker processes, with a progress bar on stderr; a feature that fails is named on stderr
with its reason, kept in the output as a row without geometry whose ``error`` says why,
and the others are written. The formats come from the file names' endings (GeoPackage,
Shapefile, GeoJSON, GeoParquet). Exit status 1 when a feature failed, 0 otherwise.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Annotated, Any

import typer

from .errors import SkelpruneError
from .options import RasterOptions

__all__ = ["register"]


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
    pixel_size: Annotated[
        float | None,
        typer.Option(help="Raster pixel size on the ground (metres for geographic data)."),
    ] = None,
    pixels_per_width: Annotated[
        float, typer.Option(help="Pixels across a polygon's narrowest part.")
    ] = RasterOptions.pixels_per_width,
    progress: Annotated[bool, typer.Option(help="A progress bar on stderr.")] = True,
) -> None:
    """Map centre lines of every polygon feature of IN, written to OUT."""
    from .geo import centerlines, log, read_frame, write_frame

    log.addHandler(logging.NullHandler())  # the failures are reported here, once
    if jobs < 1:
        typer.echo(f"error: --jobs must be >= 1, got {jobs}", err=True)
        raise typer.Exit(2)
    options: dict[str, Any] = {"pixels_per_width": pixels_per_width}
    if pixel_size is not None:
        options["pixel_size"] = pixel_size
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
            frame, jobs=jobs, progress=progress, main_path=main_path, on_feature=report, **options
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
