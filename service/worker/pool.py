"""A small pool of worker processes whose jobs can be killed.

``concurrent.futures.ProcessPoolExecutor`` cannot stop a job that hangs, and a crashed
worker breaks the whole executor. Here every worker is one process with one pipe:

- a job that runs past ``job_timeout`` gets its process killed and replaced
  (:class:`JobTimeoutError`);
- a worker that dies mid-job (EOF on the pipe) is replaced and that job fails with
  :class:`WorkerCrashedError`; the pool keeps serving;
- at most ``queue_size`` jobs wait for a free worker; one more raises
  :class:`QueueFullError` at once;
- a job run with a ``cancel`` event that gets set has its process killed and replaced
  (:class:`JobCancelledError`), and its ``progress`` callback receives the
  ``("progress", (done, total))`` messages the worker sends before its answer
  (:func:`service.worker.process.report_progress`);
- with a ``memory_limit``, the parent samples the worker's resident set (``/proc``)
  while a job runs: a worker over the limit is killed and replaced
  (:class:`JobOverMemoryError`), and a worker whose resident set did not come back
  within ``recycle_slack`` of what it held when warm is replaced after its job, so that
  one large job never leaves a worker holding memory that the next job needs.

The event loop never blocks: each job's pipe wait runs in a thread of a private
executor (one thread per worker), and that thread hands the worker back to the pool
itself, so a cancelled request cannot leak a worker.
"""

from __future__ import annotations

import asyncio
import contextlib
import contextvars
import logging
import multiprocessing as mp
import threading
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from typing import Any

from service.worker.pool_errors import (
    JobCancelledError,
    JobFailedError,
    JobLimits,
    JobOverMemoryError,
    JobRunner,
    JobTimeoutError,
    PoolClosedError,
    PoolError,
    PoolStartingError,
    Progress,
    QueueFullError,
    WorkerCrashedError,
    exit_reason,
)
from service.worker.process import worker_main
from skelprune.budget import mib, resident_bytes

__all__ = [
    "JobCancelledError",
    "JobFailedError",
    "JobOverMemoryError",
    "JobRunner",
    "JobTimeoutError",
    "PoolClosedError",
    "PoolError",
    "PoolStartingError",
    "Progress",
    "QueueFullError",
    "WorkerCrashedError",
    "WorkerPool",
]

log = logging.getLogger("service.pool")

#: Seconds between two samples of a running job's resident set.
MEMORY_SAMPLE_SECONDS = 0.02


