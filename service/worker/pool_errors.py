"""The worker pool's failures (never the caller's input) and the interface of what runs
a request's jobs; :mod:`service.worker.pool` re-exports them."""

from __future__ import annotations

import signal
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

__all__ = [
    "JobCancelledError",
    "JobFailedError",
    "JobLimits",
    "JobOverMemoryError",
    "JobRunner",
    "JobTimeoutError",
    "PoolClosedError",
    "PoolError",
    "PoolStartingError",
    "Progress",
    "QueueFullError",
    "WorkerCrashedError",
    "exit_reason",
]


class PoolError(Exception):
    """Base class of pool failures (never the caller's input)."""


class QueueFullError(PoolError):
    """All workers are busy and the wait queue is full."""


class PoolClosedError(PoolError):
    """The pool is not started or is shutting down."""


class PoolStartingError(PoolClosedError):
    """The pool is still warming up its workers (a 503 that will pass)."""


class JobTimeoutError(PoolError):
    """The job ran over its time limit; its worker was killed and replaced."""


class WorkerCrashedError(PoolError):
    """The worker process died while running the job; it was replaced."""


class JobOverMemoryError(PoolError):
    """The job's worker held more than its memory limit; it was killed and replaced."""


class JobCancelledError(PoolError):
    """The job's ``cancel`` event was set; its worker was killed and replaced."""


#: ``progress(done, total)`` of a running job, called from the pool's job thread.
Progress = Callable[[int, int], None]


class JobRunner(Protocol):
    """What runs a request's jobs: the :class:`WorkerPool`, or a long job's runner
    (:class:`service.worker.long_jobs.LongJobRunner`) in front of it."""

    async def run(self, fn: Callable[..., Any], *args: Any) -> Any: ...


class JobFailedError(PoolError):
    """The job raised an unexpected exception inside the worker (a bug, not bad input)."""


@dataclass(frozen=True)
class JobLimits:
    """One job's time limit, progress callback and cancel event."""

    timeout: float
    progress: Progress | None = None
    cancel: threading.Event | None = None


def exit_reason(code: int | None) -> str:
    """How a worker process ended, from its exit code, for the log and the problem."""
    if code is None:
        return "did not exit"
    if code < 0:
        try:
            return f"killed by signal {signal.Signals(-code).name}"
        except ValueError:
            return f"killed by signal {-code}"
    return f"exit code {code}"
