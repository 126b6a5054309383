"""Pruning volumes: a 3-D array or ``.npy`` file to a pruned curve skeleton per component.

The same pruning as for images (docs/algorithm.md), through the grid interface of
:mod:`skelprune.pruning.grid`: the curve skeleton of each 26-connected component
(:mod:`skelprune.grid3d`), end branches removed in the order that trades length against
lost volume (limbs kept), the answer chosen by ``argmin λ``, its end branches of margin
below ``min_margin`` dropped and its tips cut (``trim``). What the image pipeline has
and a volume does not (docs/volumes.md): the coarse DCE stage and ``method="dce"`` (both
follow a contour), and the noise-floor choice.
"""

from __future__ import annotations

import io
import math
import os
from collections.abc import Callable
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

import numpy as np

from .errors import (
    EmptyMaskError,
    ImageTooLargeError,
    InvalidImageError,
    InvalidOptionError,
    SkelpruneError,
)
from .options import OutputOptions, PruneOptions, VolumeOptions

if TYPE_CHECKING:  # the volume grid is imported when a volume is pruned, not before
    from .output.volume import VolumeResult
    from .volume_parallel import Progress

__all__ = [
    "IMAGE_CHANNELS",
    "MAX_VOLUME_VOXELS",
    "check_volume_size",
    "is_volume",
    "prune_volume",
    "prune_volume_labels",
    "read_volume",
    "volume_components",
]


#: The most channels an image array has (RGBA): a 3-D array whose last axis is no longer
#: is an image, read as one, unless volume options are given.
IMAGE_CHANNELS = 4


#: The most voxels a volume read from a file may declare (a 1024³ stack): checked from
#: the header, before anything is decoded.
MAX_VOLUME_VOXELS = 1 << 30
TIFF_SUFFIXES = (".tif", ".tiff")
#: The first bytes of a ``.npy`` file.
NPY_MAGIC = b"\x93NUMPY"


def is_volume(source: Any, spacing_given: bool = False) -> bool:
    """Whether ``source`` is a volume: the path of a ``.npy`` file, of a multi-page TIFF
    (a stack) or of a Zarr store (:mod:`skelprune.io.zarr`), or a 3-D array whose last
    axis is longer than an image's channels (:data:`IMAGE_CHANNELS`), or any 3-D array
    when ``spacing_given`` (a ``(Z, Y, X)`` volume with ``X ≤ 4`` is read as a volume
    when ``spacing`` is given)."""
    if isinstance(source, np.ndarray):
        return source.ndim == 3 and (spacing_given or source.shape[-1] > IMAGE_CHANNELS)
    if isinstance(source, bytes | bytearray | memoryview):
        from .io.tiff import tiff_pages

        head = bytes(source[:6])
        return head == NPY_MAGIC or (head[:2] in (b"II", b"MM") and tiff_pages(bytes(source)) > 1)
    if not isinstance(source, str | os.PathLike):
        return False
    from .io.zarr import is_zarr

    if is_zarr(source):
        return True
    name = str(source).lower()
    if name.endswith(".npy"):
        return True
    if name.endswith(TIFF_SUFFIXES):
        try:
            return _stack_pages(source) > 1
        except Exception:  # not a readable TIFF: the image reader says what is wrong
            return False
    return False


def _stack_pages(path: Any) -> int:
    """Pages of a TIFF, or slices of a single 3-D page (the header only, read by the
    bounded walker)."""
    from .io.tiff import mapped, tiff_pages

    with open(path, "rb") as f, mapped(f) as data:
        return tiff_pages(data)


def _read_stack(path: Any, max_voxels: int) -> np.ndarray:
    """A multi-page TIFF as a ``(pages, height, width)`` array: one-channel pages of one
    size, at most ``max_voxels`` voxels by the header, before decoding."""
    import tifffile

    from .io.tiff import mapped, stack_layouts

    try:
        with open(path, "rb") as f, mapped(f) as data:
            stack_layouts(data)  # the page chain and tags, bounded, before tifffile
        with tifffile.TiffFile(path) as tif:
            series = tif.series[0]
            shape = tuple(int(v) for v in series.shape)
            if len(shape) != 3:
                raise InvalidImageError(
                    f"a TIFF stack holds one-channel pages of one size; this one reads as "
                    f"{'x'.join(map(str, shape))}"
                )
            _within_limit(shape, max_voxels)
            return np.asarray(series.asarray())
    except SkelpruneError:
        raise
    except Exception as exc:  # tifffile raises many kinds on a broken file
        raise InvalidImageError(f"cannot read {os.fspath(path)!r} as a TIFF stack: {exc}") from None


