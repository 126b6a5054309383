"""A real ``python -m service`` process on a free loopback port, as a user starts it."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import httpx

from . import REPO

Running = tuple[subprocess.Popen[bytes], str]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@contextmanager
def running_server(
    log_path: Path,
    ready: str = "/readyz",
    python: str = sys.executable,
    cwd: Path = REPO,
    env_extra: dict[str, str] | None = None,
    **settings: str,
) -> Iterator[Running]:
    """Start the server with ``SKELPRUNE_<NAME>`` settings, wait until ``ready`` is 200.

    Yields the process and its base URL; output goes to ``log_path``. A server the test
    did not stop itself is killed (with its workers) on exit. No API key unless given.
    ``python`` and ``cwd`` start another installation (an installed wheel, say);
    ``env_extra`` adds environment variables.
    """
    port = free_port()
    env = {
        **os.environ,
        "SKELPRUNE_HOST": "127.0.0.1",
        "SKELPRUNE_PORT": str(port),
        "SKELPRUNE_LOG_LEVEL": "warning",
        "OMP_NUM_THREADS": "1",
        "NUMBA_NUM_THREADS": "1",
    }
    env.pop("SKELPRUNE_API_KEY", None)
    env.pop("SKELPRUNE_MAIN_MEMORY_MB", None)  # the default a user gets (tests/conftest.py)
    env.update(env_extra or {})
    env.update({f"SKELPRUNE_{k.upper()}": v for k, v in settings.items()})
    with log_path.open("wb") as log:
        proc = subprocess.Popen(
            [python, "-m", "service"],
            cwd=cwd,
            env=env,
            stdout=log,
            stderr=subprocess.STDOUT,
            start_new_session=True,
        )
        base = f"http://127.0.0.1:{port}"
        try:
            deadline = time.monotonic() + 120
            while True:
                assert proc.poll() is None, log_path.read_text(errors="replace")[-3000:]
                try:
                    if httpx.get(f"{base}{ready}", timeout=2).status_code == 200:
                        break
                except httpx.TransportError:
                    pass
                assert time.monotonic() < deadline, f"{ready} not 200 within 120 s"
                time.sleep(0.2)
            yield proc, base
        finally:
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait(30)


def stop(
    proc: subprocess.Popen[bytes], sig: int = signal.SIGTERM, timeout: float = 60
) -> int | None:
    """Ask the server to stop; its exit code, or None if it had to be killed."""
    proc.send_signal(sig)
    try:
        return proc.wait(timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait(30)
        return None
