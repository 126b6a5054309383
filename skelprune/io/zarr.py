"""Zarr and OME-Zarr volumes: a store's array, its checks, and its voxel size.

A Zarr store is a folder: an array (``.zarray`` in format 2, ``zarr.json`` in format 3)
or a group (``.zgroup`` or ``zarr.json``). An **OME-Zarr** image is a group whose
``multiscales`` metadata (``attrs["multiscales"]``, or ``attrs["ome"]["multiscales"]`` in
OME-Zarr 0.5) names its resolution levels: the first, full-resolution one is read, and
its voxel size is the product of the dataset's and the multiscale's ``scale``
coordinate transformations, on its spatial axes ``(z, y, x)``. Axes that are not spatial
(time, channel) must be of length 1. Reading needs the ``zarr`` extra
(``pip install 'skelprune[zarr]'``).
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from ..errors import InvalidImageError, SkelpruneError

__all__ = ["ZarrVolume", "chunk_boxes", "is_zarr", "open_zarr_volume"]

#: Files that make a folder a Zarr store.
MARKERS = (".zarray", ".zgroup", "zarr.json")


def is_zarr(source: Any) -> bool:
    """Whether ``source`` is the path of a Zarr store: a folder named ``*.zarr`` or one
    holding ``.zarray``, ``.zgroup`` or ``zarr.json``."""
    if not isinstance(source, str | os.PathLike):
        return False
    path = Path(source)
    if str(source).rstrip("/\\").lower().endswith(".zarr"):
        return True
    return path.is_dir() and any((path / m).exists() for m in MARKERS)


class ZarrVolume:
    """A Zarr array read as a volume: its ``(z, y, x)`` array, still on disk.

    Attributes
    ----------
    array : zarr.Array
        The full-resolution array (all axes).
    shape : (Z, Y, X)
    index : tuple
        What selects ``(z, y, x)`` from :attr:`array` (0 on the axes of length 1 that
        are not spatial).
    spacing : (dz, dy, dx) or None
        From OME-Zarr's ``scale`` metadata; ``None`` for a plain array.
    chunks : (cz, cy, cx)
    dtype : numpy.dtype
    """

    def __init__(self, array: Any, index: tuple[Any, ...], spacing: Any) -> None:
        self.array = array
        self.index = index
        keep = [i for i, sel in enumerate(index) if isinstance(sel, slice)]
        self.shape = tuple(int(array.shape[i]) for i in keep)
        self.chunks = tuple(int(array.chunks[i]) for i in keep)
        self.dtype = array.dtype
        self.spacing = spacing

    def read(self, box: tuple[slice, ...] | None = None) -> Any:
        """The volume, or the part ``box`` (slices along ``z, y, x``) of it, as a numpy
        array."""
        import numpy as np

        if box is None:
            return np.asarray(self.array[self.index])
        it = iter(box)
        sel = tuple(next(it) if isinstance(s, slice) else s for s in self.index)
        return np.asarray(self.array[sel])


def open_zarr_volume(path: str | os.PathLike[str]) -> ZarrVolume:
    """The volume of a Zarr array or OME-Zarr image, checked but not read.

    Raises
    ------
    InvalidImageError
        Not a Zarr store, a group that is not OME-Zarr, not three spatial dimensions,
        a dtype other than booleans or integers, or bad ``multiscales`` metadata.
    SkelpruneError
        The ``zarr`` package is not installed.
    """
    try:
        import zarr
    except ImportError:  # the optional extra
        raise SkelpruneError(
            "reading a Zarr store needs the zarr package: pip install 'skelprune[zarr]'"
        ) from None
    shown = os.fspath(path)
    folder = Path(path)
    if not folder.is_dir():
        raise InvalidImageError(f"{shown!r} is not a Zarr store: there is no such folder")
    if not any((folder / m).exists() for m in MARKERS):
        raise InvalidImageError(
            f"{shown!r} is not a Zarr store: it holds no .zarray, .zgroup or zarr.json"
        )
    try:
        node = zarr.open(str(folder), mode="r")
    except Exception as exc:  # zarr raises many kinds on broken metadata
        raise InvalidImageError(f"cannot open {shown!r} as a Zarr store: {exc}") from None
    spacing = None
    axes: list[str] | None = None
    if isinstance(node, zarr.Group):
        array, spacing, axes = _multiscale(node, shown)
    else:
        array = node
    index = _spatial_index(array.shape, axes, shown)
    dtype = array.dtype
    if getattr(dtype, "kind", "") not in "biu":
        raise InvalidImageError(
            f"the Zarr array {shown!r} holds {dtype} values; a volume holds booleans or "
            "integer labels (bool, int8-int64, uint8-uint64)"
        )
    return ZarrVolume(array, index, spacing)


def _multiscale(group: Any, shown: str) -> tuple[Any, Any, list[str] | None]:
    """An OME-Zarr group's full-resolution array, its spacing and axis names."""
    attrs = dict(group.attrs)
    meta = attrs.get("multiscales") or (attrs.get("ome") or {}).get("multiscales")
    if not meta:
        raise InvalidImageError(
            f"{shown!r} is a Zarr group without OME-Zarr multiscales metadata: give the "
            "path of the array inside it"
        )
    try:
        ms = meta[0]
        dataset = ms["datasets"][0]
        array = group[dataset["path"]]
        axes = [a["name"] if isinstance(a, dict) else str(a) for a in ms.get("axes", [])]
        scale = [1.0] * len(array.shape)
        for transforms in (
            dataset.get("coordinateTransformations"),
            ms.get("coordinateTransformations"),
        ):
            for t in transforms or []:
                if t.get("type") == "scale":
                    scale = [a * float(b) for a, b in zip(scale, t["scale"], strict=True)]
    except (KeyError, IndexError, TypeError, ValueError) as exc:
        raise InvalidImageError(
            f"cannot read {shown!r}'s OME-Zarr multiscales metadata: {exc!r}"
        ) from None
    if len(scale) != len(array.shape):
        raise InvalidImageError(
            f"{shown!r}: the OME-Zarr scale has {len(scale)} values for {len(array.shape)} axes"
        )
    index = _spatial_index(array.shape, axes or None, shown)
    spatial = [s for s, sel in zip(scale, index, strict=True) if isinstance(sel, slice)]
    if not all(math.isfinite(s) and s > 0 for s in spatial):
        raise InvalidImageError(f"{shown!r}: the OME-Zarr scale {spatial} is not three sizes > 0")
    return array, tuple(spatial), axes or None


