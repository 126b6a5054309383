"""What :func:`~skelprune.parallel.prune_many` takes, made into items: one a document
(a file, an array, an object of a label image) or a table row (a feature of a
GeoDataFrame), each with the name its result is written under.

This runs on the caller's side, before any task: it reads no shape (a label image is
the exception: its objects are found here, so that each task gets a batch of them).
"""

from __future__ import annotations

import glob
import itertools
import os
import re
from collections import Counter
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InvalidImageError, InvalidOptionError
from ..io.folder import FOLDER_SUFFIXES, folder_inputs
from ..io.zarr import is_zarr
from ..volume import is_volume

__all__ = ["FILE_SUFFIXES", "Item", "Labels", "expand"]

#: What a folder is searched for besides :data:`~skelprune.io.folder.FOLDER_SUFFIXES`
#: (a run's output folder holds its own ``.json`` documents, not in it); a file named as
#: such, or a glob's match, is taken whatever its ending.
FILE_SUFFIXES = (*FOLDER_SUFFIXES, ".json")
#: Names no input may take: the run's own files under ``out``.
RESERVED = ("problems",)
_UNSAFE = re.compile(r"[^\w.+-]+")


@dataclass(frozen=True)
class Labels:
    """A label image: every distinct non-zero value is its own object, pruned on its own
    (objects of different labels never join), one document each, ``NAME-LABEL.json``.

    Parameters
    ----------
    image : integer array, or a path to an integer PNG
        The labels (0 is the background).
    name : str, optional
        The documents' prefix (default: the file's name without its ending, or
        ``labels``).

    Examples
    --------
    >>> img = np.zeros((6, 9), np.uint16); img[1:5, 1:4] = 7; img[1:5, 4:8] = 9
    >>> [(i.name, i.source.mask.shape, i.source.origin) for i in Labels(img).items()]
    [('labels-7', (6, 5), (0, 0)), ('labels-9', (6, 6), (0, 3))]
    """

    image: Any
    name: str | None = None

    def array(self) -> np.ndarray:
        if isinstance(self.image, str | os.PathLike):
            from PIL import Image

            try:
                with Image.open(self.image) as img:
                    return np.asarray(img)
            except OSError as exc:
                raise InvalidImageError(f"cannot read {os.fspath(self.image)!r}: {exc}") from None
        return np.asarray(self.image)

    def prefix(self) -> str:
        if self.name is not None:
            return self.name
        if isinstance(self.image, str | os.PathLike):
            return Path(self.image).stem
        return "labels"

    def items(self) -> list[Item]:
        """One item an object: its pixels cropped with one background pixel around."""
        from scipy import ndimage

        img = self.array()
        if img.ndim != 2 or img.dtype.kind not in "iub":
            raise InvalidImageError(
                f"a label image must be a 2-D integer image, got {img.dtype} of shape {img.shape}"
            )
        values = np.unique(img)
        values = values[values != 0]
        # find_objects wants small consecutive labels: number the values 1..n first
        dense = np.searchsorted(values, img) + 1
        dense[img == 0] = 0
        out = []
        for value, box in zip(values, ndimage.find_objects(dense), strict=True):
            r0, c0 = max(box[0].start - 1, 0), max(box[1].start - 1, 0)
            rows = slice(r0, min(box[0].stop + 1, img.shape[0]))
            cols = slice(c0, min(box[1].stop + 1, img.shape[1]))
            crop = img[rows, cols] == value
            out.append(Item(f"{self.prefix()}-{int(value)}", LabelObject(crop, (r0, c0))))
        return out


@dataclass(frozen=True, eq=False)
class LabelObject:
    """One object of a label image: its mask, cropped, and the crop's top-left corner."""

    mask: np.ndarray
    origin: tuple[int, int]


@dataclass(frozen=True, eq=False)
class Feature:
    """One row of a table: its position, its index label and its geometry."""

    row: int
    index: Any
    geometry: Any


@dataclass(frozen=True, eq=False)
class Item:
    """One thing to prune and the name its result goes under: ``NAME.json`` for a
    document, or the table ``NAME.jsonl`` for a :class:`Feature`."""

    name: str
    source: Any

    @property
    def is_row(self) -> bool:
        return isinstance(self.source, Feature)

    @property
    def key(self) -> str:
        """Unique within a run: a document's name, or a table's name and row."""
        return f"{self.name}#{self.source.row}" if self.is_row else self.name


def _safe(name: str) -> str:
    return _UNSAFE.sub("_", name).strip("._") or "_"