class _Worker:
    """One worker process and the parent's end of its pipe."""

    def __init__(self, ctx: Any, initializer: Callable[[], object] | None) -> None:
        self.conn, child = ctx.Pipe(duplex=True)
        self.proc = ctx.Process(
            target=worker_main, args=(child, initializer), daemon=True, name="skelprune-worker"
        )
        self.proc.start()
        child.close()
        self.ready = False
        self.warm_bytes = 0  # resident set when warm (the parent measures it)
        # kill() can race: the job's thread replacing a dead worker and close()
        # stopping every worker may both get here; the pipe must be closed once.
        self._kill_lock = threading.Lock()

    def wait_ready(self, timeout: float) -> str | None:
        """Wait for the worker's warm-up; returns what its initializer reported."""
        if self.ready:
            return None
        if not self.conn.poll(timeout):
            raise WorkerCrashedError(
                f"worker did not start within {timeout:g} s (SKELPRUNE_STARTUP_TIMEOUT)"
            )
        tag, info = self._receive("worker died while starting ({reason})")
        if tag != "ready":
            raise WorkerCrashedError(f"worker failed to start: {info}")
        self.ready = True
        self.warm_bytes = resident_bytes(self.proc.pid)
        return info

    def _receive(self, died: str) -> tuple[str, Any]:
        """The worker's next message; a closed pipe means it died: ``died`` names how."""
        try:
            return self.conn.recv()
        except (EOFError, OSError):
            self.proc.join(1)
            raise WorkerCrashedError(died.format(reason=exit_reason(self.proc.exitcode))) from None

    def resident(self) -> int:
        """The worker's resident set now, bytes."""
        return resident_bytes(self.proc.pid)

    def call(
        self,
        fn: Callable[..., Any],
        args: tuple[Any, ...],
        timeout: float,
        memory_limit: int | None = None,
        progress: Progress | None = None,
        cancel: threading.Event | None = None,
    ) -> Any:
        self.conn.send((fn, args))
        deadline = time.monotonic() + timeout
        while True:
            self._wait(timeout, deadline, memory_limit, cancel)
            tag, payload = self._receive(
                "the worker process died while running this job ({reason}); it has been replaced"
            )
            if tag != "progress":  # a job's progress comes before its answer
                break
            if progress is not None:
                progress(*payload)
        if tag == "ok":
            return payload
        if tag == "error":
            raise payload
        message, trace = payload
        log.error("job failed in worker: %s", message)
        log.debug("worker traceback:\n%s", trace)  # only at SKELPRUNE_LOG_LEVEL=debug
        raise JobFailedError("the job failed with an internal error")

    def _wait(
        self,
        timeout: float,
        deadline: float,
        memory_limit: int | None,
        cancel: threading.Event | None,
    ) -> None:
        """Wait for the job's next message; its resident set is sampled meanwhile, and
        its ``cancel`` event watched."""
        timed_out = JobTimeoutError(f"job exceeded the time limit of {timeout:g} s and was stopped")
        if memory_limit is None and cancel is None:
            if not self.conn.poll(max(0.0, deadline - time.monotonic())):
                raise timed_out
            return
        while not self.conn.poll(MEMORY_SAMPLE_SECONDS):
            if cancel is not None and cancel.is_set():
                raise JobCancelledError("the job was cancelled and its worker stopped")
            held = self.resident() if memory_limit is not None else 0
            if memory_limit is not None and held > memory_limit:
                raise JobOverMemoryError(
                    f"this input needed more than the memory budget of {mib(memory_limit)} "
                    f"a job (its worker held {mib(held)}) and was stopped: send fewer pixels "
                    "or a cleaner mask"
                )
            if time.monotonic() > deadline:
                raise timed_out

    def stop(self, grace: float = 1.0) -> None:
        with contextlib.suppress(OSError):
            self.conn.send(None)
        self.proc.join(grace)
        self.kill()

    def kill(self) -> None:
        with self._kill_lock:
            if self.proc.is_alive():
                self.proc.kill()
            self.proc.join(5)
            if not self.conn.closed:
                self.conn.close()