def _spatial_index(shape: tuple[int, ...], axes: list[str] | None, shown: str) -> tuple[Any, ...]:
    """Slices on the spatial axes, 0 on the others (which must be of length 1)."""
    if axes is None or len(axes) != len(shape):
        spatial = [True] * len(shape)
    else:
        spatial = [a.lower() in ("z", "y", "x") for a in axes]
    for keep, n in zip(spatial, shape, strict=True):
        if not keep and n != 1:
            raise InvalidImageError(
                f"{shown!r} has axes {axes} of shape {tuple(shape)}: a volume's axes "
                "other than z, y and x must be of length 1"
            )
    if sum(spatial) != 3:
        raise InvalidImageError(
            f"a volume is a 3-D array; the Zarr array {shown!r} has {sum(spatial)} "
            f"spatial dimensions (shape {tuple(shape)})"
        )
    return tuple(slice(None) if keep else 0 for keep in spatial)


def chunk_boxes(volume: ZarrVolume, halo: int = 0) -> Iterator[tuple[slice, slice, slice]]:
    """The boxes of the array's chunks along ``(z, y, x)``, each grown by ``halo``
    voxels (within the volume), in raster order."""
    nz, ny, nx = volume.shape
    cz, cy, cx = volume.chunks
    for z in range(0, nz, cz):
        for y in range(0, ny, cy):
            for x in range(0, nx, cx):
                yield (
                    slice(max(z - halo, 0), min(z + cz + halo, nz)),
                    slice(max(y - halo, 0), min(y + cy + halo, ny)),
                    slice(max(x - halo, 0), min(x + cx + halo, nx)),
                )
