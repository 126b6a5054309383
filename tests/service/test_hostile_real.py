"""Hostile connections against the real server: header limits, read timeouts, dropped
clients, unknown methods, no banner, TCP_NODELAY on accepted sockets, pipelined bad
requests, upgrades, redirects and the size of the answer's headers."""

from __future__ import annotations

import asyncio
import io
import json
import socket
import time
from collections.abc import Iterator
from pathlib import Path

import httpx
import numpy as np
import pytest
from PIL import Image

from service.__main__ import listen
from testkit.realserver import running_server

pytestmark = pytest.mark.timeout(180)

LIMITS = {
    "workers": "1",
    "warmup": "false",
    "header_timeout": "1",
    "body_timeout": "2",
    "max_header_bytes": "4096",
    "max_headers": "20",
}


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[str, int, Path]]:
    log = tmp_path_factory.mktemp("hostile") / "server.log"
    with running_server(log, **LIMITS) as (_, base):
        yield base, int(base.rsplit(":", 1)[1]), log


def exchange(port: int, data: bytes, close_after: float | None = None) -> bytes:
    """Send ``data``, read until the server closes (at most 10 s)."""
    with socket.create_connection(("127.0.0.1", port), timeout=10) as sock:
        sock.sendall(data)
        out = b""
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            try:
                piece = sock.recv(65536)
            except (TimeoutError, ConnectionResetError):
                break
            if not piece:
                break
            out += piece
        return out


def status_and_type(answer: bytes) -> tuple[int, str]:
    head = answer.split(b"\r\n\r\n", 1)[0].decode("latin-1").split("\r\n")
    ctype = next(
        (h.split(":", 1)[1].strip() for h in head if h.lower().startswith("content-type")), ""
    )
    return int(head[0].split()[1]), ctype


PROBLEM = "application/problem+json"


def test_listening_socket_gives_accepted_connections_tcp_nodelay() -> None:
    sock = listen("127.0.0.1", 0)
    assert sock.proto == socket.IPPROTO_TCP
    port = sock.getsockname()[1]
    seen: list[int] = []

    async def main() -> None:
        async def handle(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
            raw = writer.get_extra_info("socket")
            seen.append(raw.getsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY))
            writer.close()

        server = await asyncio.start_server(handle, sock=sock)
        async with server:
            _, writer = await asyncio.open_connection("127.0.0.1", port)
            for _ in range(100):
                if seen:
                    break
                await asyncio.sleep(0.01)
            writer.close()

    asyncio.run(main())
    assert seen and seen[0] != 0


def test_no_software_banner(server: tuple[str, int, Path]) -> None:
    base, _, _ = server
    resp = httpx.get(f"{base}/healthz")
    assert resp.status_code == 200 and "server" not in resp.headers


def test_headers_over_the_size_limit_get_431(server: tuple[str, int, Path]) -> None:
    _, port, _ = server
    big = b"GET /healthz HTTP/1.1\r\nHost: x\r\nX-Big: " + b"a" * 200_000 + b"\r\n\r\n"
    assert status_and_type(exchange(port, big)) == (431, PROBLEM)


def test_too_many_header_fields_get_431(server: tuple[str, int, Path]) -> None:
    _, port, _ = server
    many = b"GET /healthz HTTP/1.1\r\nHost: x\r\n" + b"".join(b"X-%d: 1\r\n" % i for i in range(50))
    assert status_and_type(exchange(port, many + b"\r\n")) == (431, PROBLEM)


def test_an_unknown_method_gets_a_problem(server: tuple[str, int, Path]) -> None:
    _, port, _ = server
    assert status_and_type(exchange(port, b"FOO /healthz HTTP/1.1\r\nHost: x\r\n\r\n")) == (
        400,
        PROBLEM,
    )


def test_slow_headers_are_cut_off_with_408(server: tuple[str, int, Path]) -> None:
    _, port, _ = server
    assert status_and_type(exchange(port, b"GET /healthz HTTP/1.1\r\nHo")) == (408, PROBLEM)


def test_a_silent_connection_is_closed(server: tuple[str, int, Path]) -> None:
    _, port, _ = server
    assert exchange(port, b"") == b""  # closed by the server (the read ends before 10 s)


def test_a_slow_body_is_cut_off_with_408(server: tuple[str, int, Path]) -> None:
    _, port, _ = server
    head = b"POST /v1/prune HTTP/1.1\r\nHost: x\r\nContent-Type: image/png\r\n"
    answer = exchange(port, head + b"Content-Length: 1000\r\n\r\n\x89PNG")
    assert status_and_type(answer) == (408, PROBLEM)
    assert b"connection: close" in answer.lower()


def _prune_counts(base: str) -> dict[str, float]:
    counts: dict[str, float] = {}
    for line in httpx.get(f"{base}/metrics").text.splitlines():
        if line.startswith("http_requests_total") and 'handler="/v1/prune"' in line:
            status = line.split('status="', 1)[1].split('"', 1)[0]
            counts[status] = counts.get(status, 0.0) + float(line.rsplit(" ", 1)[1])
    return counts


def test_a_client_gone_mid_body_is_not_a_server_error(server: tuple[str, int, Path]) -> None:
    base, port, log = server
    before = _prune_counts(base)
    head = b"POST /v1/prune HTTP/1.1\r\nHost: x\r\nContent-Type: image/png\r\n"
    with socket.create_connection(("127.0.0.1", port), timeout=10) as sock:
        sock.sendall(head + b"Content-Length: 100000\r\n\r\n\x89PNG\r\n")
        time.sleep(0.2)
    after = before
    for _ in range(50):  # the server notices the close within a moment
        after = _prune_counts(base)
        if sum(after.values()) > sum(before.values()):
            break
        time.sleep(0.1)
    assert after.get("4xx", 0) == before.get("4xx", 0) + 1, (before, after)
    assert after.get("5xx", 0) == 0
    assert '"level": "ERROR"' not in log.read_text()


