"""Service settings, every one read from a ``SKELPRUNE_`` environment variable."""

from __future__ import annotations

import os
from typing import Literal

from pydantic import Field
from pydantic_settings import BaseSettings, SettingsConfigDict

__all__ = ["Settings", "available_cores"]


def available_cores() -> int:
    """CPU cores this process may run on (respects affinity / container cpusets)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


class Settings(BaseSettings):
    """Configuration of the service.

    Each field ``name`` is read from the environment variable ``SKELPRUNE_NAME``
    (case-insensitive); unknown ``SKELPRUNE_*`` variables are ignored.
    """

    model_config = SettingsConfigDict(env_prefix="SKELPRUNE_", extra="ignore")

    host: str = Field("127.0.0.1", description="Interface to listen on.")
    port: int = Field(8000, ge=0, le=65535, description="TCP port to listen on.")
    workers: int = Field(
        default_factory=available_cores, ge=1, le=256,
        description="Worker processes that run pruning jobs (default: usable CPU cores).",
    )
    queue_size: int = Field(
        16, ge=0, le=100_000,
        description="Jobs that may wait for a free worker; one more gets 503 + Retry-After.",
    )
    job_timeout: float = Field(
        30.0, gt=0, description="Seconds a job may run before its worker is killed (504)."
    )
    startup_timeout: float = Field(
        300.0, gt=0, description="Seconds a worker may take to start and warm up."
    )
    warmup: bool = Field(True, description="Prune a tiny shape in each worker at start (JIT).")
    retry_after: int = Field(1, ge=1, description="Retry-After seconds sent with a 503.")
    max_body_bytes: int = Field(
        16 * 1024 * 1024, ge=1024, description="Largest request body accepted, bytes (413)."
    )
    max_pixels: int = Field(
        4096 * 4096, ge=1, description="Largest image or polygon raster, pixels (413)."
    )
    max_vertices: int = Field(
        100_000, ge=4, description="Most positions in a polygon input, all rings together."
    )
    polygon_longest_side: int = Field(
        512, ge=8, le=16384, description="Default raster size of a polygon's longer side, px."
    )
    mp_context: Literal["forkserver", "spawn"] = Field(
        "forkserver",
        description="multiprocessing start method for workers (forkserver: fast restarts).",
    )
    log_level: Literal["critical", "error", "warning", "info", "debug"] = Field(
        "info", description="uvicorn log level."
    )
