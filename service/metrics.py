"""The service's own Prometheus metrics: job timings and the worker pool's gauges (HTTP
metrics come from the instrumentator)."""

from __future__ import annotations

from dataclasses import dataclass

from prometheus_client import CollectorRegistry, Gauge, Histogram

from service.worker.pool import WorkerPool
from skelprune.budget import resident_bytes

__all__ = ["Metrics", "metrics"]


@dataclass
class Metrics:
    """The service's own Prometheus metrics (HTTP ones come from the instrumentator)."""

    registry: CollectorRegistry
    prune_seconds: Histogram
    job_seconds: Histogram


def metrics(registry: CollectorRegistry, pool: WorkerPool) -> Metrics:
    """The metrics registered in ``registry``, the pool's gauges read as they are scraped."""
    buckets = (0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1, 2, 5, 10, 30, 60)
    m = Metrics(
        registry=registry,
        prune_seconds=Histogram(
            "skelprune_prune_seconds",
            "Time in skelprune.prune per job.",
            buckets=buckets,
            registry=registry,
        ),
        job_seconds=Histogram(
            "skelprune_job_seconds",
            "Worker round trip per job: decode, prune, serialise, transfer.",
            buckets=buckets,
            registry=registry,
        ),
    )
    Gauge(
        "skelprune_queue_depth", "Jobs waiting for a free worker.", registry=registry
    ).set_function(lambda: pool.waiting)
    Gauge("skelprune_workers_busy", "Workers running a job.", registry=registry).set_function(
        lambda: pool.busy
    )
    Gauge("skelprune_workers", "Worker processes alive.", registry=registry).set_function(
        pool.alive
    )
    Gauge(
        "skelprune_worker_restarts",
        "Workers replaced (a timeout, a crash, over the memory budget, or recycled).",
        registry=registry,
    ).set_function(lambda: pool.restarts)
    Gauge(
        "skelprune_workers_recycled",
        "Workers replaced because their memory did not come back after a job.",
        registry=registry,
    ).set_function(lambda: pool.recycled)
    Gauge(
        "skelprune_main_resident_bytes",
        "Resident memory of the main process (reads and checks every request body).",
        registry=registry,
    ).set_function(resident_bytes)
    pool.on_job_done = m.job_seconds.observe
    return m
