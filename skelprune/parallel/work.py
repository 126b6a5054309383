"""What runs inside a task, on a worker: read, check the budget, prune and serialise a
batch of items, each one's failure caught and named, so that one bad input fails alone.

The client imports this module for :class:`Job` and :class:`Done`: the pruning's own
modules (numba's kernels, scipy, the output) are imported where they run, on a worker.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any, TypeVar

import numpy as np

from ..errors import JobTooLargeError, SkelpruneError, problem_kind
from ..limits import DATASET_LIMITS, Limits
from ..options import OutputOptions, PruneOptions, RasterOptions, ReadOptions, VolumeOptions
from ..volume import is_volume
from .items import Feature, Item, LabelObject

__all__ = [
    "INTERNAL_ERROR",
    "UNREADABLE",
    "WORKER_CRASHED",
    "Answer",
    "Done",
    "Job",
    "document_answer",
    "document_bytes",
    "feature_lines",
    "finite_lines",
    "run_batch",
    "run_item",
]

#: Problem kinds of failures that are not the input's own error (the service's names).
WORKER_CRASHED = "worker-crashed"
INTERNAL_ERROR = "internal-error"
#: A file that cannot be read at all (missing, no permission): the input's problem.
UNREADABLE = SkelpruneError.kind

T = TypeVar("T")


@dataclass(frozen=True)
class Job:
    """Everything a task needs besides its items: the options, the limits and the
    answers written beside each document.

    ``volume``: the voxel spacing of the volumes among the items (``.npy`` files, TIFF
    stacks, 3-D arrays); given, any 3-D array is a volume, as for :func:`skelprune.prune`.
    ``files``: the answers written beside each input's document (``"png"``, the overlay
    as ``NAME.png``; ``"csv"``, the table as ``NAME.csv``).
    """

    options: PruneOptions = field(default_factory=PruneOptions)
    read: ReadOptions | None = None
    raster: RasterOptions | None = None
    output: OutputOptions = field(default_factory=OutputOptions)
    volume: VolumeOptions | None = None
    limits: Limits = DATASET_LIMITS
    files: tuple[str, ...] = ()


@dataclass(frozen=True)
class Answer:
    """One input's serialised result: its document (or a table's line) and the files
    written beside it, by answer (``{"png": ..., "csv": ...}``)."""

    payload: bytes
    files: dict[str, bytes] = field(default_factory=dict)


@dataclass(frozen=True)
class Done:
    """One item's outcome: its position in the run, and its serialised result (a
    document, or a table's line, and its files) or its problem ``(kind, detail)``."""

    position: int
    answer: Answer | None = None
    problem: tuple[str, str] | None = None


def document_bytes(doc: Any) -> bytes:
    """A result document as ``prune_many`` and ``skelprune prune-many`` write it:
    compact JSON (no spaces), UTF-8, non-finite numbers null, one newline at the end
    (:func:`skelprune.output.encode.json_bytes`).

    >>> document_bytes({"a": [1, 2.5], "b": None})
    b'{"a":[1,2.5],"b":null}\\n'
    """
    from ..output.encode import json_bytes

    return json_bytes(doc) + b"\n"


def finite_lines(collection: dict[str, Any]) -> dict[str, Any]:
    """A GeoJSON FeatureCollection as it is, its coordinates all finite (a line with a
    coordinate past the float range has no place on a map): refused otherwise.

    >>> finite_lines({"features": [{"geometry": {"coordinates": [[0, 1e400]]}}]})
    Traceback (most recent call last):
    ...
    skelprune.errors.SkelpruneError: the answer would hold a number JSON cannot write ...
    """
    from ..output.finite import OVERFLOW

    for feature in collection["features"]:
        if not np.isfinite(np.asarray(feature["geometry"]["coordinates"], float)).all():
            raise SkelpruneError(OVERFLOW)
    return collection


def feature_lines(item: Item, result: Any, job: Job) -> dict[str, Any]:
    """A feature's GeoJSON lines, non-finite numbers null, coordinates all finite."""
    from ..output.finite import finite_tree

    return finite_lines(finite_tree(result.to_geojson()))


def _result(item: Item, job: Job) -> Any:
    """One item pruned by the library's one entry, with the run's limits and answers."""
    from ..api import prune
    from ..io.frame import PixelFrame
    from ..io.input import Input

    source = item.source
    answers = ("geojson",) if isinstance(source, Feature) else ("json", *job.files)
    common: dict[str, Any] = {"limits": job.limits, "answers": answers, "output": job.output}
    if isinstance(source, LabelObject):
        row, col = source.origin
        # the object's own crop, answered in the label image's pixel coordinates
        shape = Input(source.mask, frame=PixelFrame(x0=float(col), y0=float(row)))
        return prune(shape, job.options, **common)
    if isinstance(source, Feature):
        return prune(source.geometry, job.options, raster=job.raster, **common)
    if is_volume(source, spacing_given=job.volume is not None):
        # a label-image run's volumes: each label is a shape of its own already
        read = None if job.read is None else replace(job.read, labels=False)
        volume = job.volume or VolumeOptions()
        return prune(source, job.options, read=read, volume=volume, **common)
    return prune(source, job.options, read=job.read, raster=job.raster, **common)


def document_answer(item: Item, result: Any, job: Job) -> Answer:
    """An input's document and its files, as :func:`skelprune.encode` writes them (a
    table's row: its line ``{"row", "index", "result"}``, the result its GeoJSON)."""
    from ..output.encode import encode

    if isinstance(item.source, Feature):
        index = json.dumps(_plain(item.source.index)).encode()
        head = b'{"row":%d,"index":%s,"result":' % (item.source.row, index)
        return Answer(head + encode(result, "geojson") + b"}\n")
    files = {kind: encode(result, kind) for kind in job.files}
    return Answer(encode(result, "json") + b"\n", files)


def _plain(value: Any) -> Any:
    """A table's index label as JSON writes it (numpy scalars as Python ones)."""
    return value.item() if hasattr(value, "item") else value


def run_item(
    item: Item, job: Job, write: Callable[[Item, Any, Job], T]
) -> tuple[T | None, tuple[str, str] | None]:
    """One item's result, serialised by ``write(item, result, job)``
    (:func:`document_answer`, or for a caller that reads the result at once another such
    as :func:`feature_lines`), or its problem ``(kind, detail)``."""
    try:
        return write(item, _result(item, job), job), None
    except MemoryError:
        from ..budget import out_of_memory

        err: JobTooLargeError = out_of_memory(job.limits.memory)
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
        answer, problem = run_item(item, job, document_answer)
        out.append(Done(position, answer, problem))
    return out