def check_volume_size(data: bytes, max_voxels: int | None) -> tuple[int, int, int]:
    """A ``.npy`` or TIFF stack's ``(depth, height, width)`` from its header; refuses
    more than ``max_voxels`` voxels before anything is decoded (what the service checks
    before it queues a volume).

    >>> buf = io.BytesIO(); np.save(buf, np.zeros((4, 5, 6), bool))
    >>> check_volume_size(buf.getvalue(), 1000)
    (4, 5, 6)
    """
    data = bytes(data)
    if data[:6] == NPY_MAGIC:
        shape, _, _ = _npy_header(io.BytesIO(data))
        if len(shape) != 3:
            raise InvalidImageError(
                f"a volume is a 3-D array; this one has {len(shape)} dimensions"
            )
        dims = (int(shape[0]), int(shape[1]), int(shape[2]))
    else:
        from .io.tiff import is_tiff, stack_layouts

        if not is_tiff(data):
            raise InvalidImageError("not a volume: neither a .npy file nor a multi-page TIFF")
        pages = stack_layouts(data)
        if len(pages) < 2:
            raise InvalidImageError("not a volume: a TIFF of one page is an image")
        dims = (len(pages), pages[0].height, pages[0].width)
    if max_voxels is not None:
        _within_limit(dims, max_voxels)
    return dims


def _npy_header(f: IO[bytes]) -> tuple[tuple[int, ...], bool, np.dtype[Any]]:
    """A ``.npy`` header: shape, Fortran order, dtype, every field checked: the shape a
    tuple of whole numbers of at least 1 (not booleans), the dtype booleans or integers
    of a plain, non-empty type (no objects, sub-arrays, records, times).

    Raises
    ------
    InvalidImageError
        Naming the field that is not read.
    """
    try:
        version = np.lib.format.read_magic(f)
        read_header = (
            np.lib.format.read_array_header_1_0
            if version == (1, 0)
            else np.lib.format.read_array_header_2_0
        )
        shape, fortran, dtype = read_header(f)
    except Exception:  # numpy's messages may quote the parser's objects
        raise InvalidImageError(
            "cannot read the .npy header: not a .npy header dictionary of 'descr', "
            "'fortran_order' and 'shape' (write it with numpy.save)"
        ) from None
    if not isinstance(shape, tuple) or any(type(d) is not int for d in shape):
        raise InvalidImageError(
            f"the .npy header's shape {_shown(shape)} is not a tuple of whole numbers"
        )
    if any(d < 1 for d in shape):
        raise InvalidImageError(
            f"the .npy header's shape {_shown(shape)} has a dimension below 1; a "
            "volume's dimensions are 1 or more"
        )
    if dtype.hasobject:
        raise InvalidImageError("a .npy of Python objects is not read (no pickles)")
    if dtype.subdtype is not None or dtype.names is not None or dtype.kind not in "biu":
        raise InvalidImageError(
            f"the .npy header's dtype {_shown(dtype.str)} is not read: a volume holds "
            "booleans or integer labels (bool, int8-int64, uint8-uint64)"
        )
    return shape, bool(fortran), dtype


def _shown(value: Any) -> str:
    """A header field as a message quotes it (short)."""
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def _npy_bytes(data: bytes, max_voxels: int) -> np.ndarray:
    """A ``.npy`` file's array from its bytes: the header checked (no pickles, the size
    within ``max_voxels`` and within the bytes given) before the array is made."""
    f = io.BytesIO(data)
    shape, fortran, dtype = _npy_header(f)
    voxels = _within_limit(shape, max_voxels)
    if len(data) - f.tell() < voxels * dtype.itemsize:
        raise InvalidImageError(
            f"truncated .npy: {'×'.join(map(str, shape))} {dtype} needs "
            f"{voxels * dtype.itemsize} bytes, {len(data) - f.tell()} follow the header"
        )
    arr = np.frombuffer(data, dtype, voxels, offset=f.tell())
    return arr.reshape(shape, order="F" if fortran else "C")


def _within_limit(shape: tuple[int, ...], max_voxels: int) -> int:
    """The voxels of a volume of ``shape`` (from an array or a file's header), refused
    past ``max_voxels``: the one check of a volume's size.

    Raises
    ------
    ImageTooLargeError
        More voxels than ``max_voxels``.
    """
    voxels = math.prod(int(d) for d in shape)  # Python integers: no wrap-around
    if voxels > max_voxels:
        raise ImageTooLargeError(
            f"the volume has {voxels} voxels ({_dims(shape)}), the limit is {max_voxels}"
        )
    return voxels


def _dims(shape: tuple[int, ...]) -> str:
    text = "×".join(map(str, shape))
    return text if len(text) <= 80 else text[:77] + "..."


