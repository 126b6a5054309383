"""The API key: with ``SKELPRUNE_API_KEY`` set, every path but :data:`OPEN_PATHS` needs
``Authorization: Bearer <key>`` or ``X-API-Key: <key>``, compared with
:func:`hmac.compare_digest`; otherwise 401 with ``WWW-Authenticate``. It runs before a
body is read: strangers send nothing.
"""

from __future__ import annotations

import hmac

from starlette.types import ASGIApp, Receive, Scope, Send

from service.errors import UnauthorizedError, problem
from service.http.request_context import header

__all__ = ["OPEN_PATHS", "ApiKeyMiddleware"]

#: Paths open without the API key: probes carry no credentials, and say nothing secret.
OPEN_PATHS = frozenset({"/healthz", "/readyz"})


class ApiKeyMiddleware:
    """Refuse requests without the right API key (401 problem+json)."""

    def __init__(self, app: ASGIApp, *, key: str) -> None:
        self.app = app
        self.key = key.encode("utf-8")

    def _presented(self, scope: Scope) -> list[bytes]:
        keys = []
        auth = header(scope, b"authorization")
        if auth is not None:
            scheme, _, token = auth.strip().partition(b" ")
            if scheme.lower() == b"bearer" and token.strip():
                keys.append(token.strip())
        api_key = header(scope, b"x-api-key")
        if api_key is not None and api_key.strip():
            keys.append(api_key.strip())
        return keys

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http" or scope["path"] in OPEN_PATHS:
            await self.app(scope, receive, send)
            return
        presented = self._presented(scope)
        # compare against every presented key (no early exit) in constant time
        matches = [hmac.compare_digest(k, self.key) for k in presented]
        if any(matches):
            await self.app(scope, receive, send)
            return

        challenge = 'Bearer realm="skelprune"'
        if presented:
            challenge += ', error="invalid_token"'
            detail = "invalid API key"
        else:
            detail = "API key required: send 'Authorization: Bearer <key>' or 'X-API-Key: <key>'"
        response = problem(
            UnauthorizedError(detail),
            instance=scope["path"],
            headers={"WWW-Authenticate": challenge},
        )
        await response(scope, receive, send)
