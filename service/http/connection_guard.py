"""HTTP/1.1 connection guards below the application: header limits and read timeouts.

uvicorn's httptools protocol reads a request's line and headers without a limit on
their size or count and without a deadline, so one client can hold a connection (and
its buffers) open for as long as it trickles bytes. :func:`guarded_protocol` makes a
subclass that

- refuses a request whose line and headers are over ``max_header_bytes``, or that has
  more than ``max_headers`` fields (431);
- closes a connection whose request line and headers take longer than
  ``header_timeout`` seconds (408 if the request had begun; a new connection that
  stays silent is closed without a word);
- answers a request the parser cannot read (malformed, or an unknown method: 400)

each with problem details and ``Connection: close``. A refusal that follows valid
requests on the same connection (pipelining) is written after their answers, in order;
nothing after it is read. An ``Upgrade`` (WebSocket) is not taken up: the request is
answered as plain HTTP. The body's deadline is the application's
(:class:`service.app.BodyLimitMiddleware`): it knows when a body is done.
"""

from __future__ import annotations

import asyncio
import http
import logging
import uuid
from dataclasses import dataclass
from typing import Any

import httptools
from uvicorn.protocols.http.httptools_impl import HttpToolsProtocol

from service.errors import (
    BadRequestError,
    HeaderTooLargeError,
    RequestTimeoutError,
    problem,
)
from service.logs import request_id_var

__all__ = ["Limits", "guarded_protocol"]

log = logging.getLogger("service.access")
#: Seconds a refused connection keeps reading (and dropping) before it closes.
LINGER_SECONDS = 2.0


@dataclass(frozen=True)
class Limits:
    max_header_bytes: int
    max_headers: int
    header_timeout: float


def _raw_answer(exc: Exception) -> bytes:
    """A complete HTTP/1.1 response with the problem of ``exc``, under a request ID of
    its own (never the previous request's on the connection); the connection closes."""
    rid = uuid.uuid4().hex
    token = request_id_var.set(rid)
    try:
        response = problem(exc, headers={"x-request-id": rid})
    finally:
        request_id_var.reset(token)
    status = response.status_code
    head = [f"HTTP/1.1 {status} {http.HTTPStatus(status).phrase}"]
    head += [f"{k}: {v}" for k, v in response.headers.items()]
    head.append("connection: close")
    return ("\r\n".join(head) + "\r\n\r\n").encode("latin-1") + bytes(response.body)


class _Refused(Exception):
    """Raised from a parser callback to stop parsing: the connection is answered."""

    def __init__(self, error: Exception) -> None:
        self.error = error