def _read_npy(path: str | os.PathLike[str], max_voxels: int) -> np.ndarray:
    """A ``.npy`` file's array, mapped rather than read: its header is checked (no
    pickles, at most ``max_voxels`` voxels) before the file is mapped, so a header
    promising too many voxels is refused whatever follows it."""
    try:
        with open(path, "rb") as f:
            shape, _, _ = _npy_header(f)
    except OSError as exc:
        raise InvalidImageError(f"cannot read {os.fspath(path)!r} as a .npy array: {exc}") from None
    _within_limit(shape, max_voxels)
    try:
        return np.load(Path(path), mmap_mode="r", allow_pickle=False)
    except (OSError, ValueError) as exc:  # a body shorter than its header says
        raise InvalidImageError(f"cannot read {os.fspath(path)!r} as a .npy array: {exc}") from None


def _is_zarr(source: Any) -> bool:
    from .io.zarr import is_zarr

    return is_zarr(source)


def read_zarr(
    source: str | os.PathLike[str], max_voxels: int = MAX_VOLUME_VOXELS
) -> tuple[np.ndarray, tuple[float, float, float] | None]:
    """A Zarr array or OME-Zarr image as an array, refused past ``max_voxels`` voxels
    from its metadata (before any chunk is read), with its OME-Zarr voxel size (``None``
    for a plain array)."""
    from .io.zarr import open_zarr_volume

    store = open_zarr_volume(source)
    _within_limit(store.shape, max_voxels)
    return store.read(), store.spacing


def read_volume(source: Any, max_voxels: int | None = None) -> np.ndarray:
    """A volume as an array: ``source`` itself, a ``.npy`` file (no pickles), a
    multi-page TIFF (its pages along ``z``) or a Zarr / OME-Zarr store (the
    full-resolution level), as a path or, but for Zarr, as the file's bytes; files of
    more than ``max_voxels`` voxels (default :data:`MAX_VOLUME_VOXELS`) are refused from
    their header, and so are arrays when ``max_voxels`` is given.

    Raises
    ------
    InvalidImageError
        Not a 3-D array of booleans or integers, or an unreadable file.
    ImageTooLargeError
        A file declaring more voxels than ``max_voxels``.
    """
    limit = MAX_VOLUME_VOXELS if max_voxels is None else max_voxels
    if isinstance(source, bytes | bytearray | memoryview):
        data = bytes(source)
        if data[:6] == NPY_MAGIC:
            arr = _npy_bytes(data, limit)
        else:
            from .io.tiff import read_tiff_stack

            arr = read_tiff_stack(data, max_voxels=limit)
    elif _is_zarr(source):
        arr, _ = read_zarr(source, limit)
    elif isinstance(source, str | os.PathLike) and str(source).lower().endswith(TIFF_SUFFIXES):
        arr = _read_stack(source, limit)
    elif isinstance(source, str | os.PathLike):
        arr = _read_npy(source, limit)
    else:
        arr = np.asarray(source)
        if max_voxels is not None:
            _within_limit(arr.shape, max_voxels)
    if arr.ndim != 3:
        hint = ""
        if arr.ndim == 2 and not isinstance(source, np.ndarray):  # a mask saved with numpy
            hint = (
                " (a .npy file is read as a volume; for a 2-D image pass the array itself, "
                "numpy.load(path), or save it as a PNG or TIFF)"
            )
        raise InvalidImageError(
            f"a volume is a 3-D array; this one has {arr.ndim} dimensions{hint}"
        )
    if not (arr.dtype == np.bool_ or np.issubdtype(arr.dtype, np.integer)):
        raise InvalidImageError(
            f"a volume holds booleans or integer labels, not {arr.dtype} values"
        )
    return arr


def volume_components(
    volume: np.ndarray,
) -> list[tuple[np.ndarray, tuple[int, int, int], int | None]]:
    """26-connected components as padded crops, with the crop's origin in the volume
    and the label (``None`` for a boolean or 0/1 volume, else each non-zero value is a
    shape of its own).

    A label volume's components are each label's pieces, found inside the label's
    bounding box from the label's own voxels (one pass over the volume groups the
    voxels by label, :mod:`skelprune.volume_labels`), so that the work follows the
    labelled voxels, not labels × voxels. Order: by label, then as
    ``scipy.ndimage.label`` finds them.

    >>> v = np.zeros((3, 4, 5), np.int64); v[1, 1, 1:3] = 7; v[1, 2:4, 4] = 2
    >>> [(c.shape, o, lab) for c, o, lab in volume_components(v)]
    [((3, 4, 3), (0, 1, 3), 2), ((3, 3, 4), (0, 0, 0), 7)]
    """
    inside = volume != 0
    if volume.dtype != np.bool_ and np.any(inside & (volume != 1)):  # labels, not 0/1
        from .volume_labels import label_groups, label_pieces

        return list(label_pieces(label_groups(volume)))
    from .grid3d.components import binary_pieces

    return binary_pieces(inside)


