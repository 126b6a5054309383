"""A real Dask cluster on 127.0.0.1: ``dask scheduler`` and ``dask worker`` processes
over TCP, started as an operator starts them (the path a cluster's tasks take)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from .realserver import free_port

#: Seconds the cluster may take to come up (the workers import the library).
START_TIMEOUT = 120.0


def _dask() -> str:
    exe = Path(sys.executable).parent / "dask"
    assert exe.exists(), "dask is not installed (the parallel extra)"
    return str(exe)


def _stop(procs: list[subprocess.Popen[bytes]]) -> None:
    for proc in procs:  # each its own process group: the worker's nanny and its child
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGTERM)
    deadline = time.monotonic() + 20
    for proc in procs:
        try:
            proc.wait(timeout=max(0.1, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(timeout=10)


@contextmanager
def dask_cluster(folder: Path, workers: int = 2, memory_limit: str = "3GiB") -> Iterator[str]:
    """A scheduler and ``workers`` one-thread worker processes on 127.0.0.1; yields the
    scheduler's address (``tcp://127.0.0.1:PORT``). Logs go to ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    env = {**os.environ, "OMP_NUM_THREADS": "1", "NUMBA_NUM_THREADS": "1"}
    procs: list[subprocess.Popen[bytes]] = []

    def start(args: list[str], log: str) -> None:
        with (folder / log).open("wb") as out:
            procs.append(
                subprocess.Popen(
                    [_dask(), *args],
                    stdout=out,
                    stderr=subprocess.STDOUT,
                    env=env,
                    start_new_session=True,
                )
            )

    try:
        start(
            ["scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"],
            "scheduler.log",
        )
        for i in range(workers):
            start(
                [
                    "worker",
                    address,
                    "--host",
                    "127.0.0.1",
                    "--nthreads",
                    "1",
                    "--no-dashboard",
                    "--memory-limit",
                    memory_limit,
                    "--name",
                    f"worker-{i}",
                    "--death-timeout",
                    "60",
                ],
                f"worker-{i}.log",
            )
        _wait_for_workers(address, workers, procs, folder)
        yield address
    finally:
        _stop(procs)


def _wait_for_workers(
    address: str, n: int, procs: list[subprocess.Popen[bytes]], folder: Path
) -> None:
    code = (
        "import json, sys\n"
        "from distributed import Client\n"
        "with Client(sys.argv[1], timeout=60) as c:\n"
        "    c.wait_for_workers(int(sys.argv[2]), timeout=float(sys.argv[3]))\n"
        "    print(json.dumps(len(c.nthreads())))\n"
    )
    try:
        out = subprocess.run(
            [sys.executable, "-c", code, address, str(n), str(START_TIMEOUT)],
            capture_output=True,
            text=True,
            timeout=START_TIMEOUT + 30,
            check=True,
        )
    except (subprocess.CalledProcessError, subprocess.TimeoutExpired) as exc:
        logs = "\n".join(p.read_text()[-2000:] for p in sorted(folder.glob("*.log")))
        dead = [p.args for p in procs if p.poll() is not None]
        message = f"the Dask cluster did not start ({exc}); exited: {dead}\n{logs}"
        raise AssertionError(message) from None
    assert json.loads(out.stdout) == n
