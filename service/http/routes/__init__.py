"""The endpoints, one module a family, each registering on its own router:
:mod:`.prune` (``POST /v1/prune``, ``POST /v1/prune/batch``), :mod:`.jobs`
(``/v1/jobs``: long jobs), :mod:`.match` (``POST /v1/match``), :mod:`.ops`
(``/healthz``, ``/readyz``, ``/metrics``, ``/v1/version``) and :mod:`.viewer` (the page
at ``/``)."""

from __future__ import annotations

from fastapi import APIRouter

from service.http.routes import jobs, match, ops, prune, viewer

__all__ = ["ROUTERS"]

#: The routers :func:`service.app.create_app` includes, in this order.
ROUTERS: tuple[APIRouter, ...] = (
    prune.router,
    jobs.router,
    match.router,
    ops.router,
    viewer.router,
)
