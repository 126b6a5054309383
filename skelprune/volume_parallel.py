"""A volume's components pruned in parallel: on the machine's cores or on dask.distributed.

Every component (each label's 26-connected pieces, :mod:`skelprune.volume_labels`) is
pruned on its own, so they can go to worker processes in any order and come back in the
volume's order: the answer is the one :func:`skelprune.prune` gives, component for
component. :func:`prune_volume_labels` is the entry point; :func:`prune_components` the
map it runs.
"""

from __future__ import annotations

import multiprocessing as mp
import sys
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np

from .options import PruneOptions

if TYPE_CHECKING:
    from .output.volume import VolumeComponent

__all__ = [
    "Progress",
    "in_batches",
    "map_batches",
    "prune_components",
    "prune_volume_component",
]

Piece = tuple[np.ndarray, tuple[int, int, int], "int | None"]
T = TypeVar("T")
R = TypeVar("R")


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


def prune_volume_component(
    crop: np.ndarray,
    origin: tuple[int, int, int],
    options: PruneOptions,
    spacing: tuple[float, float, float],
) -> VolumeComponent:
    """The curve skeleton of one padded component crop and its pruning."""
    from .grid3d.skeleton import VolumeSkeleton
    from .grid3d.tips import trim_volume_tips
    from .output.volume import VolumeComponent
    from .pruning.bayesian import pruning_sequence
    from .pruning.choice import chosen_step
    from .pruning.margin import branch_margins

    axis = VolumeSkeleton.curve_skeleton(crop, spacing, origin)
    norm = axis.normalisation(options.beta)
    seq = pruning_sequence(axis, norm.alpha, norm.lbar)
    chosen = chosen_step(seq, options.choice, options.min_margin)
    answer = seq.skeleton_at(chosen)
    trim = None
    if options.trim and seq.alpha is not None:
        trim = trim_volume_tips(answer, seq.lost[chosen], seq.alpha, seq.lbar)
        answer = trim.skeleton
    margins = branch_margins(answer.graph, seq, chosen, trim)
    return VolumeComponent(axis, answer, seq, chosen, margins, trim)


def _prune_batch(
    batch: Sequence[Piece], options: PruneOptions, spacing: tuple[float, float, float]
) -> list[VolumeComponent]:
    out = []
    for crop, origin, label in batch:
        component = prune_volume_component(crop, origin, options, spacing)
        component.label = label
        out.append(component)
    return out


def in_batches(items: Sequence[T], sizes: Sequence[int], target: int) -> list[list[T]]:
    """Consecutive items in batches of about ``target`` in size (``sizes``, each item's):
    small items travel together, so a task's overhead is paid per batch.

    >>> in_batches("abcde", [3, 1, 1, 4, 1], 2)
    [['a'], ['b', 'c'], ['d'], ['e']]
    """
    out: list[list[T]] = []
    size = 0
    for item, n in zip(items, sizes, strict=True):
        if not out or size >= target:
            out.append([])
            size = 0
        out[-1].append(item)
        size += n
    return out


def map_batches(
    fn: Callable[..., list[R]],
    batches: Sequence[Sequence[Any]],
    args: tuple[Any, ...],
    *,
    client: Any = None,
    workers: int = 1,
    progress: Callable[[int], None] | None = None,
) -> list[R]:
    """``fn(batch, *args)`` for every batch, each a task: on ``client`` (a
    ``dask.distributed.Client`` or a scheduler's address) or on a pool of ``workers``
    processes; the results joined in the batches' order, ``progress(len(batch))`` as
    each batch finishes."""
    if client is not None:
        from dask.distributed import Client, as_completed

        own = isinstance(client, str)
        executor: Any = Client(client) if own else client
        options: dict[str, Any] = {"pure": False}
        close = executor.close if own else (lambda: None)
    else:
        from concurrent.futures import as_completed  # type: ignore[assignment]

        # fork where there is one: the workers start with the kernels already loaded
        method = "fork" if "fork" in mp.get_all_start_methods() else "spawn"
        executor = ProcessPoolExecutor(workers, mp_context=mp.get_context(method))
        options = {}
        close = executor.shutdown
    results: list[list[R]] = [[] for _ in batches]
    try:
        futures = {executor.submit(fn, b, *args, **options): i for i, b in enumerate(batches)}
        for fut in as_completed(futures):
            # let each result go on the cluster once it is here: a worker keeps a
            # future's result for as long as the client holds the future
            i = futures.pop(fut)
            results[i] = fut.result()
            if progress is not None:
                progress(len(batches[i]))
    finally:
        close()
    return [r for batch in results for r in batch]


def prune_components(
    pieces: Sequence[Piece],
    options: PruneOptions,
    spacing: tuple[float, float, float],
    workers: int = 1,
    client: Any = None,
    progress: Callable[[int], None] | None = None,
) -> list[VolumeComponent]:
    """Each piece pruned (:func:`prune_volume_component`), in order.

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
    batches = in_batches(pieces, [p[0].size for p in pieces], max(total // parts, 1))
    return map_batches(
        _prune_batch, batches, (options, spacing), client=client, workers=workers, progress=progress
    )