def _files(pattern: str) -> list[Path]:
    """A folder's inputs (files of :data:`FILE_SUFFIXES`, Zarr stores), a glob's matches,
    or the path itself (a Zarr store: one input)."""
    path = Path(pattern)
    if path.is_dir() and not is_zarr(path):
        return folder_inputs(path, also=(".json",))
    if glob.has_magic(pattern):
        found = (Path(p) for p in glob.glob(pattern, recursive=True))
        return sorted(p for p in found if p.is_file() or is_zarr(p))
    return [path]


def _file_names(paths: list[Path]) -> list[str]:
    """Each file's name without its ending; where two would share one, the path from
    their common folder with its ending (``a/x.png`` and ``b/x.png``: ``a__x.png``)."""
    stems = [_safe(p.stem) for p in paths]
    twice = {s for s, n in Counter(stems).items() if n > 1}
    if not twice:
        return stems
    base = Path(os.path.commonpath([str(p.resolve().parent) for p in paths]))
    return [
        _safe("__".join(p.resolve().relative_to(base).parts)) if s in twice else s
        for s, p in zip(stems, paths, strict=True)
    ]


def _table_items(frame: Any, name: str) -> list[Item]:
    geometry = frame.geometry
    return [
        Item(name, Feature(row, index, geom))
        for row, (index, geom) in enumerate(zip(frame.index, geometry, strict=True))
    ]


def expand(inputs: Any, labels: bool = False) -> list[Item]:
    """The items of ``inputs``, in order, each named.

    ``inputs`` is a path, a glob (``masks/*.png``, ``**`` for sub-folders) or a folder;
    an array; a :class:`Labels`; a GeoDataFrame (each row a feature of the table
    ``NAME.jsonl``, ``NAME`` its ``name`` attribute or ``table``); a mapping of names to
    any of these; or a list of them. Arrays in a list are named by their position
    (``0000`` ...). With ``labels``, integer files and arrays are label images (a volume
    stays one input: each of its labels is pruned on its own already).

    Raises
    ------
    InvalidOptionError
        When two inputs would be written under one name, a name is reserved, or nothing
        is given.
    """
    items: list[Item] = []
    arrays: list[np.ndarray] = []
    files: list[Path] = []

    def add(x: Any, name: str | None) -> None:
        if isinstance(x, Labels):
            items.extend(x.items() if name is None else Labels(x.image, name).items())
        elif hasattr(x, "geometry") and hasattr(x, "index") and hasattr(x, "iloc"):
            items.extend(_table_items(x, name or getattr(x, "name", None) or "table"))
        elif isinstance(x, str | os.PathLike):
            found = _files(os.fspath(x))
            if labels:  # a volume's labels are its shapes already: it stays one input
                volume = [is_volume(p) for p in found]
                for p in itertools.compress(found, [not v for v in volume]):
                    items.extend(Labels(p, name).items())
                found = list(itertools.compress(found, volume))
            if name is not None and len(found) == 1:
                items.append(Item(name, os.path.abspath(found[0])))
            else:
                files.extend(found)
                # absolute: a cluster's workers need not share this process's folder
                items.extend(Item("", os.path.abspath(p)) for p in found)
        elif labels and not is_volume(x):
            items.extend(Labels(x, name).items())
        else:
            arr = np.asarray(x)
            if name is None:
                arrays.append(arr)
                items.append(Item("", arr))
            else:
                items.append(Item(name, arr))

    if isinstance(inputs, Mapping):
        for name, x in inputs.items():
            add(x, _safe(str(name)))
    elif isinstance(inputs, str | os.PathLike | np.ndarray | Labels) or hasattr(inputs, "geometry"):
        add(inputs, None)
    elif isinstance(inputs, Iterable):
        for x in inputs:
            add(x, None)
    else:
        add(inputs, None)
    # unnamed files and arrays get their names now that all of them are known
    file_names = iter(_file_names(files))
    width = max(4, len(str(len(arrays))))
    array_names = (f"{i:0{width}d}" for i in range(len(arrays)))
    items = [
        it
        if it.name
        else Item(next(file_names) if isinstance(it.source, str) else next(array_names), it.source)
        for it in items
    ]
    if not items:
        raise InvalidOptionError("no input given (no file matched, or an empty list)")
    _check_names(items)
    return items


def _check_names(items: list[Item]) -> None:
    docs = Counter(it.name for it in items if not it.is_row)
    tables = {it.name for it in items if it.is_row}
    clash = sorted({n for n, k in docs.items() if k > 1} | (set(docs) & tables))
    if clash:
        raise InvalidOptionError(
            f"several inputs would be written as {clash[0]!r}"
            + (f" (and {len(clash) - 1} more names)" if len(clash) > 1 else "")
            + ": name them (a mapping of names to inputs)"
        )
    reserved = sorted((set(docs) | tables) & set(RESERVED))
    if reserved:
        raise InvalidOptionError(f"{reserved[0]!r} is the name of the run's own file: rename it")
