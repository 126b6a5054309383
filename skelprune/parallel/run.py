"""Running a data set on dask.distributed: :func:`prune_many` and
:func:`iter_prune_many`."""

from __future__ import annotations

import contextlib
import json
import logging
import math
import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

from ..errors import InvalidOptionError, shown
from ..limits import DATASET_LIMITS, Limits
from ..options import (
    OutputOptions,
    PruneOptions,
    RasterOptions,
    ReadOptions,
    VolumeOptions,
    resolve_options,
    volume_value,
)
from .items import Item, expand
from .store import Store
from .work import WORKER_CRASHED, Done, Job, run_batch

if TYPE_CHECKING:
    from distributed import Client

__all__ = ["Outcome", "iter_prune_many", "prune_many"]

#: Largest batch of inputs one task prunes: small enough to spread a data set over the
#: workers and to stream results, large enough that dask's per-task cost (about a
#: millisecond) stays small against a few milliseconds an input.
MAX_BATCH = 32
#: Seconds to wait for restarted workers before trying a suspect input alone.
RESTART_TIMEOUT = 60
#: Memory a worker process holds besides the input it prunes (dask, the library, numba's
#: kernels), added to the budget for the worker's memory limit.
WORKER_OWN_MB = 512
#: The answers a run writes beside each document when asked (``files=``), and their
#: files' endings.
FILES = {"png": ".png", "csv": ".csv"}


@dataclass(frozen=True)
class Outcome:
    """What became of one input.

    Attributes
    ----------
    input : str
        Its name: the document's (``NAME`` of ``NAME.json``), or ``NAME#ROW`` for a row
        of the table ``NAME.jsonl``.
    position : int
        Its place among the inputs, from 0.
    status : {"done", "failed", "skipped"}
        ``skipped``: its result was written by an earlier run.
    result : dict or None
        The document (a row's: ``{"row", "index", "result"}``), when there is no
        ``out`` folder to write it to.
    path : Path or None
        Where it was written (with ``out``).
    problem : dict or None
        ``{"input", "kind", "detail"}`` of a failed input: ``kind`` is the service's
        problem type (``invalid-image``, ``empty-mask``, ``job-too-large``, ...).
    files : dict or None
        The bytes of the answers asked for with ``files`` (by answer), when there is no
        ``out`` folder to write them to.
    """

    input: str
    position: int
    status: Literal["done", "failed", "skipped"]
    result: dict[str, Any] | None = None
    path: Path | None = None
    problem: dict[str, str] | None = None
    files: dict[str, bytes] | None = None


def _batches(
    todo: list[tuple[int, Item]], workers: int, size: int | None
) -> list[list[tuple[int, Item]]]:
    if size is None:  # some eight tasks a worker, so that the work spreads and streams
        size = max(1, min(MAX_BATCH, math.ceil(len(todo) / (8 * max(workers, 1)))))
    return [todo[i : i + size] for i in range(0, len(todo), size)]


@contextlib.contextmanager
def _client(client: Client | str | None, jobs: int | None, limits: Limits) -> Iterator[Client]:
    """The client given, one to the scheduler at an address, or a local cluster of
    ``jobs`` one-thread worker processes (default: one a core), each under a memory
    limit of the budget plus its own needs (the nanny restarts a worker over it)."""
    from distributed import Client, LocalCluster

    if client is not None and not isinstance(client, str):
        yield client
        return
    if isinstance(client, str):
        with Client(client) as c:
            yield c
        return
    n = jobs or (
        len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    )
    limit = "auto" if limits.memory_mb is None else f"{limits.memory_mb + WORKER_OWN_MB}MiB"
    with forked_workers():  # the workers start here
        cluster = LocalCluster(
            n_workers=n,
            threads_per_worker=1,
            processes=True,
            memory_limit=limit,
            dashboard_address=":0",  # a free port: never a clash with another cluster
            silence_logs=logging.ERROR,
        )
    with cluster, Client(cluster) as c:
        yield c


@contextlib.contextmanager
def forked_workers() -> Iterator[None]:
    """The workers a local cluster starts within: forked from one process that has
    loaded dask's worker, the library and its kernels (:mod:`skelprune.parallel.preload`),
    where the platform has a forkserver, instead of each started afresh and loading them
    on its first input (about 1.5 s of CPU a worker, measured: docs/performance.md). A
    worker its nanny restarts later is started afresh (dask's default)."""
    import multiprocessing

    import dask

    if "forkserver" not in multiprocessing.get_all_start_methods():
        yield
        return
    import distributed.utils

    multiprocessing.get_context("forkserver").set_forkserver_preload([f"{__package__}.preload"])
    # dask's own preload list, set once unless this flag says it is: it imports numpy,
    # pandas ... in this process first, to check them (0.4 s here); ours imports what a
    # worker runs
    distributed.utils._forkserver_preload_set = True
    with dask.config.set({"distributed.worker.multiprocessing-method": "forkserver"}):
        yield


