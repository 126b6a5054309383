"""A volume's components pruned in parallel: on the machine's cores or on dask.distributed.

Every component (each label's 26-connected pieces, :mod:`skelprune.volume_labels`) is
pruned on its own, so they can go to worker processes in any order and come back in the
volume's order: the answer is the one :func:`skelprune.prune` gives, component for
component. :func:`prune_volume_labels` is the entry point; :func:`prune_components` the
map it runs.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import sys
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from typing import TYPE_CHECKING, Any

import numpy as np

from .errors import InvalidOptionError
from .options import OutputOptions, PruneOptions, VolumeOptions

if TYPE_CHECKING:
    from .output.volume import VolumeComponent, VolumeResult

__all__ = ["Progress", "prune_components", "prune_volume_labels"]

Piece = tuple[np.ndarray, tuple[int, int, int], "int | None"]


class Progress:
    """Components done out of all, written to a stream (stderr) at most every
    ``every`` seconds and once at the end: ``labels: 120/458 (26 %), 3.1 s``."""

    def __init__(self, total: int, stream: Any = None, every: float = 0.5) -> None:
        self.total, self.done = total, 0
        self.stream = sys.stderr if stream is None else stream
        self.every = every
        self.start = self.last = time.monotonic()

    def __call__(self, n: int = 1) -> None:
        self.done += n
        now = time.monotonic()
        if now - self.last >= self.every or self.done == self.total:
            self.last = now
            pct = 100 * self.done // max(self.total, 1)
            end = "\n" if self.done == self.total else "\r"
            self.stream.write(
                f"components: {self.done}/{self.total} ({pct} %), {now - self.start:.1f} s{end}"
            )
            self.stream.flush()


def _prune_batch(
    batch: Sequence[Piece], options: PruneOptions, spacing: tuple[float, float, float]
) -> list[VolumeComponent]:
    from .volume import prune_volume_component

    out = []
    for crop, origin, label in batch:
        component = prune_volume_component(crop, origin, options, spacing)
        component.label = label
        out.append(component)
    return out


def _batches(pieces: Sequence[Piece], target_voxels: int) -> list[list[Piece]]:
    """Consecutive pieces in batches of about ``target_voxels`` crop voxels: small
    labels travel together, so a task's overhead is paid per batch."""
    out: list[list[Piece]] = []
    size = 0
    for piece in pieces:
        if not out or size >= target_voxels:
            out.append([])
            size = 0
        out[-1].append(piece)
        size += piece[0].size
    return out


def prune_components(
    pieces: Sequence[Piece],
    options: PruneOptions,
    spacing: tuple[float, float, float],
    workers: int = 1,
    client: Any = None,
    progress: Callable[[int], None] | None = None,
) -> list[VolumeComponent]:
    """Each piece pruned (:func:`skelprune.volume.prune_volume_component`), in order.

    ``workers > 1``: in a pool of that many processes; ``client``: a
    ``dask.distributed.Client`` (or a scheduler's address), each batch of pieces a task.
    ``progress(n)`` is called as ``n`` more pieces are done.
    """
    if client is None and workers <= 1:
        out = []
        for piece in pieces:
            out.extend(_prune_batch([piece], options, spacing))
            if progress is not None:
                progress(1)
        return out
    total = sum(p[0].size for p in pieces)
    parts = max(1, 8 * (workers if client is None else 4))
    batches = _batches(pieces, max(total // parts, 1))
    results: list[list[VolumeComponent]] = [[] for _ in batches]
    if client is not None:
        from dask.distributed import Client, as_completed

        own = isinstance(client, str)
        dask_client = Client(client) if own else client
        try:
            futures = {
                dask_client.submit(_prune_batch, b, options, spacing, pure=False): i
                for i, b in enumerate(batches)
            }
            for fut in as_completed(futures):
                i = futures[fut]
                results[i] = fut.result()
                if progress is not None:
                    progress(len(batches[i]))
        finally:
            if own:
                dask_client.close()
    else:
        # fork where there is one: the workers start with the kernels already loaded
        method = "fork" if "fork" in mp.get_all_start_methods() else "spawn"
        with ProcessPoolExecutor(workers, mp_context=mp.get_context(method)) as pool:
            jobs = {
                pool.submit(_prune_batch, b, options, spacing): i for i, b in enumerate(batches)
            }
            from concurrent.futures import as_completed as done_first

            for fut in done_first(jobs):
                i = jobs[fut]
                results[i] = fut.result()
                if progress is not None:
                    progress(len(batches[i]))
    return [c for batch in results for c in batch]


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
    from .volume import prune_volume

    if workers is not None and (type(workers) is not int or workers < 1):
        raise InvalidOptionError(f"workers is a whole number >= 1, not {workers!r}")
    volume = volume_value(volume, keywords) or VolumeOptions()
    opts, _, _, out = resolve_options(options, None, None, output, keywords)
    n = workers or os.cpu_count() or 1
    shown = _on_stderr() if progress is True else (progress or None)
    return prune_volume(source, opts, volume, out, workers=n, client=client, progress=shown)


def _on_stderr() -> Callable[[int, int], None]:
    """``progress(done, total)`` drawn by a :class:`Progress` on stderr."""
    bars: list[Progress] = []

    def show(done: int, total: int) -> None:
        if not bars:
            bars.append(Progress(total))
        bars[0](done - bars[0].done)

    return show
