"""``python -m service``: serve on SKELPRUNE_HOST:SKELPRUNE_PORT."""

from __future__ import annotations

import logging
import logging.config
import os
import signal
import socket
import sys
from types import FrameType
from typing import Any

from pydantic import ValidationError

from service.logs import logging_config
from service.settings import Settings, settings_error
from service.worker.numba_seed import seed_numba_cache


def _exit_cleanly(signum: int, frame: FrameType | None) -> None:
    sys.exit(0)


def listen(host: str, port: int) -> socket.socket:
    """A listening TCP socket on ``host:port`` (IPv6 when ``host`` has a colon).

    Raises
    ------
    SystemExit
        With a one-line message, when the address cannot be bound (e.g. in use).
    """
    # IPPROTO_TCP spelled out: asyncio sets TCP_NODELAY only on sockets whose protocol
    # says TCP, and accepted sockets inherit it. Without it, Nagle's algorithm holds a
    # kept-alive connection's small answers until the client's delayed ACK (~40 ms).
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM, socket.IPPROTO_TCP)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((host, port))
        sock.listen(2048)
    except OSError as exc:
        sock.close()
        raise SystemExit(
            f"skelprune: cannot listen on {host}:{port} "
            f"(SKELPRUNE_HOST, SKELPRUNE_PORT): {exc.strerror or exc}"
        ) from None
    sock.set_inheritable(True)
    return sock


def main() -> None:
    """Read the settings from the environment and run uvicorn (one process; the
    pruning work is spread over the app's own worker pool).

    The port is bound first, before anything slow: an address in use fails at once,
    and clients can connect while the workers warm up (``/healthz`` 200, ``/readyz``
    503 until they are ready).
    """
    try:
        settings = Settings()
    except ValidationError as exc:  # one line naming the variable, not a traceback
        print(f"error: {settings_error(exc)}", file=sys.stderr)
        sys.exit(2)
    logging.config.dictConfig(logging_config(settings.log_level))  # uvicorn sets it again
    sock = listen(settings.host, settings.port)
    host, port = sock.getsockname()[:2]
    logging.getLogger("service").info("listening on %s:%d", host, port)
    cache = os.environ.get("NUMBA_CACHE_DIR")
    if settings.numba_cache_seed and cache:
        # before the pool starts: its workers read the cache when they warm up
        copied = seed_numba_cache(settings.numba_cache_seed, cache)
        logging.getLogger("service").info("numba cache seeded: %d files", copied)
    import uvicorn  # only after the port is bound: a port in use fails sooner

    from service.app import create_app  # only now: importing it already compiles
    from service.http.connection_guard import Limits, guarded_protocol

    # uvicorn drains in-flight requests and closes the pool on SIGTERM/SIGINT, then
    # re-raises the signal under the handlers it found. These make that final step a
    # clean exit 0 (what `docker stop` and Kubernetes expect) instead of death by signal.
    for sig in (signal.SIGTERM, signal.SIGINT):
        signal.signal(sig, _exit_cleanly)
    server: Any = None  # the uvicorn.Server, once made

    def stop_server() -> None:  # the pool failed to start: nothing to serve
        if server is not None:
            server.should_exit = True

    app = create_app(settings, warm_in_background=True, on_pool_failure=stop_server)
    server = uvicorn.Server(
        uvicorn.Config(
            app,
            log_level=settings.log_level,
            log_config=logging_config(settings.log_level),  # JSON lines on stderr
            access_log=False,  # the service writes its own access log, with request IDs
            # httptools (the service extra) with header limits and a header deadline
            http=guarded_protocol(
                Limits(settings.max_header_bytes, settings.max_headers, settings.header_timeout)
            ),
            timeout_keep_alive=settings.keep_alive_timeout,
            server_header=False,  # no software banner on every answer
            # a drain after SIGTERM is bounded: below the orchestrator's grace period
            timeout_graceful_shutdown=settings.shutdown_timeout,
        )
    )
    server.run(sockets=[sock])
    if app.state.pool_failure is not None:
        raise SystemExit(f"skelprune: the worker pool failed to start: {app.state.pool_failure}")


if __name__ == "__main__":
    main()