def _workers(client: Client) -> int:
    with contextlib.suppress(Exception):
        return sum(client.nthreads().values())
    return 1


def iter_prune_many(
    inputs: Any,
    options: PruneOptions | None = None,
    *,
    read: ReadOptions | None = None,
    raster: RasterOptions | None = None,
    output: OutputOptions | None = None,
    volume: VolumeOptions | None = None,
    client: Client | str | None = None,
    out: str | os.PathLike[str] | None = None,
    jobs: int | None = None,
    limits: Limits | None = None,
    batch_size: int | None = None,
    files: tuple[str, ...] = (),
    **keywords: Any,
) -> Iterator[Outcome]:
    """:func:`prune_many`'s outcomes one by one, as they finish (skipped inputs first).

    The first value is the number of inputs (an ``int``), for a progress bar; then one
    :class:`Outcome` an input.
    """
    for name, value in (("jobs", jobs), ("batch_size", batch_size)):
        if value is not None and (
            isinstance(value, bool) or not isinstance(value, int) or value < 1
        ):
            raise InvalidOptionError(f"{name} must be a whole number >= 1, got {shown(value)}")
    volume = volume_value(volume, keywords)
    options, read, raster, output = resolve_options(options, read, raster, output, keywords)
    unknown = [f for f in files if f not in FILES]
    if unknown:
        raise InvalidOptionError(
            f"files: {', '.join(map(repr, unknown))} not one of {', '.join(FILES)}"
        )
    job = Job(options, read, raster, output, volume, limits or DATASET_LIMITS, tuple(files))
    # label images, once the read options know them: every object is its own shape
    items = expand(inputs, labels=bool(getattr(job.read, "labels", False)))
    store = None if out is None else Store(out)
    yield len(items)  # type: ignore[misc]
    todo: list[tuple[int, Item]] = []
    for position, item in enumerate(items):
        done = store is not None and (
            store.has_row(item.name, item.source.row)
            if item.is_row
            else store.has_document(item.name, job.files)
        )
        if done:
            assert store is not None  # only a store says what is done
            yield Outcome(item.key, position, "skipped", path=_path(store, item))
        else:
            todo.append((position, item))
    if store is not None:
        store.start_problems({item.key for _, item in todo})
    try:
        if todo:
            yield from _run(todo, items, job, store, client, jobs, batch_size)
    finally:
        if store is not None:
            store.close()


def _path(store: Store, item: Item) -> Path:
    return store.table_path(item.name) if item.is_row else store.document_path(item.name)


def _run(
    todo: list[tuple[int, Item]],
    items: list[Item],
    job: Job,
    store: Store | None,
    client: Client | str | None,
    jobs: int | None,
    batch_size: int | None,
) -> Iterator[Outcome]:
    from distributed import as_completed

    with _client(client, jobs, job.limits) as c:
        batches, futures = {}, []
        workers = _workers(c)
        for batch in _batches(todo, workers, batch_size):
            future = c.submit(run_batch, batch, job, pure=False)
            batches[future.key] = batch
            futures.append(future)
        pending = as_completed(futures)
        del futures  # as_completed holds them; each is let go once handled
        suspects: list[tuple[int, Item]] = []
        for future in pending:
            batch = batches.pop(future.key)
            try:
                results = future.result()
            except Exception:  # the worker died (over its memory limit, or killed)
                if len(batch) > 1:  # which input was it? each alone, in parallel
                    for one in batch:
                        f = c.submit(run_batch, [one], job, pure=False)
                        batches[f.key] = [one]
                        pending.add(f)
                else:  # it, or another input on the same worker: tried alone, below
                    suspects.extend(batch)
                continue
            for done in results:
                yield _record(done, items[done.position], store)
        # one at a time, alone on the cluster: only an input that kills a worker by
        # itself is reported as having done so
        for one in suspects:
            with contextlib.suppress(Exception):  # the workers restarted by the nanny
                c.wait_for_workers(workers, timeout=RESTART_TIMEOUT)
            if not _workers(c):  # none came back: nothing would ever run it
                detail = (
                    "its worker died while pruning it, and no worker came back within "
                    f"{RESTART_TIMEOUT} s to try it alone"
                )
                results = [Done(one[0], problem=(WORKER_CRASHED, detail))]
                yield _record(results[0], items[one[0]], store)
                continue
            try:
                results = c.submit(run_batch, [one], job, pure=False).result()
            except Exception as exc:
                detail = (
                    f"its worker died while pruning it ({type(exc).__name__}): over the "
                    "worker's memory limit, or killed"
                )
                results = [Done(one[0], problem=(WORKER_CRASHED, detail))]
            yield _record(results[0], items[one[0]], store)


