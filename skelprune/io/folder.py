"""What a run over a folder reads from it: one rule for the command line's folders and
:func:`skelprune.parallel.prune_many`'s."""

from __future__ import annotations

import os
from pathlib import Path

from .zarr import is_zarr

__all__ = ["FOLDER_SUFFIXES", "folder_inputs"]

#: The files a folder run reads, by ending, any case (a ``.npy`` or a multi-page TIFF is
#: a volume).
FOLDER_SUFFIXES = (".png", ".gif", ".geojson", ".tif", ".tiff", ".npy")


def folder_inputs(folder: str | os.PathLike[str], also: tuple[str, ...] = ()) -> list[Path]:
    """The inputs a folder holds, sorted by name: its files of :data:`FOLDER_SUFFIXES`
    (and of the endings ``also``) and its Zarr stores (each one input).

    Examples
    --------
    >>> import tempfile
    >>> d = Path(tempfile.mkdtemp())
    >>> for name in ("a.PNG", "b.txt", "c.npy"):
    ...     _ = (d / name).write_bytes(b"")
    >>> (d / "cells.zarr").mkdir(); (d / "notes").mkdir()
    >>> [p.name for p in folder_inputs(d)]
    ['a.PNG', 'c.npy', 'cells.zarr']
    """
    suffixes = FOLDER_SUFFIXES + also
    return sorted(
        f
        for f in Path(folder).iterdir()
        if (f.is_file() and f.suffix.lower() in suffixes) or (f.is_dir() and is_zarr(f))
    )
