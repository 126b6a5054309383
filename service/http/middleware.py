"""The request guards that wrap the application: the body's size and time limits, and
``HEAD`` answered as ``GET``."""

from __future__ import annotations

import asyncio

from starlette.types import ASGIApp, Message, Receive, Scope, Send

from service.errors import BodyTooLargeError, RequestTimeoutError, problem

__all__ = ["BodyLimitMiddleware", "HeadMiddleware"]


class BodyLimitMiddleware:
    """Refuse request bodies over ``limit`` bytes with 413, streamed or not, and bodies
    that take longer than ``timeout`` seconds to arrive with 408.

    A declared ``Content-Length`` over the limit is answered before anything is read;
    a chunked body is counted as it arrives and stopped at the limit. The deadline runs
    from the request's start until its body is complete (later receives, such as the
    wait for a disconnect while an answer streams, are not bounded).
    """

    def __init__(self, app: ASGIApp, limit: int, timeout: float | None = None) -> None:
        self.app = app
        self.limit = limit
        self.timeout = timeout

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        declared = dict(scope["headers"]).get(b"content-length")
        message = f"request body exceeds the limit of {self.limit} bytes"
        if declared is not None and declared.isdigit() and int(declared) > self.limit:
            response = problem(
                BodyTooLargeError(f"{message} (Content-Length: {int(declared)})"),
                instance=scope.get("path"),
            )
            await response(scope, receive, send)
            return
        received = 0
        complete = False
        loop = asyncio.get_running_loop()
        deadline = None if self.timeout is None else loop.time() + self.timeout

        async def limited() -> Message:
            nonlocal received, complete
            if complete or deadline is None:
                msg = await receive()
            else:
                try:
                    msg = await asyncio.wait_for(receive(), max(0.0, deadline - loop.time()))
                except TimeoutError:
                    raise RequestTimeoutError(
                        f"the request body took longer than {self.timeout:g} s to arrive"
                    ) from None
            if msg["type"] == "http.request":
                received += len(msg.get("body", b""))
                complete = not msg.get("more_body", False)
                if received > self.limit:
                    raise BodyTooLargeError(message)
            return msg

        await self.app(scope, limited, send)


class HeadMiddleware:
    """``HEAD`` on any path is its ``GET`` without the body (uvicorn drops the body of a
    ``HEAD`` answer and keeps its headers): probes and caches may ask with ``HEAD``."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] == "http" and scope["method"] == "HEAD":
            scope = {**scope, "method": "GET"}  # a copy: the server's own says HEAD
        await self.app(scope, receive, send)
