"""Latency of a kept-alive connection against a fresh one, on loopback.

A real ``python -m service`` (one worker) gets, one at a time, ``GET /healthz`` and a
small ``POST /v1/prune`` (a 10 × 10 GeoJSON square, rasterised to 64 px), each
``REQUESTS`` times on one kept-alive connection and ``REQUESTS`` times on a new
connection each, interleaved so that a slow spell of a shared machine hits both. Plain
sockets and hand-written HTTP/1.1, so that the client adds nothing of its own (no
pooling, no Nagle: the request goes out in one ``sendall``). The server sets
``TCP_NODELAY`` on accepted connections: without it, every answer after the first on
a kept connection waited for the client's delayed ACK (~40 ms).

``python -m benchmarks keepalive`` (about half a minute).
"""

from __future__ import annotations

import json
import socket
import statistics
import tempfile
import time
from pathlib import Path

from testkit.realserver import running_server

from .common import table

REQUESTS = 200
SQUARE = json.dumps(
    {"type": "Polygon", "coordinates": [[[0, 0], [10, 0], [10, 10], [0, 10], [0, 0]]]}
).encode()


def _request(method: str, path: str, body: bytes = b"", ctype: str = "") -> bytes:
    head = f"{method} {path} HTTP/1.1\r\nHost: bench\r\n"
    if body:
        head += f"Content-Type: {ctype}\r\nContent-Length: {len(body)}\r\n"
    return (head + "\r\n").encode() + body


def _read_response(sock: socket.socket) -> int:
    """Read one response (Content-Length framed); returns its status."""
    data = b""
    while b"\r\n\r\n" not in data:
        chunk = sock.recv(65536)
        if not chunk:
            raise ConnectionError("closed before the answer")
        data += chunk
    head, _, rest = data.partition(b"\r\n\r\n")
    lines = head.split(b"\r\n")
    length = next(
        int(line.split(b":", 1)[1]) for line in lines if line.lower().startswith(b"content-length")
    )
    while len(rest) < length:
        chunk = sock.recv(65536)
        if not chunk:
            raise ConnectionError("closed mid-answer")
        rest += chunk
    return int(lines[0].split()[1])


def _connect(port: int) -> socket.socket:
    sock = socket.create_connection(("127.0.0.1", port), timeout=30)
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    return sock


def measure(port: int, request: bytes) -> tuple[list[float], list[float]]:
    """Milliseconds per request: on one kept connection, and on a fresh one each."""
    kept_sock = _connect(port)
    sock = kept_sock
    sock.sendall(request)  # the first answer on a connection is not a kept-alive one
    _read_response(sock)
    kept, fresh = [], []
    for _ in range(REQUESTS):
        t = time.perf_counter()
        kept_sock.sendall(request)
        assert _read_response(kept_sock) == 200
        kept.append(1000 * (time.perf_counter() - t))
        t = time.perf_counter()
        with _connect(port) as sock:
            sock.sendall(request)
            assert _read_response(sock) == 200
        fresh.append(1000 * (time.perf_counter() - t))
    kept_sock.close()
    return kept, fresh


def _p95(values: list[float]) -> float:
    return statistics.quantiles(values, n=20)[-1]


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        log = Path(tmp) / "server.log"
        with running_server(log, workers="1", access_log="false") as (_, base):
            port = int(base.rsplit(":", 1)[1])
            rows = []
            for name, request in (
                ("GET /healthz", _request("GET", "/healthz")),
                (
                    "POST /v1/prune (10 × 10 square, 64 px)",
                    _request("POST", "/v1/prune?longest_side=64", SQUARE, "application/json"),
                ),
            ):
                kept, fresh = measure(port, request)
                rows.append(
                    [
                        name,
                        f"{statistics.median(kept):.2f}",
                        f"{_p95(kept):.2f}",
                        f"{statistics.median(fresh):.2f}",
                        f"{_p95(fresh):.2f}",
                        f"{statistics.median(kept) - statistics.median(fresh):+.2f}",
                    ]
                )
    print(
        table(
            [
                "request",
                "kept-alive median, ms",
                "kept-alive p95, ms",
                "fresh median, ms",
                "fresh p95, ms",
                "kept − fresh (medians), ms",
            ],
            rows,
        )
    )
    print(f"\n{REQUESTS} requests of each kind on each connection kind, interleaved.")


if __name__ == "__main__":
    main()
