"""What the commands do with the files they are given: a folder's files found, one file
pruned by the library's pipeline (its result and document, with a progress bar on a
terminal), or, in a worker process, its JSON line with the result or the error.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

from .errors import SkelpruneError
from .io.folder import folder_inputs
from .io.zarr import is_zarr
from .options import OutputOptions, PruneOptions, RasterOptions, ReadOptions, VolumeOptions


def _prune(
    path: str,
    options: PruneOptions,
    read: ReadOptions,
    raster: RasterOptions,
    output: OutputOptions,
    geojson: bool = False,
    volume: VolumeOptions | None = None,
    answers: tuple[str, ...] = (),
) -> tuple[Any, bytes]:
    """The result and its answer's bytes (the document, a polygon's in the polygon's own
    coordinates, or its GeoJSON): the library's one entry and one encoder
    (``.geojson``/``.json`` files are polygons, ``.npy`` files and TIFF stacks volumes,
    pruned with ``volume``'s spacing). ``answers``: the files also written (``png``,
    ``csv``), whose options then apply."""
    from .api import prune
    from .output.encode import encode

    answer = "geojson" if geojson else "json"
    res = prune(
        Path(path),
        options,
        read=read,
        raster=raster,
        output=output,
        volume=volume,
        answers=(answer, *answers),
        progress=_progress(path),
    )
    return res, encode(res, answer)


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
        res, answer = _prune(path, options, read, raster, output, geojson, volume)
        line = {"file": path, "result": json.loads(answer)}
        if res.warnings:
            line["warnings"] = [w["message"] for w in res.warnings]
        return line
    except (SkelpruneError, OSError) as exc:
        return {"file": path, "error": f"{type(exc).__name__}: {exc}"}


def _expand(paths: list[Path]) -> list[Path]:
    files: list[Path] = []
    for p in paths:
        if p.is_dir() and not is_zarr(p):
            files.extend(folder_inputs(p))
        else:
            files.append(p)
    return files
