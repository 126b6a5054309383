"""The killable worker pool, with job functions of our own (sleep, crash, raise)."""

from __future__ import annotations

import asyncio
import os
import signal
import time
from collections.abc import Awaitable, Callable
from typing import Any

import pytest

from service.worker.pool import (
    JobFailedError,
    JobOverMemoryError,
    JobTimeoutError,
    PoolClosedError,
    QueueFullError,
    WorkerCrashedError,
    WorkerPool,
)
from skelprune.errors import EmptyMaskError

pytestmark = pytest.mark.timeout(120)


# Job functions: module level, so that spawned workers can unpickle them.
def add(a: int, b: int) -> int:
    return a + b


def pid_after(seconds: float) -> int:
    time.sleep(seconds)
    return os.getpid()


def hang() -> None:
    time.sleep(3600)


def die(code: int) -> None:
    os._exit(code)


def segfault() -> None:
    os.kill(os.getpid(), signal.SIGSEGV)


def bad_input() -> None:
    raise EmptyMaskError("no foreground here")


def bug() -> None:
    raise RuntimeError("secret internal state")


def failing_init() -> None:
    raise RuntimeError("cannot warm up")


def run(coro_fn: Callable[[WorkerPool], Awaitable[Any]], **kw: Any) -> Any:
    """Start a pool, run ``coro_fn(pool)``, always close the pool."""

    async def main() -> Any:
        pool = WorkerPool(
            kw.pop("size", 1),
            queue_size=kw.pop("queue_size", 4),
            job_timeout=kw.pop("job_timeout", 20.0),
            **kw,
        )
        await pool.start()
        try:
            return await coro_fn(pool)
        finally:
            await pool.close()
            assert pool.alive() == 0

    return asyncio.run(main())


def test_results_and_domain_errors_pass_through() -> None:
    async def body(pool: WorkerPool) -> None:
        assert await pool.run(add, 2, 3) == 5
        with pytest.raises(EmptyMaskError, match="no foreground here"):
            await pool.run(bad_input)
        assert await pool.run(add, 1, 1) == 2  # same worker still fine
        assert pool.restarts == 0

    run(body)


def test_unexpected_exception_hides_internals() -> None:
    async def body(pool: WorkerPool) -> None:
        with pytest.raises(JobFailedError) as info:
            await pool.run(bug)
        assert "secret" not in str(info.value)
        assert pool.restarts == 0 and await pool.run(add, 0, 1) == 1

    run(body)


def test_timeout_kills_and_replaces_the_worker() -> None:
    async def body(pool: WorkerPool) -> None:
        first = await pool.run(pid_after, 0)
        with pytest.raises(JobTimeoutError, match=r"time limit of 0\.5 s"):
            await pool.run(hang)
        assert pool.restarts == 1
        pool.job_timeout = 20.0
        second = await pool.run(pid_after, 0)
        assert second != first  # a new process took over
        assert pool.alive() == 1

    run(body, job_timeout=0.5)


@pytest.mark.parametrize(
    ("job", "args", "reason"),
    [(die, (7,), "exit code 7"), (segfault, (), "SIGSEGV")],
)
def test_crash_is_reported_and_the_pool_keeps_serving(
    job: Callable[..., None], args: tuple[int, ...], reason: str
) -> None:
    async def body(pool: WorkerPool) -> None:
        with pytest.raises(WorkerCrashedError, match=reason):
            await pool.run(job, *args)
        assert pool.restarts == 1
        assert await pool.run(add, 20, 22) == 42

    run(body)


def test_worker_dead_while_idle_is_replaced_without_failing_a_job() -> None:
    async def body(pool: WorkerPool) -> None:
        victim = await pool.run(pid_after, 0)
        os.kill(victim, signal.SIGKILL)
        await asyncio.sleep(0.2)  # let the kernel reap it
        assert await pool.run(add, 1, 2) == 3
        assert pool.restarts == 1

    run(body)


def test_workers_run_in_parallel_in_distinct_processes() -> None:
    async def body(pool: WorkerPool) -> None:
        pids = await asyncio.gather(pool.run(pid_after, 0.3), pool.run(pid_after, 0.3))
        assert len(set(pids)) == 2 and os.getpid() not in pids

    run(body, size=2)


def test_bounded_queue() -> None:
    async def body(pool: WorkerPool) -> None:
        running = asyncio.create_task(pool.run(pid_after, 1.0))
        while pool.busy == 0:
            await asyncio.sleep(0.01)
        waiting = asyncio.create_task(pool.run(add, 1, 1))
        while pool.waiting == 0:
            await asyncio.sleep(0.01)
        assert not pool.ready
        with pytest.raises(QueueFullError, match="1 jobs are already waiting"):
            await pool.run(add, 2, 2)
        assert await waiting == 2
        await running
        assert pool.ready and pool.waiting == 0 and pool.busy == 0

    run(body, queue_size=1)


