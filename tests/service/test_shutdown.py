"""Graceful shutdown of the real server process (``python -m service``).

On SIGTERM the server must stop accepting connections, let the requests in flight (running
and queued) finish with their normal answer, close its worker pool and exit with code 0.
This is what ``docker stop``, ``podman stop`` and Kubernetes do to a container.
"""

from __future__ import annotations

import http.client
import io
import json
import math
import signal
import socket
import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from testkit import DATA
from testkit.realserver import running_server

pytestmark = [pytest.mark.slow, pytest.mark.timeout(300)]


def shape_png(longest_side: int) -> bytes:
    """A dataset shape scaled up (nearest neighbour) so its longer side is ``longest_side``."""
    path = sorted((DATA / "kimia216").glob("*.png"))[0]
    with Image.open(path) as im:
        mask = np.asarray(im.convert("L")) > 0
    h, w = mask.shape
    scale = longest_side / max(h, w)
    big = Image.fromarray(mask.astype(np.uint8) * 255).resize(
        (round(w * scale), round(h * scale)), Image.NEAREST
    )
    buf = io.BytesIO()
    big.save(buf, format="PNG")
    return buf.getvalue()


def post_png(port: int, body: bytes, sent: threading.Event | None = None) -> tuple[int, bytes]:
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=120)
    try:
        conn.request("POST", "/v1/prune", body=body, headers={"Content-Type": "image/png"})
        if sent is not None:
            sent.set()
        resp = conn.getresponse()
        return resp.status, resp.read()
    finally:
        conn.close()


def refuses_connections(port: int) -> bool:
    try:
        with socket.create_connection(("127.0.0.1", port), timeout=1.0):
            return False
    except (ConnectionRefusedError, ConnectionResetError):
        return True
    except OSError:
        return False


def children_of(pid: int) -> set[int]:
    """Direct and indirect child processes of ``pid`` (Linux /proc)."""
    parents: dict[int, int] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:
            continue
        # the command name may hold spaces: the ppid is the 2nd field after the last ')'
        parents[int(entry.name)] = int(stat.rsplit(")", 1)[1].split()[1])
    found: set[int] = set()
    frontier = {pid}
    while frontier:
        frontier = {c for c, p in parents.items() if p in frontier} - found
        found |= frontier
    return found


def alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


class InFlight(threading.Thread):
    def __init__(self, port: int, body: bytes):
        super().__init__(daemon=True)
        self.port, self.body = port, body
        self.status: int | None = None
        self.payload = b""
        self.error: BaseException | None = None
        self.done_at: float | None = None
        self.sent = threading.Event()

    def run(self) -> None:
        try:
            self.status, self.payload = post_png(self.port, self.body, self.sent)
        except BaseException as exc:
            self.error = exc
        self.done_at = time.monotonic()


@pytest.fixture
def server(tmp_path):
    """The real server with one worker (the requests queue up behind each other and stay
    in flight longer): its process, port, and a function giving the tail of its log."""
    log = tmp_path / "server.log"
    settings = {"workers": "1", "queue_size": "32", "job_timeout": "120"}
    with running_server(log, **settings) as (proc, base):
        yield proc, int(base.rsplit(":", 1)[1]), lambda: log.read_text(errors="replace")[-4000:]


def test_sigterm_drains_in_flight_requests_then_exits_cleanly(server):
    proc, port, output = server

    # A shape big enough that one prune takes a noticeable time on this machine (grow it
    # until it does), then enough of them that the queued work outlasts the signal by far.
    side, body, took = 384, b"", 0.0
    while True:
        body = shape_png(side)
        t0 = time.monotonic()
        status, payload = post_png(port, body)
        took = time.monotonic() - t0
        assert status == 200, payload[:2000]
        if took >= 0.5 or side >= 2048:
            break
        side = min(2048, int(side * 1.5))
    n = min(8, max(3, math.ceil(3.0 / took)))

    workers = children_of(proc.pid)
    assert workers, "the worker pool runs in child processes"

    requests = [InFlight(port, body) for _ in range(n)]
    for r in requests:
        r.start()
    for r in requests:
        assert r.sent.wait(timeout=30), f"request not sent: {r.error!r}"
    # give the server's event loop a moment to read them all: the first one is running,
    # the others wait in the queue
    time.sleep(min(0.3, took / 3))

    proc.send_signal(signal.SIGTERM)
    signalled = time.monotonic()

    # it stops accepting at once, while the accepted requests are still being served
    refused_at = None
    while time.monotonic() < signalled + 10 and proc.poll() is None:
        if refuses_connections(port):
            refused_at = time.monotonic()
            break
        time.sleep(0.05)
    assert refused_at is not None or proc.poll() is not None, output()
    pending_when_refused = (
        sum(1 for r in requests if r.done_at is None or r.done_at > refused_at)
        if refused_at is not None
        else 0
    )

    # every accepted request gets its normal answer
    for r in requests:
        r.join(timeout=60 + n * took * 4)
        assert not r.is_alive(), f"request still hanging after SIGTERM:\n{output()}"
        assert r.error is None, f"in-flight request failed: {r.error!r}\n{output()}"
        assert r.status == 200, f"in-flight request got {r.status}: {r.payload[:500]!r}"
        doc = json.loads(r.payload)
        assert doc["components"] and doc["components"][0]["skeleton"]["endpoints"]
    assert max(r.done_at for r in requests) > signalled, "nothing was in flight at SIGTERM"

    # ... then the process exits with 0 and its workers are gone too
    try:
        code = proc.wait(timeout=60)
    except subprocess.TimeoutExpired:
        pytest.fail(f"server still running 60 s after its last request:\n{output()}")
    assert code == 0, f"exit code {code}:\n{output()}"
    assert pending_when_refused > 0, (
        "new connections were not refused while requests were still in flight:\n" + output()
    )
    deadline = time.monotonic() + 15
    while any(alive(w) for w in workers) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not any(alive(w) for w in workers), "worker processes outlived the server"
    assert refuses_connections(port)
