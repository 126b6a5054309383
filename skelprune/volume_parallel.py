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
from typing import TYPE_CHECKING, Any

import numpy as np

from .options import PruneOptions

if TYPE_CHECKING:
    from .output.volume import VolumeComponent

__all__ = ["Progress", "prune_components", "prune_volume_component"]

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
