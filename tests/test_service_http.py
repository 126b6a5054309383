"""`python -m service` as a real process on 127.0.0.1, spoken to over HTTP."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import httpx
import pytest

pytestmark = pytest.mark.timeout(180)

REPO = Path(__file__).resolve().parents[1]
BIRD = (REPO.parent / "shared" / "data" / "kimia216" / "bird-10.png").read_bytes()


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_real_server_round_trip() -> None:
    port = free_port()
    env = {**os.environ, "SKELPRUNE_HOST": "127.0.0.1", "SKELPRUNE_PORT": str(port),
           "SKELPRUNE_WORKERS": "1", "SKELPRUNE_LOG_LEVEL": "warning"}
    proc = subprocess.Popen([sys.executable, "-m", "service"], cwd=REPO, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    base = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 120
        while True:
            assert proc.poll() is None, proc.stdout.read().decode() if proc.stdout else ""
            try:
                if httpx.get(f"{base}/healthz", timeout=1).status_code == 200:
                    break
            except httpx.TransportError:
                pass
            assert time.monotonic() < deadline, "server did not come up"
            time.sleep(0.2)
        with httpx.Client(base_url=base, timeout=30) as client:
            assert client.get("/readyz").json()["workers"] == 1
            doc = client.post("/v1/prune", content=BIRD,
                              headers={"content-type": "image/png"}).json()
            assert (doc["width"], doc["height"]) == (116, 103)
            assert len(doc["components"]) == 1
            png = client.post("/v1/prune", files={"file": ("b.png", BIRD, "image/png")},
                              headers={"accept": "image/png"})
            assert png.status_code == 200 and png.content.startswith(b"\x89PNG")
            poly = client.post("/v1/prune", json={"type": "Polygon", "coordinates": [
                [[0, 0], [4, 0], [4, 2], [0, 2], [0, 0]]]},
                headers={"accept": "application/geo+json"})
            assert poly.headers["content-type"] == "application/geo+json"
            bad = client.post("/v1/prune", content=b"nope",
                              headers={"content-type": "image/png"})
            assert bad.status_code == 400
            assert bad.headers["content-type"] == "application/problem+json"
            assert "http_requests_total" in client.get("/metrics").text
    finally:
        proc.send_signal(signal.SIGINT)  # uvicorn's graceful shutdown, pool closed
        try:
            code = proc.wait(30)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(10)
            code = None
    assert code == 0
