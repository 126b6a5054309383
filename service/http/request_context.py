"""Each request's context: its ID and its access-log line, the outermost middleware.

:class:`RequestContextMiddleware` gives every request an ID (the
  client's ``X-Request-ID`` when it is sane, else a fresh one), echoes it in the
  response, makes it available to problem bodies (:data:`request_id_var`), writes the
  request's one access-log line (method, path, status, duration, request id) and turns
any exception that escaped everything else into a 500 problem without internals (503 for
one cut short by a shutdown).
"""

from __future__ import annotations

import asyncio
import logging
import re
import time
import uuid

from starlette.types import ASGIApp, Message, Receive, Scope, Send

from service.errors import InternalError, problem
from service.logs import request_id_var
from service.worker.pool import PoolClosedError

__all__ = ["REQUEST_ID_HEADER", "RequestContextMiddleware", "header"]

access_log = logging.getLogger("service.access")
log = logging.getLogger("service.errors")

REQUEST_ID_HEADER = "X-Request-ID"
_SANE_ID = re.compile(rb"^[A-Za-z0-9._:\-]{1,128}$")


def header(scope: Scope, name: bytes) -> bytes | None:
    """A request header's raw value (the first of that name), or None."""
    for key, value in scope["headers"]:
        if key == name:
            return value
    return None


class RequestContextMiddleware:
    """Request ID, one JSON access-log line per request, last-resort 500."""

    def __init__(self, app: ASGIApp, *, access_log_enabled: bool = True) -> None:
        self.app = app
        self.access_log_enabled = access_log_enabled

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        given = header(scope, b"x-request-id")
        rid = given.decode("ascii") if given and _SANE_ID.match(given) else uuid.uuid4().hex
        request_id_var.set(rid)
        scope.setdefault("state", {})["request_id"] = rid
        status = 500
        started = False
        t0 = time.perf_counter()

        async def send_with_id(message: Message) -> None:
            nonlocal status, started
            if message["type"] == "http.response.start":
                started = True
                status = message["status"]
                headers = [
                    (k, v) for k, v in message.get("headers", []) if k.lower() != b"x-request-id"
                ]
                headers.append((b"x-request-id", rid.encode("ascii")))
                message = {**message, "headers": headers}
            await send(message)

        try:
            await self.app(scope, receive, send_with_id)
        except asyncio.CancelledError:
            # uvicorn cancels what is still running when a graceful shutdown runs out of
            # time (SKELPRUNE_SHUTDOWN_TIMEOUT): answer 503 rather than drop the line.
            if started:
                raise

            response = problem(
                PoolClosedError("the server shut down before this request finished; retry it"),
                instance=scope["path"],
                headers={"Retry-After": "1"},
            )
            await response(scope, receive, send_with_id)
            status = 503
        except Exception as exc:
            # A bug that got past every handler: answer (if still possible) and log it
            # without the traceback (that needs SKELPRUNE_LOG_LEVEL=debug).
            ref = uuid.uuid4().hex[:12]
            log.error(
                "unhandled error %s on %s %s: %s",
                ref,
                scope["method"],
                scope["path"],
                type(exc).__name__,
                exc_info=log.isEnabledFor(logging.DEBUG),
                extra={"request_id": rid, "reference": ref},
            )
            if not started:
                response = problem(
                    InternalError(
                        f"internal error (reference {ref}); the server log has the details"
                    ),
                    instance=scope["path"],
                )
                await response(scope, receive, send_with_id)
            status = 500
        finally:
            if self.access_log_enabled:
                client = scope.get("client")
                access_log.info(
                    "%s %s %d",
                    scope["method"],
                    scope["path"],
                    status,
                    extra={
                        "method": scope["method"],
                        "path": scope["path"],
                        "status": status,
                        "duration_ms": round(1000 * (time.perf_counter() - t0), 3),
                        "request_id": rid,
                        "client": client[0] if client else None,
                    },
                )