def _record(done: Done, item: Item, store: Store | None) -> Outcome:
    key = item.key
    if done.problem is not None:
        problem = {"input": key, "kind": done.problem[0], "detail": done.problem[1]}
        if store is not None:
            store.write_problem(problem)
        return Outcome(key, done.position, "failed", problem=problem)
    assert done.answer is not None
    if store is None:
        result = json.loads(done.answer.payload)
        return Outcome(key, done.position, "done", result=result, files=done.answer.files)
    if item.is_row:
        path = store.write_row(item.name, item.source.row, done.answer.payload)
    else:
        for kind, payload in done.answer.files.items():  # the document last: it marks done
            store.write_document(item.name, payload, FILES[kind])
        path = store.write_document(item.name, done.answer.payload)
    return Outcome(key, done.position, "done", path=path)


def prune_many(
    inputs: Any,
    options: PruneOptions | None = None,
    *,
    read: ReadOptions | None = None,
    raster: RasterOptions | None = None,
    output: OutputOptions | None = None,
    volume: VolumeOptions | None = None,
    client: Client | str | None = None,
    out: str | os.PathLike[str] | None = None,
    ordered: bool = False,
    jobs: int | None = None,
    limits: Limits | None = None,
    batch_size: int | None = None,
    files: tuple[str, ...] = (),
    **keywords: Any,
) -> list[Outcome]:
    """Prune a whole data set on dask.distributed, each input on its own.

    Parameters
    ----------
    inputs : path, glob, folder, array, Labels, GeoDataFrame, mapping or list of them
        What :func:`skelprune.parallel.items.expand` takes: files (a folder's ``*.png``,
        ``*.geojson``, ``*.json``, ``*.tif``, ``*.tiff`` and ``*.npy``; a glob's
        matches), arrays, label images (each object its own document), a GeoDataFrame
        (each row a feature of one table), a mapping of names to inputs, or a list.
        Volumes (a ``.npy`` file, a multi-page TIFF, a 3-D array) are pruned as
        :func:`skelprune.prune` prunes them, their document a volume's.
    options, read, raster, output, volume, **keywords
        As for :func:`skelprune.prune`, the same for every input (``spacing=`` or
        ``volume=VolumeOptions(...)``: the volumes' voxel size; read options hold for
        images, and a volume given them fails as ``invalid-option``).
    client : distributed.Client or str, optional
        Where to run: a client, or a scheduler's address (``tcp://host:8786``). Default:
        a local cluster of ``jobs`` one-thread worker processes (one a core), closed at
        the end; its workers are forked from a process that loads the library and its
        kernels once (a forkserver, where the platform has one), which stays while this
        process lives and starts the workers of its later runs.
    out : path, optional
        The folder to write to (made if missing): ``NAME.json`` a document (compact
        JSON, :func:`~skelprune.parallel.work.document_bytes`), ``NAME.jsonl`` a table
        (one line a row, as rows finish), ``problems.jsonl`` (one line a failed input).
        Results are written as they finish, atomically; inputs whose result is there are
        skipped, so a run stopped halfway finishes where it stopped. Without ``out`` the
        results come back in the outcomes.
    ordered : bool
        Outcomes in the inputs' order (default: as they finished, skipped ones first).
    limits : Limits, optional
        Each input's memory and time budget and size limits
        (:data:`skelprune.limits.DATASET_LIMITS`, the service's, by default; a volume's
        voxels count against ``max_pixels``): an input over it fails as
        ``job-too-large`` (over a size limit: ``image-too-large``), and a local cluster's
        workers are restarted past it, so one input cannot sink a worker.
    files : tuple of {"png", "csv"}
        Answers written beside each document: ``NAME.png`` the overlay (a volume's: its
        projections), ``NAME.csv`` the table (``table=``); with ``out`` only (without it,
        each outcome's ``files`` holds their bytes).
    batch_size : int, optional
        Inputs a task (default: up to 32, some eight tasks a worker).

    Returns
    -------
    list of Outcome
        One an input: ``done``, ``failed`` (with its ``problem``) or ``skipped``.

    Raises
    ------
    InvalidOptionError
        For an option its class refuses, no input, or two inputs of one name.

    Examples
    --------
    >>> import numpy as np
    >>> from skelprune.parallel import prune_many
    >>> m = np.zeros((20, 40), bool); m[4:16, 4:36] = True
    >>> outcomes = prune_many({"bar": m, "none": m & False}, jobs=1, ordered=True)
    >>> [(o.input, o.status) for o in outcomes]
    [('bar', 'done'), ('none', 'failed')]
    >>> outcomes[1].problem["kind"], len(outcomes[0].result["components"])
    ('empty-mask', 1)
    """
    it = iter_prune_many(
        inputs,
        options,
        read=read,
        raster=raster,
        output=output,
        volume=volume,
        client=client,
        out=out,
        jobs=jobs,
        limits=limits,
        batch_size=batch_size,
        files=files,
        **keywords,
    )
    next(it)  # the count
    outcomes = list(it)
    return sorted(outcomes, key=lambda o: o.position) if ordered else outcomes
