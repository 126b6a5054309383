"""The request guards that wrap the application: the body's size and time limits,
``HEAD`` answered as ``GET``, and a trailing slash redirected without the client's
``Host``."""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from urllib.parse import quote

from starlette.responses import RedirectResponse
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from service.errors import BodyTooLargeError, RequestTimeoutError, problem

__all__ = ["BodyLimitMiddleware", "HeadMiddleware", "SlashRedirectMiddleware"]


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


class SlashRedirectMiddleware:
    """A known path with a trailing slash is redirected (307) to the path without it, by
    a relative ``Location``: the router's own redirect writes the request's ``Host``
    header into it, so that any client could make the service point elsewhere.

    ``paths`` gives the application's fixed paths (called once, at the first request).
    """

    def __init__(self, app: ASGIApp, paths: Callable[[], set[str]]) -> None:
        self.app = app
        self._paths = paths
        self._known: set[str] | None = None

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        path = scope.get("path", "")
        if scope["type"] == "http" and len(path) > 1 and path.endswith("/"):
            if self._known is None:
                self._known = self._paths()
            bare = path.rstrip("/")
            if bare in self._known:
                query = scope.get("query_string", b"").decode("latin-1")
                location = quote(bare) + (f"?{query}" if query else "")
                await RedirectResponse(location, status_code=307)(scope, receive, send)
                return
        await self.app(scope, receive, send)