class WorkerPool:
    """Fixed-size pool of killable worker processes, used from asyncio.

    Parameters
    ----------
    size : int
        Number of worker processes.
    queue_size : int
        Jobs allowed to wait for a free worker.
    job_timeout : float
        Seconds a job may run before its worker is killed.
    initializer : callable, optional
        Module-level function run once in every new worker (warm-up); what it returns,
        if not None, goes to the log when the pool starts.
    startup_timeout : float
        Seconds a new worker may take to run ``initializer``.
    context : str
        multiprocessing start method, ``"forkserver"`` or ``"spawn"``. With the fork
        server, ``preload`` is imported once and each new worker is a cheap fork of it,
        so replacing a killed worker takes milliseconds, not an interpreter start.
    preload : sequence of str
        Modules the fork server imports up front (``forkserver`` only).
    memory_limit : int, optional
        Bytes a worker may hold while it runs a job (its own memory included): its
        resident set is sampled every :data:`MEMORY_SAMPLE_SECONDS`, and a worker over
        the limit is killed and replaced (:class:`JobOverMemoryError`).
    recycle_slack : int
        A worker holding more than this many bytes above its warm resident set after a
        job is replaced (only with a ``memory_limit``).
    """

    def __init__(
        self,
        size: int,
        *,
        queue_size: int,
        job_timeout: float,
        initializer: Callable[[], object] | None = None,
        startup_timeout: float = 300.0,
        context: str = "forkserver",
        preload: Sequence[str] = (),
        memory_limit: int | None = None,
        recycle_slack: int = 256 * 2**20,
    ) -> None:
        self.size = size
        self.memory_limit = memory_limit
        self.recycle_slack = recycle_slack
        self.queue_size = queue_size
        self.job_timeout = job_timeout
        self.startup_timeout = startup_timeout
        self._initializer = initializer
        self._ctx = mp.get_context(context)
        if context == "forkserver":
            # Only takes effect before the (process-wide) fork server first starts.
            self._ctx.set_forkserver_preload(["service.worker.pool", *preload])
        self._idle: asyncio.Queue[_Worker | None] | None = None  # None: "pool closed"
        self._workers: set[_Worker] = set()
        self._lock = threading.Lock()
        self._executor: ThreadPoolExecutor | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self.waiting = 0
        self.waiting_unqueued = 0  # jobs run with queue=False waiting for a worker
        self.busy = 0
        self.restarts = 0
        self.recycled = 0
        self.started = False
        self.starting = False
        self.closed = False
        self.on_restart: Callable[[str], None] | None = None
        self.on_job_done: Callable[[float], None] | None = None

    # -- lifecycle -----------------------------------------------------------------
    async def start(self) -> None:
        """Start every worker and wait until all have warmed up (again, after a close).

        The first worker warms up alone, then the others together: on a cold numba
        cache the first one compiles the kernels and the others load what it cached,
        instead of every worker compiling the same code at once on shared cores.
        """
        self.closed = False
        self.starting = True
        self.waiting = self.waiting_unqueued = self.busy = 0
        loop = self._loop = asyncio.get_running_loop()
        self._idle = asyncio.Queue()
        self._executor = ThreadPoolExecutor(self.size, thread_name_prefix="skelprune-pool")
        t0 = time.perf_counter()
        try:
            first = await self._spawn_in_thread()
            info = await loop.run_in_executor(
                self._executor, first.wait_ready, self.startup_timeout
            )
            log.info(
                "worker 1 of %d warm in %.1f s%s",
                self.size,
                time.perf_counter() - t0,
                f": {info}" if info else "",
            )
            rest = [await self._spawn_in_thread() for _ in range(self.size - 1)]
            infos = await asyncio.gather(
                *(
                    loop.run_in_executor(self._executor, w.wait_ready, self.startup_timeout)
                    for w in rest
                )
            )
            for i, info in enumerate(infos, start=2):
                log.info("worker %d of %d warm%s", i, self.size, f": {info}" if info else "")
        finally:
            self.starting = False
        if self.closed:  # closed while starting: close() has stopped the workers
            raise PoolClosedError("the worker pool was closed while it was starting")
        for w in (first, *rest):
            self._idle.put_nowait(w)
        self.started = True
        log.info("worker pool ready: %d workers in %.1f s", self.size, time.perf_counter() - t0)

    @property
    def warm(self) -> int:
        """Workers that have finished warming up (while the pool starts)."""
        with self._lock:
            return sum(w.ready for w in self._workers)

    async def close(self) -> None:
        """Stop all workers (running jobs are killed, waiting ones get PoolClosedError)."""
        self.closed = True
        if self._idle is not None:
            for _ in range(self.waiting + self.waiting_unqueued):
                self._idle.put_nowait(None)
        with self._lock:
            workers = list(self._workers)
            self._workers.clear()
        await asyncio.gather(*(asyncio.to_thread(w.stop) for w in workers))
        if self._executor is not None:
            self._executor.shutdown(wait=False, cancel_futures=True)

    async def _spawn_in_thread(self) -> _Worker:
        # in a thread: a fork server's first start imports the library, a second or more
        assert self._loop is not None
        worker = await self._loop.run_in_executor(self._executor, self._spawn)
        if self.closed:  # close() ran meanwhile and did not see this one
            worker.kill()
            raise PoolClosedError("the worker pool was closed while it was starting")
        return worker

    def _spawn(self) -> _Worker:
        worker = _Worker(self._ctx, self._initializer)
        with self._lock:
            self._workers.add(worker)
        return worker

    def _replace(self, worker: _Worker, reason: str) -> _Worker:
        worker.kill()
        with self._lock:
            self._workers.discard(worker)
        if self.closed:  # shutting down: nothing to replace it for
            return worker
        self.restarts += 1
        log.warning("worker replaced: %s", reason)
        if self.on_restart is not None:
            self.on_restart(reason)
        return self._spawn()

    # -- state ---------------------------------------------------------------------
    @property
    def ready(self) -> bool:
        """Started, not closing, and a new job would not be refused."""
        if not self.started or self.closed or self._idle is None:
            return False
        return not self._idle.empty() or self.waiting < self.queue_size

    def alive(self) -> int:
        """Number of worker processes currently alive."""
        with self._lock:
            return sum(w.proc.is_alive() for w in self._workers)

    # -- jobs ----------------------------------------------------------------------
    async def run(
        self,
        fn: Callable[..., Any],
        *args: Any,
        timeout: float | None = None,
        progress: Progress | None = None,
        cancel: threading.Event | None = None,
        queue: bool = True,
    ) -> Any:
        """Run ``fn(*args)`` in a worker and return its result.

        ``fn`` and its arguments must be picklable (module-level function).
        Domain errors (:class:`SkelpruneError`) raised by ``fn`` are re-raised here.

        Parameters
        ----------
        timeout : float, optional
            Seconds the job may run (default: the pool's ``job_timeout``).
        progress : callable, optional
            Called with each ``(done, total)`` the job reports, in the job's thread.
        cancel : threading.Event, optional
            Set, it stops the job: its worker is killed and replaced
            (:class:`JobCancelledError`).
        queue : bool
            Count the job in the wait queue (refused when it is full); ``False`` for
            jobs admitted by a limit of their own (long jobs), which wait for a worker
            without taking a place in the queue.
        """
        if self.starting and not self.closed:
            raise PoolStartingError(
                f"the worker pool is warming up ({self.warm} of {self.size} workers ready)"
            )
        if not self.started or self.closed or self._idle is None or self._loop is None:
            raise PoolClosedError("the worker pool is not running")
        if queue and self._idle.empty() and self.waiting >= self.queue_size:
            raise QueueFullError(
                f"all {self.size} workers are busy and {self.waiting} jobs are already waiting"
            )
        if queue:
            self.waiting += 1
        else:
            self.waiting_unqueued += 1
        try:
            worker = await self._idle.get()
        finally:
            if queue:
                self.waiting -= 1
            else:
                self.waiting_unqueued -= 1
        if worker is None:
            raise PoolClosedError("the worker pool shut down while this job was waiting")
        self.busy += 1
        assert self._executor is not None
        # in the caller's context: what the job thread logs carries the request's ID
        ctx = contextvars.copy_context()
        limits = JobLimits(self.job_timeout if timeout is None else timeout, progress, cancel)
        fut = self._loop.run_in_executor(
            self._executor, ctx.run, self._run_on, worker, fn, args, limits
        )
        return await fut

    def _recycle_if_grown(self, worker: _Worker) -> _Worker:
        """Replace a worker whose resident set did not come back after its job."""
        if self.memory_limit is None or not worker.warm_bytes:
            return worker
        held = worker.resident()
        if held <= worker.warm_bytes + self.recycle_slack:
            return worker
        self.recycled += 1
        return self._replace(
            worker,
            f"it held {mib(held)} after a job, {mib(held - worker.warm_bytes)} more than when warm",
        )

    def _release(self, worker: _Worker) -> None:
        self.busy -= 1
        if self.closed:
            worker.stop(0.1)
            if self._idle is not None and (self.waiting or self.waiting_unqueued):
                self._idle.put_nowait(None)
        elif self._idle is not None:
            self._idle.put_nowait(worker)

    def _run_on(
        self, worker: _Worker, fn: Callable[..., Any], args: tuple[Any, ...], limits: JobLimits
    ) -> Any:
        """Thread body: run one job, replace the worker on timeout/crash, always hand it back."""
        assert self._loop is not None
        try:
            if not worker.proc.is_alive():  # died while idle (e.g. OOM killer): no job lost
                worker = self._replace(worker, f"found dead ({exit_reason(worker.proc.exitcode)})")
            try:
                worker.wait_ready(self.startup_timeout)
            except WorkerCrashedError as exc:
                worker = self._replace(worker, str(exc))
                raise
            if limits.cancel is not None and limits.cancel.is_set():  # before it starts
                raise JobCancelledError("the job was cancelled before it started")
            t0 = time.perf_counter()
            try:
                result = worker.call(
                    fn, args, limits.timeout, self.memory_limit, limits.progress, limits.cancel
                )
            except (
                JobTimeoutError,
                WorkerCrashedError,
                JobOverMemoryError,
                JobCancelledError,
            ) as exc:
                worker = self._replace(worker, str(exc))
                raise
            except OSError as exc:  # broken pipe on send: the worker is gone
                worker = self._replace(worker, f"pipe error: {exc}")
                raise WorkerCrashedError(
                    "the worker process died before it took this job; it has been replaced"
                ) from None
            except BaseException:  # the input's error: the worker lives on, if it shrank
                worker = self._recycle_if_grown(worker)
                raise
            worker = self._recycle_if_grown(worker)
            if self.on_job_done is not None:
                self.on_job_done(time.perf_counter() - t0)
            return result
        finally:
            self._loop.call_soon_threadsafe(self._release, worker)
