"""The operations endpoints: ``/healthz``, ``/v1/version``, ``/readyz``, ``/metrics``."""

from __future__ import annotations

from fastapi import APIRouter, Request, Response
from prometheus_client import CONTENT_TYPE_LATEST, generate_latest

from service.apidocs import openapi
from service.http.schemas import Health, Readiness, Version
from service.worker.pool import PoolClosedError, PoolStartingError, QueueFullError, WorkerPool
from skelprune import ALGORITHM_VERSION, __version__

__all__ = ["router"]

router = APIRouter()


@router.get(
    "/healthz",
    response_model=Health,
    summary="Liveness: the process answers",
    tags=["ops"],
    responses=openapi.HEALTH_RESPONSES,
)
async def healthz() -> Health:
    return Health(status="ok", version=__version__, algorithm=ALGORITHM_VERSION)


@router.get(
    "/v1/version",
    response_model=Version,
    summary="Versions of the service and its results",
    responses=openapi.VERSION_RESPONSES,
    tags=["ops"],
)
async def version() -> Version:
    return Version(service=__version__, library=__version__, algorithm=ALGORITHM_VERSION)


@router.get(
    "/readyz",
    response_model=Readiness,
    summary="Readiness: worker pool up and the queue not full",
    responses=openapi.READY_RESPONSES,
    tags=["ops"],
)
async def readyz(request: Request) -> Readiness:
    pool: WorkerPool = request.app.state.pool
    if pool.starting and not pool.closed:
        raise PoolStartingError(
            f"the worker pool is warming up ({pool.warm} of {pool.size} workers ready)"
        )
    failure = request.app.state.pool_failure
    if failure is not None:
        raise PoolClosedError(f"the worker pool failed to start: {failure}")
    if not pool.started or pool.closed:
        raise PoolClosedError("the worker pool is not running")
    if not pool.ready:
        raise QueueFullError(f"the queue is full ({pool.waiting} jobs waiting)")
    return Readiness(
        status="ready",
        workers=pool.alive(),
        busy=pool.busy,
        queued=pool.waiting,
        queue_size=pool.queue_size,
    )


@router.get(
    "/metrics",
    summary="Prometheus metrics",
    response_class=Response,
    responses=openapi.METRICS_RESPONSES,
    tags=["ops"],
)
async def metrics(request: Request) -> Response:
    return Response(
        generate_latest(request.app.state.metrics.registry), media_type=CONTENT_TYPE_LATEST
    )
