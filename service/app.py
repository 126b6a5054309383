"""Application factory: the settings, the worker pool, the metrics, the routes with their
errors and middlewares, and the API's documentation, wired together."""

from __future__ import annotations

import asyncio
import logging
from collections.abc import AsyncIterator, Callable
from contextlib import asynccontextmanager
from functools import partial

from fastapi import FastAPI
from fastapi.middleware.cors import CORSMiddleware
from prometheus_client import CollectorRegistry
from prometheus_fastapi_instrumentator import Instrumentator

from service import __version__
from service.apidocs.document import install_docs
from service.errors import install_error_handlers
from service.http.api_key import ApiKeyMiddleware
from service.http.middleware import BodyLimitMiddleware, HeadMiddleware, SlashRedirectMiddleware
from service.http.request_context import REQUEST_ID_HEADER, RequestContextMiddleware
from service.http.routes import ROUTERS
from service.metrics import metrics
from service.settings import Settings
from service.worker.jobs import warmup
from service.worker.long_jobs import LongJobs
from service.worker.pool import WorkerPool

__all__ = ["create_app"]

log = logging.getLogger("service")


def _fixed_paths(app: FastAPI) -> set[str]:
    """The application's paths without parameters (those a trailing slash redirects to)."""
    routes = [*app.routes, *(r for router in ROUTERS for r in router.routes)]
    return {p for p in (getattr(r, "path", "") for r in routes) if p and "{" not in p}


def _load_crs_database() -> None:
    """Load pyproj and its CRS database once, at start and off the event loop: the first
    request naming a ``crs`` (checked in the main process) would otherwise hold the
    event loop while they load (~0.2 s)."""
    from skelprune.io.crs import check_crs, has_pyproj

    if has_pyproj():
        check_crs("EPSG:4326")


def create_app(
    settings: Settings | None = None,
    *,
    warm_in_background: bool = False,
    on_pool_failure: Callable[[], None] | None = None,
) -> FastAPI:
    """Build the FastAPI application.

    Parameters
    ----------
    settings : Settings, optional
        Defaults to :class:`Settings` read from the environment.
    warm_in_background : bool
        Serve at once and warm the worker pool meanwhile (``python -m service``):
        ``/healthz`` answers 200 and ``/readyz`` and jobs 503 until the pool is ready.
        Otherwise the application's startup waits for the pool.
    on_pool_failure : callable, optional
        Called when the pool fails to start in the background (after the error is
        logged), e.g. to stop the server.
    """
    settings = settings or Settings()
    pool = WorkerPool(
        settings.workers,
        queue_size=settings.queue_size,
        job_timeout=settings.job_timeout,
        initializer=warmup if settings.warmup else None,
        startup_timeout=settings.startup_timeout,
        context=settings.mp_context,
        preload=("skelprune", "service.worker.jobs"),
        memory_limit=settings.job_memory_mb * 2**20,
    )

    long_jobs = LongJobs(
        pool,
        max_jobs=settings.long_jobs,
        slots=settings.long_job_slots,
        timeout=settings.long_job_timeout,
        ttl=settings.long_job_ttl,
        max_bytes=settings.long_job_results_bytes,
    )

    async def start_in_background() -> None:
        try:
            await pool.start()
        except Exception as exc:
            if pool.closed:  # shut down while warming: nothing went wrong
                return
            app.state.pool_failure = str(exc)
            log.error("the worker pool failed to start: %s", exc)
            if on_pool_failure is not None:
                on_pool_failure()

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        if settings.warmup:
            await asyncio.to_thread(_load_crs_database)
            log.info(
                "starting %d workers: the first one warms up alone, then the others "
                "(a cold numba cache compiles the kernels first, half a minute to a "
                "minute on one core; `make setup` and the image build compile them "
                "ahead)",
                pool.size,
            )
        warming = None
        if warm_in_background:
            warming = asyncio.create_task(start_in_background())
        else:
            await pool.start()
        try:
            yield
        finally:
            await long_jobs.close()  # a restart keeps no long job (docs/service.md)
            await pool.close()
            if warming is not None:  # closing stopped its workers: it ends at once
                await asyncio.gather(warming, return_exceptions=True)

    app = FastAPI(
        title="skelprune",
        version=__version__,
        description="Pruned skeletons of 2-D shapes (Bayesian skeleton pruning, "
        "Shen, Bai, Yang & Latecki 2013). Errors are RFC 9457 problem details.",
        lifespan=lifespan,
        docs_url=None,
        redoc_url=None,  # served below from installed assets, not a CDN
        redirect_slashes=False,  # SlashRedirectMiddleware: a relative Location
    )
    registry = CollectorRegistry()
    app.state.settings = settings
    app.state.pool = pool
    app.state.long_jobs = long_jobs
    app.state.pool_failure = None  # why the pool did not start, if it did not
    app.state.metrics = metrics(registry, pool)
    for router in ROUTERS:
        app.include_router(router)
    install_docs(app)  # /openapi.json, /docs and /redoc
    install_error_handlers(app, retry_after=settings.retry_after)
    Instrumentator(registry=registry, excluded_handlers=["/metrics"]).instrument(app)
    # Middlewares, innermost first (each add wraps the ones before it):
    app.add_middleware(
        BodyLimitMiddleware, limit=settings.max_body_bytes, timeout=settings.body_timeout
    )
    if settings.api_key is not None:  # before the body is read: strangers send nothing
        app.add_middleware(ApiKeyMiddleware, key=settings.api_key.get_secret_value())
    if settings.cors_origins:  # outside the key check: preflights carry no credentials
        app.add_middleware(
            CORSMiddleware,
            allow_origins=settings.cors_origins,
            allow_credentials=False,
            allow_methods=["GET", "POST", "DELETE"],
            allow_headers=[
                "Authorization",
                "X-API-Key",
                "Content-Type",
                "Accept",
                "Prefer",
                REQUEST_ID_HEADER,
            ],
            expose_headers=[
                REQUEST_ID_HEADER,
                "Retry-After",
                "WWW-Authenticate",
                "Location",
                "Preference-Applied",
            ],
            max_age=600,
        )
    app.add_middleware(SlashRedirectMiddleware, paths=partial(_fixed_paths, app))
    app.add_middleware(RequestContextMiddleware, access_log_enabled=settings.access_log)
    app.add_middleware(HeadMiddleware)
    return app