# ---------------------------------------------------------------- pipelining, upgrades
def answers(raw: bytes) -> list[tuple[int, str, bytes]]:
    """The HTTP/1.1 answers in ``raw``, in order: status, content type, body (each
    answer has a Content-Length)."""
    out = []
    while raw:
        head, _, rest = raw.partition(b"\r\n\r\n")
        lines = head.decode("latin-1").split("\r\n")
        fields = {k.strip().lower(): v.strip() for k, _, v in (h.partition(":") for h in lines[1:])}
        length = int(fields.get("content-length", "0"))
        out.append((int(lines[0].split()[1]), fields.get("content-type", ""), rest[:length]))
        raw = rest[length:]
    return out


@pytest.mark.parametrize(
    ("bad", "status"),
    [
        (b"NOT HTTP AT ALL\r\n\r\n", 400),
        (b"GET /healthz HTTP/1.1\r\nHost: x\r\nX-Big: " + b"a" * 8000 + b"\r\n\r\n", 431),
    ],
)
def test_a_pipelined_bad_request_is_answered_after_the_good_one(
    server: tuple[str, int, Path], bad: bytes, status: int
) -> None:
    _, port, _ = server
    good = b"GET /healthz HTTP/1.1\r\nHost: x\r\n\r\n"
    raw = exchange(port, good + bad)
    got = answers(raw)
    assert [(s, t) for s, t, _ in got] == [(200, "application/json"), (status, PROBLEM)]
    assert b'"status":"ok"' in got[0][2].replace(b" ", b"")
    # the bad request's ID is its own (in its header and body), not the good one's
    rid = json.loads(got[1][2])["request_id"].encode()
    assert raw.count(rid) == 2


def test_a_pipelined_prune_keeps_its_answer_and_nothing_is_logged_as_an_error(
    server: tuple[str, int, Path],
) -> None:
    _, port, log = server
    body = json.dumps(
        {"type": "Polygon", "coordinates": [[[0, 0], [8, 0], [8, 8], [0, 8], [0, 0]]]}
    ).encode()
    good = (
        b"POST /v1/prune HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
        b"Content-Length: %d\r\n\r\n" % len(body) + body
    )
    got = answers(exchange(port, good + b"GET /healthz HTTP/1.1\r\nHost: x\r\nBad header\r\n\r\n"))
    assert [(s, t) for s, t, _ in got] == [(200, "application/json"), (400, PROBLEM)]
    assert json.loads(got[0][2])["components"]
    text = log.read_text()
    for sign in ("RuntimeError", '"level": "ERROR"', "without completing response"):
        assert sign not in text


def test_a_websocket_upgrade_is_answered_as_http(server: tuple[str, int, Path]) -> None:
    _, port, _ = server
    upgrade = (
        b"Host: x\r\nConnection: Upgrade\r\nUpgrade: websocket\r\n"
        b"Sec-WebSocket-Version: 13\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n\r\n"
    )
    got = answers(exchange(port, b"GET /healthz HTTP/1.1\r\n" + upgrade))
    assert got[0][:2] == (200, "application/json")
    got = answers(exchange(port, b"GET /v1/socket HTTP/1.1\r\n" + upgrade))
    assert got[0][:2] == (404, PROBLEM) and json.loads(got[0][2])["status"] == 404


def test_a_trailing_slash_redirect_does_not_repeat_the_clients_host(
    server: tuple[str, int, Path],
) -> None:
    base, _, _ = server
    resp = httpx.get(f"{base}/healthz/?x=1", headers={"Host": "evil.example"})
    assert resp.status_code == 307
    assert resp.headers["location"] == "/healthz?x=1"


def test_png_answer_headers_stay_within_a_proxys_buffer(server: tuple[str, int, Path]) -> None:
    """841 components: their per-component values would be ~12 KB of headers, over the
    4-KiB page nginx buffers an upstream's headers in by default (it answers 502)."""
    base, _, _ = server
    mask = np.zeros((60, 60), np.uint8)
    mask[1:-1:2, 1:-1:2] = 255
    buf = io.BytesIO()
    Image.fromarray(mask).save(buf, "PNG")
    params = {"foreground": "nonzero"}
    png_headers = {"content-type": "image/png", "accept": "image/png"}
    resp = httpx.post(
        f"{base}/v1/prune", content=buf.getvalue(), params=params, headers=png_headers, timeout=60
    )
    assert resp.status_code == 200, resp.text
    size = sum(len(k) + len(v) + 4 for k, v in resp.headers.raw)
    assert size < 4096 - 512, resp.headers  # room for what a proxy adds
    assert resp.headers["x-skelprune-components"] == "841"
    assert "application/json" in resp.headers["x-skelprune-values"]
    assert "x-skelprune-rer" not in resp.headers
    few = np.zeros((24, 24), np.uint8)
    few[4:20, 4:10] = few[4:20, 14:20] = 255
    buf = io.BytesIO()
    Image.fromarray(few).save(buf, "PNG")
    resp = httpx.post(
        f"{base}/v1/prune", content=buf.getvalue(), params=params, headers=png_headers, timeout=60
    )
    assert len(resp.headers["x-skelprune-rer"].split(",")) == 2
    assert "x-skelprune-values" not in resp.headers
