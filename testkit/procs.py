"""A server's processes from Linux ``/proc``: its workers, and what they hold."""

from __future__ import annotations

from pathlib import Path

__all__ = ["descendants", "rss_mib"]


def descendants(pid: int) -> list[int]:
    """The process's children and theirs, from every thread's ``children`` (Linux
    ``/proc``: the pool starts its workers from threads)."""
    found, todo = [], [pid]
    while todo:
        p = todo.pop()
        for children in Path(f"/proc/{p}/task").glob("*/children"):
            try:
                kids = [int(k) for k in children.read_text().split()]
            except OSError:
                continue
            found += kids
            todo += kids
    return found


def rss_mib(pid: int) -> float:
    """The process's resident set, MiB (0 when it is gone)."""
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    except OSError:
        pass
    return 0.0