def test_cancelled_request_does_not_leak_the_worker() -> None:
    async def body(pool: WorkerPool) -> None:
        task = asyncio.create_task(pool.run(pid_after, 0.3))
        while pool.busy == 0:
            await asyncio.sleep(0.01)
        task.cancel()
        assert await pool.run(add, 3, 4) == 7  # waits for the worker to come back

    run(body)


def test_failing_initializer_fails_start() -> None:
    async def main() -> None:
        pool = WorkerPool(1, queue_size=1, job_timeout=5, initializer=failing_init)
        try:
            with pytest.raises(WorkerCrashedError, match="cannot warm up"):
                await pool.start()
        finally:
            await pool.close()

    asyncio.run(main())


def test_closed_pool_refuses_jobs() -> None:
    async def main() -> None:
        pool = WorkerPool(1, queue_size=1, job_timeout=5)
        with pytest.raises(PoolClosedError):
            await pool.run(add, 1, 1)
        assert not pool.ready

    asyncio.run(main())


def test_close_fails_waiting_jobs_instead_of_hanging() -> None:
    async def main() -> None:
        pool = WorkerPool(1, queue_size=4, job_timeout=20)
        await pool.start()
        running = asyncio.create_task(pool.run(pid_after, 0.5))
        while pool.busy == 0:
            await asyncio.sleep(0.01)
        waiting = asyncio.create_task(pool.run(add, 1, 1))
        while pool.waiting == 0:
            await asyncio.sleep(0.01)
        await pool.close()
        with pytest.raises(PoolClosedError, match="shut down while this job was waiting"):
            await waiting
        # The running job either finished inside the stop grace period or lost its
        # worker; what matters is that it answers instead of hanging.
        (outcome,) = await asyncio.gather(running, return_exceptions=True)
        assert isinstance(outcome, int | WorkerCrashedError | PoolClosedError), outcome
        assert pool.alive() == 0

    asyncio.run(main())


def test_spawn_context_works_too() -> None:
    async def body(pool: WorkerPool) -> None:
        assert await pool.run(add, 2, 2) == 4

    run(body, context="spawn")


# -- memory: the worker's resident set, not its address space ---------------------------
_KEPT: list[Any] = []


def touch(mib: int) -> int:
    """Allocate and touch ``mib`` MiB, free it; the worker's pid."""
    block = bytearray(mib * 2**20)
    block[::4096] = b"\x01" * len(block[::4096])
    del block
    return os.getpid()


def keep(mib: int) -> int:
    """Allocate, touch and keep ``mib`` MiB (a job that leaves memory behind)."""
    block = bytearray(mib * 2**20)
    block[::4096] = b"\x01" * len(block[::4096])
    _KEPT.append(block)
    return os.getpid()


def reserve(gib: int) -> int:
    """Reserve ``gib`` GiB of address space without touching it (what allocators and
    thread arenas do): it is not memory the job uses."""
    import mmap

    _KEPT.append(mmap.mmap(-1, gib * 2**30, flags=mmap.MAP_PRIVATE | mmap.MAP_ANONYMOUS))
    return os.getpid()


def test_a_worker_over_its_memory_limit_is_stopped_and_replaced() -> None:
    async def body(pool: WorkerPool) -> None:
        first = await pool.run(touch, 16)  # well under the limit: answered, same worker
        assert await pool.run(touch, 16) == first and pool.restarts == 0
        with pytest.raises(JobOverMemoryError, match="memory budget of 400 MiB"):
            await pool.run(touch, 1024)
        assert pool.restarts == 1
        assert await pool.run(add, 2, 2) == 4  # the replacement serves at once
        assert pool.alive() == 1

    run(body, memory_limit=400 * 2**20)


def test_virtual_memory_is_not_what_a_job_is_refused_for() -> None:
    async def body(pool: WorkerPool) -> None:
        first = await pool.run(reserve, 8)  # 8 GiB reserved, nothing touched
        assert await pool.run(touch, 64) == first  # the same worker serves on
        assert pool.restarts == 0

    run(body, memory_limit=400 * 2**20)


def test_a_worker_whose_memory_did_not_come_back_is_recycled() -> None:
    async def body(pool: WorkerPool) -> None:
        first = await pool.run(keep, 8)  # within the slack: kept
        assert await pool.run(add, 1, 1) == 2 and pool.recycled == 0
        assert await pool.run(keep, 96) == first  # answered, then the worker is replaced
        assert pool.recycled == 1 and pool.restarts == 1
        assert await pool.run(pid_after, 0) != first
        assert pool.alive() == 1

    run(body, memory_limit=600 * 2**20, recycle_slack=64 * 2**20)
