"""What runs inside a task, on a worker: read, check the budget, prune and serialise a
batch of items, each one's failure caught and named, so that one bad input fails alone.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any, TypeVar

import numpy as np

from ..budget import VOLUME_BASIS, check_budget, estimate, out_of_memory, volume_estimate
from ..errors import JobTooLargeError, SkelpruneError, problem_kind
from ..options import OutputOptions, PruneOptions, RasterOptions, ReadOptions, VolumeOptions
from ..volume import is_volume, prune_volume, read_volume, refuse_image_options
from .items import Feature, Item, LabelObject

__all__ = [
    "INTERNAL_ERROR",
    "UNREADABLE",
    "WORKER_CRASHED",
    "Budget",
    "Done",
    "Job",
    "document_bytes",
    "finite_lines",
    "run_batch",
    "run_item",
]

#: Problem kinds of failures that are not the input's own error (the service's names).
WORKER_CRASHED = "worker-crashed"
INTERNAL_ERROR = "internal-error"
#: A file that cannot be read at all (missing, no permission): the input's problem.
UNREADABLE = SkelpruneError.kind
#: An answer with a number JSON cannot write (an infinity from an overflow).
OVERFLOW = (
    "the answer would hold a number JSON cannot write (an overflow); scale the input "
    "coordinates down"
)

T = TypeVar("T")


@dataclass(frozen=True)
class Budget:
    """What one input may cost: the service's limits, with the service's defaults.

    ``memory_mb``: a worker's memory for one input, its own included; an input whose
    estimate (:mod:`skelprune.budget`) is over it is refused before any work
    (``job-too-large``), and so is one that runs out all the same. ``seconds``: the time
    an input may be expected to take (the same estimate). ``max_pixels`` and
    ``max_vertices``: the largest image, raster or volume (its voxels, checked from a
    file's header before it is read), and polygon. ``None``: no limit.
    """

    memory_mb: int | None = 2048
    seconds: float | None = 30.0
    max_pixels: int | None = 4096 * 4096
    max_vertices: int | None = 100_000


@dataclass(frozen=True)
class Job:
    """Everything a task needs besides its items: the options and the budget.

    ``volume``: the voxel spacing of the volumes among the items (``.npy`` files, TIFF
    stacks, 3-D arrays); given, any 3-D array is a volume, as for :func:`skelprune.prune`.
    """

    options: PruneOptions = field(default_factory=PruneOptions)
    read: ReadOptions | None = None
    raster: RasterOptions | None = None
    output: OutputOptions = field(default_factory=OutputOptions)
    volume: VolumeOptions | None = None
    budget: Budget = field(default_factory=Budget)

    @property
    def memory(self) -> int | None:
        """The memory budget of one input, bytes."""
        return None if self.budget.memory_mb is None else self.budget.memory_mb * 2**20


@dataclass(frozen=True)
class Done:
    """One item's outcome: its position in the run, and its serialised result (a
    document, or a table's line) or its problem ``(kind, detail)``."""

    position: int
    payload: bytes | None = None
    problem: tuple[str, str] | None = None


def document_bytes(doc: Any) -> bytes:
    """A result document as ``prune_many`` and ``skelprune prune-many`` write it:
    compact JSON (no spaces), UTF-8, one newline at the end.

    >>> document_bytes({"a": [1, 2.5], "b": None})
    b'{"a":[1,2.5],"b":null}\\n'
    """
    try:
        return json.dumps(doc, separators=(",", ":"), allow_nan=False).encode() + b"\n"
    except ValueError:
        raise SkelpruneError(OVERFLOW) from None


def finite_lines(line: dict[str, Any]) -> dict[str, Any]:
    """A feature's line (``{"row", "index", "result"}``) as it is, its coordinates all
    finite: what :func:`document_bytes` would refuse is refused here too, unwritten.

    >>> finite_lines({"result": {"features": [{"geometry": {"coordinates": [[0, 1e400]]}}]}})
    Traceback (most recent call last):
    ...
    skelprune.errors.SkelpruneError: the answer would hold a number JSON cannot write ...
    """
    for feature in line["result"]["features"]:
        if not np.isfinite(np.asarray(feature["geometry"]["coordinates"], float)).all():
            raise SkelpruneError(OVERFLOW)
    return line


def _read(item: Item, job: Job) -> Any:
    from ..io.frame import PixelFrame
    from ..io.input import Input, read_input

    source = item.source
    most_pixels, most_vertices = job.budget.max_pixels, job.budget.max_vertices
    if isinstance(source, LabelObject):
        row, col = source.origin
        # the object's own crop, answered in the label image's pixel coordinates
        frame = PixelFrame(x0=float(col), y0=float(row))
        return Input(source.mask, frame=frame)
    if isinstance(source, Feature):
        return read_input(
            source.geometry,
            kind="geojson",
            raster=job.raster,
            max_pixels=most_pixels,
            max_vertices=most_vertices,
        )
    return read_input(
        source,
        read=job.read,
        raster=job.raster,
        max_pixels=most_pixels,
        max_vertices=most_vertices,
    )


def _is_volume(item: Item, job: Job) -> bool:
    """Whether an item is a volume (with the run's volume options, any 3-D array)."""
    source = item.source
    if isinstance(source, LabelObject | Feature):
        return False
    return is_volume(source, spacing_given=job.volume is not None)


def _volume_answer(item: Item, job: Job) -> dict[str, Any]:
    """A volume's document: its voxels within ``max_pixels`` (a file's from its header,
    before it is read), its estimate within the budget, then pruned."""
    # a label-image run's volumes: each label is a shape of its own already
    read = None if job.read is None else replace(job.read, labels=False)
    refuse_image_options(read, job.output)
    volume = read_volume(item.source, max_voxels=job.budget.max_pixels)
    check_budget(volume_estimate(volume), job.memory, job.budget.seconds, VOLUME_BASIS)
    res = prune_volume(volume, job.options, job.volume or VolumeOptions(), job.output)
    return res.to_dict()


def _answer(item: Item, job: Job) -> dict[str, Any]:
    from ..api import prune_input

    if _is_volume(item, job):
        return _volume_answer(item, job)
    shape = _read(item, job)
    check_budget(
        estimate(shape.mask, scope=job.options.scope, labels=shape.labels),
        job.memory,
        job.budget.seconds,
    )
    res = prune_input(shape, job.options, job.output)
    if isinstance(item.source, Feature):
        line = {"row": item.source.row, "index": _plain(item.source.index)}
        line["result"] = res.to_geojson()
        return line
    return res.to_dict()


def _plain(value: Any) -> Any:
    """A table's index label as JSON writes it (numpy scalars as Python ones)."""
    return value.item() if hasattr(value, "item") else value


def run_item(
    item: Item, job: Job, encode: Callable[[dict[str, Any]], T]
) -> tuple[T | None, tuple[str, str] | None]:
    """One item's result, serialised by ``encode`` (:func:`document_bytes`, or for a
    caller that reads the result at once a check such as :func:`finite_lines`), or its
    problem ``(kind, detail)``."""
    try:
        return encode(_answer(item, job)), None
    except MemoryError:
        err: JobTooLargeError = out_of_memory(job.memory)
        return None, (err.kind, str(err))
    except SkelpruneError as exc:
        return None, (problem_kind(exc) or SkelpruneError.kind, str(exc))
    except OSError as exc:
        return None, (UNREADABLE, f"cannot read {item.source!s}: {exc.strerror or exc}")
    except Exception as exc:  # a bug: named, and the batch goes on
        return None, (INTERNAL_ERROR, f"{type(exc).__name__}: {exc}")


def run_batch(batch: list[tuple[int, Item]], job: Job) -> list[Done]:
    """A task: every item of the batch, in order (what runs on a worker)."""
    out = []
    for position, item in batch:
        payload, problem = run_item(item, job, document_bytes)
        out.append(Done(position, payload, problem))
    return out