class GuardedHttpToolsProtocol(HttpToolsProtocol):
    """uvicorn's httptools protocol with :class:`Limits` (see the module docstring)."""

    limits: Limits = Limits(16 * 1024, 100, 10.0)

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._head_bytes = 0
        self._head_fields = 0
        self._in_head = False  # a request has begun and its headers are not complete
        self._fed = 0  # bytes fed to the parser on this connection
        self._head_start = 0
        self._head_timer: asyncio.TimerHandle | None = None
        self._discarding = False  # refused: what comes is dropped
        self._refusal: Exception | None = None  # to write once the answers before it are

    # -- the header deadline ------------------------------------------------------
    def _arm(self) -> None:
        if self._head_timer is None:
            self._head_timer = self.loop.call_later(self.limits.header_timeout, self._too_slow)

    def _disarm(self) -> None:
        if self._head_timer is not None:
            self._head_timer.cancel()
            self._head_timer = None

    def _too_slow(self) -> None:
        self._head_timer = None
        if self.transport.is_closing():
            return
        if self._in_head:
            self._answer(
                RequestTimeoutError(
                    f"the request line and headers took longer than "
                    f"{self.limits.header_timeout:g} s"
                )
            )
        elif self.cycle is None:  # a connection that never sent a request
            self.transport.close()

    def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
        super().connection_made(transport)
        self._arm()

    def connection_lost(self, exc: Exception | None) -> None:
        self._disarm()
        super().connection_lost(exc)

    # -- counting -------------------------------------------------------------------
    def _count(self, n: int, fields: int = 0) -> None:
        self._head_bytes += n
        self._head_fields += fields
        if self._head_fields > self.limits.max_headers:
            raise _Refused(
                HeaderTooLargeError(
                    f"more than {self.limits.max_headers} header fields in one request"
                )
            )
        if self._head_bytes > self.limits.max_header_bytes:
            raise _Refused(
                HeaderTooLargeError(
                    f"the request line and headers are over {self.limits.max_header_bytes} bytes"
                )
            )

    def on_message_begin(self) -> None:
        super().on_message_begin()
        self._head_bytes = self._head_fields = 0
        self._in_head = True
        self._head_start = self._fed
        self._arm()

    def on_url(self, url: bytes) -> None:
        self._count(len(url))
        super().on_url(url)

    def on_header(self, name: bytes, value: bytes) -> None:
        self._count(len(name) + len(value) + 4, 1)
        super().on_header(name, value)

    def on_headers_complete(self) -> None:
        self._in_head = False
        self._disarm()
        super().on_headers_complete()

    # -- answering ------------------------------------------------------------------
    def _answer(self, error: Exception) -> None:
        self._disarm()
        log.info("refused a request: %s", error, extra={"status": problem(error).status_code})
        if self.transport.is_closing() or self._discarding:
            return
        self._discarding = True
        if self._answering():
            # pipelined after requests still being answered: their answers go first
            self._refusal = error
            return
        self._refuse(error)

    def _answering(self) -> bool:
        """A request before this one is still being answered, or waits to be."""
        return bool(self.pipeline) or (self.cycle is not None and not self.cycle.response_complete)

    def _refuse(self, error: Exception) -> None:
        self.transport.write(_raw_answer(error))
        # A lingering close: closing with the client's bytes still unread would reset the
        # connection, and the client could lose the answer. Half-close, drop what still
        # comes for a moment, then close.
        if self.transport.can_write_eof():
            self.transport.write_eof()
        self.loop.call_later(LINGER_SECONDS, self.transport.close)

    def on_response_complete(self) -> None:
        super().on_response_complete()
        if self._refusal is not None and not self._answering():
            error, self._refusal = self._refusal, None
            if not self.transport.is_closing():
                self._refuse(error)

    def _should_upgrade(self) -> bool:
        return False  # no WebSocket here: the request is answered as HTTP

    def _unsupported_upgrade_warning(self) -> None:
        pass  # not a server problem: the Upgrade header is ignored, as HTTP allows

    def data_received(self, data: bytes) -> None:
        # uvicorn's, but a refusal or a parser error is answered with problem details
        self._unset_keepalive_if_required()
        if self.transport.is_closing() or self._discarding:
            return
        self._fed += len(data)
        try:
            self.parser.feed_data(data)
        except httptools.HttpParserUpgrade:
            if self._should_upgrade():
                self.handle_websocket_upgrade()
            else:
                self._unsupported_upgrade_warning()
            return
        except httptools.HttpParserInvalidMethodError:
            self._answer(BadRequestError("unknown request method"))
            return
        except httptools.HttpParserError as exc:
            refused = exc.__context__
            if isinstance(refused, _Refused):
                self._answer(refused.error)
            else:
                self._answer(BadRequestError("the request is not valid HTTP/1.1"))
            return
        # a header line still arriving is not counted by on_header yet: bound it here
        if self._in_head and self._fed - self._head_start > self.limits.max_header_bytes + 1024:
            self._answer(
                HeaderTooLargeError(
                    f"the request line and headers are over {self.limits.max_header_bytes} bytes"
                )
            )


def guarded_protocol(limits: Limits) -> type[GuardedHttpToolsProtocol]:
    """A :class:`GuardedHttpToolsProtocol` subclass with these limits (uvicorn's
    ``Config(http=...)`` takes a class)."""
    return type("GuardedHttpToolsProtocol", (GuardedHttpToolsProtocol,), {"limits": limits})
