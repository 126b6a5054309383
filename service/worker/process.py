"""The loop each worker process runs: warm up, say ready, then run jobs until told to
stop, giving the C heap's free pages back after each (so that the resident set the pool
watches is what the worker still uses). The parent side is :mod:`service.worker.pool`.
"""

from __future__ import annotations

import functools
import signal
import traceback
from collections.abc import Callable
from multiprocessing.connection import Connection
from typing import Any

from skelprune.errors import SkelpruneError

__all__ = ["report_progress", "worker_main"]

#: This worker's end of its pipe (set by :func:`worker_main`): where progress goes.
_parent: Connection | None = None


def report_progress(done: int, total: int) -> None:
    """Tell the parent how far the running job is (``("progress", (done, total))``, read
    by the pool before the job's answer); outside a worker it does nothing."""
    if _parent is not None:
        _parent.send(("progress", (int(done), int(total))))


@functools.cache
def _malloc_trim() -> Any:
    """glibc's ``malloc_trim``, loaded once a worker (None: not glibc)."""
    import ctypes

    try:
        return ctypes.CDLL("libc.so.6").malloc_trim
    except (OSError, AttributeError):
        return None


def _trim_heap() -> None:
    """Give the C heap's free pages back to the system (glibc), so that the resident
    set after a job is what the worker still uses."""
    trim = _malloc_trim()
    if trim is not None:
        trim(0)


def worker_main(conn: Connection, initializer: Callable[[], object] | None) -> None:
    """Worker process: warm up, say ready (with what the initializer returned, for the
    log), then run ``(fn, args)`` jobs until told to stop."""
    global _parent
    _parent = conn
    # Ctrl-C in a terminal reaches the whole process group; the parent decides when we stop.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    info = None
    try:
        if initializer is not None:
            info = initializer()
    except BaseException as exc:  # report, then exit: the parent replaces us
        conn.send(("init-failed", f"{type(exc).__name__}: {exc}"))
        return
    conn.send(("ready", None if info is None else str(info)))
    while True:
        try:
            msg = conn.recv()
        except (EOFError, OSError):
            return
        if msg is None:
            return
        fn, args = msg
        try:
            reply: tuple[str, Any] = ("ok", fn(*args))
        except SkelpruneError as exc:  # the caller's fault: travels back as itself
            reply = ("error", exc)
        except Exception as exc:
            reply = ("failed", (f"{type(exc).__name__}: {exc}", traceback.format_exc()))
        del msg, fn, args  # the job's input is freed before the heap is trimmed
        try:
            conn.send(reply)
        except Exception as exc:  # unpicklable result or exception
            conn.send(("failed", (f"cannot send result: {exc}", traceback.format_exc())))
        del reply
        _trim_heap()
