"""Start-up of the real server process (``python -m service``) on 127.0.0.1.

The port is bound before anything slow: ``/healthz`` answers 200 at once, ``/readyz``
and jobs answer 503 with a problem body until the workers have warmed up, and on a cold
numba cache only the first worker compiles (the others load what it cached). An
address in use, or a worker that cannot start, stops the server with one line.
"""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import httpx
import pytest

from testkit import DATA, REPO
from testkit.realserver import free_port

PNG = (DATA / "kimia216" / "bird-2.png").read_bytes()

pytestmark = [pytest.mark.slow, pytest.mark.timeout(400)]


def server_env(port: int, **settings: str) -> dict[str, str]:
    env = {
        **os.environ,
        "SKELPRUNE_HOST": "127.0.0.1",
        "SKELPRUNE_PORT": str(port),
        "OMP_NUM_THREADS": "1",
        "NUMBA_NUM_THREADS": "1",
    }
    env.pop("SKELPRUNE_API_KEY", None)
    env.update(
        {k if k.startswith("NUMBA_") else f"SKELPRUNE_{k.upper()}": v for k, v in settings.items()}
    )
    return env


def start(port: int, log: Path, **settings: str) -> subprocess.Popen[bytes]:
    with log.open("wb") as out:
        return subprocess.Popen(
            [sys.executable, "-m", "service"],
            cwd=REPO,
            env=server_env(port, **settings),
            stdout=out,
            stderr=subprocess.STDOUT,
            start_new_session=True,
        )


def kill(proc: subprocess.Popen[bytes]) -> None:
    if proc.poll() is None:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait(30)


def messages(log: Path) -> list[str]:
    out = []
    for line in log.read_text(errors="replace").splitlines():
        try:
            out.append(json.loads(line)["message"])
        except (ValueError, KeyError, TypeError):
            out.append(line)
    return out


def test_cold_cache_probes_tell_the_truth_and_one_worker_compiles(tmp_path: Path) -> None:
    """An empty NUMBA_CACHE_DIR: the first worker compiles (tens of seconds), and all the
    while the port answers: /healthz 200, /readyz and /v1/prune 503 ``starting``."""
    port, log = free_port(), tmp_path / "server.log"
    proc = start(port, log, workers="2", log_level="info", NUMBA_CACHE_DIR=str(tmp_path / "nc"))
    base = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 60
        while True:  # the port opens before the first worker has compiled anything
            assert proc.poll() is None, log.read_text()[-3000:]
            try:
                health = httpx.get(f"{base}/healthz", timeout=5)
                break
            except httpx.TransportError:
                assert time.monotonic() < deadline, "port not open within 60 s"
                time.sleep(0.1)
        assert health.status_code == 200 and health.json()["status"] == "ok"
        ready = httpx.get(f"{base}/readyz", timeout=5)
        assert ready.status_code == 503
        assert ready.headers["content-type"] == "application/problem+json"
        assert ready.headers["retry-after"]
        body = ready.json()
        assert body["type"] == "urn:skelprune:problem:starting"
        assert body["status"] == 503
        assert "warming up (0 of 2 workers ready)" in body["detail"]
        job = httpx.post(
            f"{base}/v1/prune", content=PNG, headers={"Content-Type": "image/png"}, timeout=10
        )
        assert job.status_code == 503
        assert job.json()["type"] == "urn:skelprune:problem:starting"
        deadline = time.monotonic() + 300
        while httpx.get(f"{base}/readyz", timeout=5).status_code != 200:
            assert proc.poll() is None, log.read_text()[-3000:]
            assert time.monotonic() < deadline, "not ready within 300 s"
            time.sleep(0.5)
        job = httpx.post(
            f"{base}/v1/prune", content=PNG, headers={"Content-Type": "image/png"}, timeout=60
        )
        assert job.status_code == 200 and job.json()["components"]
    finally:
        kill(proc)
    said = messages(log)
    first = next(m for m in said if m.startswith("worker 1 of 2 warm"))
    second = next(m for m in said if m.startswith("worker 2 of 2 warm"))
    assert "compiled" in first, first  # the cold cache was compiled, once, by worker 1
    assert "compiled" not in second and "loaded from the cache" in second, second
    assert any(m.startswith("starting 2 workers") for m in said)
    assert said.index(next(m for m in said if m.startswith("listening on"))) < said.index(first)


def test_port_in_use_fails_at_once_with_one_line(tmp_path: Path) -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        log = tmp_path / "server.log"
        proc = start(port, log, log_level="info")
        try:
            code = proc.wait(60)
        finally:
            kill(proc)
    lines = log.read_text().splitlines()
    assert code == 1
    assert lines == [
        f"skelprune: cannot listen on 127.0.0.1:{port} (SKELPRUNE_HOST, "
        "SKELPRUNE_PORT): Address already in use"
    ], lines
    # it failed before starting any worker: no warm-up to wait for


def test_worker_that_cannot_start_stops_the_server_with_one_line(tmp_path: Path) -> None:
    """A start-up limit no warm-up can meet: the server says why and exits 1, no traceback."""
    port, log = free_port(), tmp_path / "server.log"
    proc = start(port, log, workers="1", startup_timeout="0.001", log_level="info")
    try:
        code = proc.wait(120)
    finally:
        kill(proc)
    text = log.read_text()
    assert code == 1
    assert "Traceback" not in text
    last = text.splitlines()[-1]
    assert last == (
        "skelprune: the worker pool failed to start: worker did not start "
        "within 0.001 s (SKELPRUNE_STARTUP_TIMEOUT)"
    ), last
    assert "the worker pool failed to start" in " ".join(messages(log)[:-1])  # logged too


def test_warm_start_serves_after_make_setup(tmp_path: Path) -> None:
    """With the kernels compiled ahead (``make setup``), every worker loads them."""
    port, log = free_port(), tmp_path / "server.log"
    proc = start(port, log, workers="2", log_level="info")
    base = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 120
        while True:
            assert proc.poll() is None, log.read_text()[-3000:]
            try:
                if httpx.get(f"{base}/readyz", timeout=5).status_code == 200:
                    break
            except httpx.TransportError:
                pass
            assert time.monotonic() < deadline, "not ready within 120 s"
            time.sleep(0.1)
        assert (
            httpx.post(
                f"{base}/v1/prune", content=PNG, headers={"Content-Type": "image/png"}, timeout=60
            ).status_code
            == 200
        )
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(60) == 0
    finally:
        kill(proc)
    warm = [m for m in messages(log) if " of 2 warm" in m]
    assert len(warm) == 2
    assert all("loaded from the cache" in m and "compiled" not in m for m in warm), warm


def test_the_entry_point_imports_no_library_before_it_seeds() -> None:
    # Importing skelprune writes numba's cache index into NUMBA_CACHE_DIR, and the seed
    # copies the image's prebuilt cache only into an empty folder: python -m service must
    # bind its port and seed before anything imports the library.
    code = "import sys, service, service.__main__; print('skelprune' in sys.modules)"
    done = subprocess.run(
        [sys.executable, "-c", code],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
    )
    assert done.stdout.strip() == "False"