def prune_volume(
    source: Any,
    options: PruneOptions,
    volume_options: VolumeOptions,
    output: OutputOptions | None = None,
    workers: int = 1,
    client: Any = None,
    progress: Callable[[int, int], None] | None = None,
) -> VolumeResult:
    """Prune every 26-connected component of a volume (what :func:`skelprune.prune` runs
    for a 3-D array, a ``.npy`` path, a TIFF stack or a Zarr store).

    ``workers`` and ``client``: as :func:`skelprune.volume.prune_volume_labels`
    takes them (default: in this process). ``progress(done, total)`` is called once the
    components are found (``done=0``) and as each is pruned.

    Raises
    ------
    EmptyMaskError
        No voxel inside.
    InvalidOptionError
        An option that holds for images only (``method="dce"``, ``scope="local"``).
    """
    applied = options.resolved()
    if applied.method != "bayesian":
        raise InvalidOptionError(
            "method='dce' follows a contour and holds for images only; a volume is pruned "
            "with method='bayesian'"
        )
    if applied.scope != "global":
        raise InvalidOptionError(
            "scope='local' prunes an image window by window and holds for images only; a "
            "volume is pruned whole"
        )
    spacing = volume_options.spacing
    if _is_zarr(source):
        volume, stored = read_zarr(source)
        if stored is not None and spacing == VolumeOptions().spacing:
            spacing = stored  # OME-Zarr's scale, unless a spacing is given
        volume = read_volume(volume)  # the dims and dtype checks
    else:
        volume = read_volume(source)
    if not volume.any():
        raise EmptyMaskError("the volume has no voxel inside")
    from .output.volume import VolumeResult

    result = VolumeResult(
        shape=(int(volume.shape[0]), int(volume.shape[1]), int(volume.shape[2])),
        spacing=spacing,
        options=applied,
        output=OutputOptions() if output is None else output,
        volume=volume != 0,
    )
    from .volume_parallel import prune_components

    pieces = volume_components(volume)
    tick = None if progress is None else _counted(progress, len(pieces))
    result.components.extend(prune_components(pieces, applied, spacing, workers, client, tick))
    return result


def _counted(progress: Callable[[int, int], None], total: int) -> Callable[[int], None]:
    """``progress(done, total)`` told ``(0, total)`` now, and fed by ``tick(n)`` as ``n``
    more components are done."""
    progress(0, total)
    done = [0]

    def tick(n: int = 1) -> None:
        done[0] += n
        progress(done[0], total)

    return tick


def prune_volume_labels(
    source: Any,
    options: PruneOptions | None = None,
    volume: VolumeOptions | None = None,
    output: OutputOptions | None = None,
    *,
    workers: int | None = None,
    client: Any = None,
    progress: bool | Callable[[int, int], None] = False,
    **keywords: Any,
) -> VolumeResult:
    """Prune a (label) volume as :func:`skelprune.prune` does, its components in parallel.

    Parameters
    ----------
    source
        A 3-D array, a ``.npy`` file, a TIFF stack or a Zarr / OME-Zarr store.
    options, volume, output, **keywords
        As for :func:`skelprune.prune` (``spacing=``, ``beta=``, ...).
    workers : int, optional
        Worker processes on this machine (default: one a CPU core; 1: in this process).
    client : dask.distributed.Client or str, optional
        Prune on a Dask cluster instead (a client or a scheduler's address).
    progress : bool or callable
        ``True``: components done on stderr; a callable: ``progress(done, total)``, as
        :func:`skelprune.prune` calls it.

    Returns
    -------
    VolumeResult
        The same components as :func:`skelprune.prune` gives, in the same order.

    Examples
    --------
    >>> v = np.zeros((20, 20, 40), np.uint16); v[4:12, 4:12, 2:20] = 3; v[4:12, 4:12, 20:38] = 9
    >>> res = prune_volume_labels(v, workers=2)
    >>> [c.label for c in res.components]
    [3, 9]
    """
    from .options import resolve_options, volume_value

    if workers is not None and (type(workers) is not int or workers < 1):
        raise InvalidOptionError(f"workers is a whole number >= 1, not {workers!r}")
    volume = volume_value(volume, keywords) or VolumeOptions()
    opts, _, _, out = resolve_options(options, None, None, output, keywords)
    n = workers or os.cpu_count() or 1
    shown = _on_stderr() if progress is True else (progress or None)
    return prune_volume(source, opts, volume, out, workers=n, client=client, progress=shown)


def _on_stderr() -> Callable[[int, int], None]:
    """``progress(done, total)`` drawn by a :class:`Progress` on stderr."""
    from .volume_parallel import Progress

    bars: list[Progress] = []

    def show(done: int, total: int) -> None:
        if not bars:
            bars.append(Progress(total))
        bars[0](done - bars[0].done)

    return show
