"""Service settings, every one read from a ``SKELPRUNE_`` environment variable."""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import Field, SecretStr, ValidationError, field_validator
from pydantic_settings import BaseSettings, NoDecode, SettingsConfigDict

__all__ = ["Settings", "available_cores", "cgroup_cpu_limit", "settings_error"]

CGROUP = Path("/sys/fs/cgroup")


def cgroup_cpu_limit(root: Path = CGROUP) -> float | None:
    """CPUs allowed by the cgroup CPU quota, or None when there is no quota.

    Reads ``cpu.max`` (cgroup v2: ``"<quota> <period>"`` or ``"max <period>"``), else
    ``cpu/cpu.cfs_quota_us`` and ``cpu/cpu.cfs_period_us`` (cgroup v1, -1 = no quota).
    A container started with ``--cpus 1.5`` has a quota of 1.5 CPUs on every core of
    the host: its affinity alone would size the pool far too large.
    """
    try:
        quota, period = (root / "cpu.max").read_text().split()[:2]
        if quota == "max":
            return None
        return int(quota) / int(period) if int(period) > 0 and int(quota) > 0 else None
    except (OSError, ValueError):
        pass
    try:
        quota_us = int((root / "cpu" / "cpu.cfs_quota_us").read_text())
        period_us = int((root / "cpu" / "cpu.cfs_period_us").read_text())
    except (OSError, ValueError):
        return None
    return quota_us / period_us if quota_us > 0 and period_us > 0 else None


def available_cores(cgroup_root: Path = CGROUP) -> int:
    """CPU cores this process may use: its CPU affinity (container cpusets), capped by
    the cgroup CPU quota rounded up (``--cpus 1.5`` gives 2 workers)."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        cores = os.cpu_count() or 1
    limit = cgroup_cpu_limit(cgroup_root)
    if limit is not None:
        cores = min(cores, math.ceil(limit))
    return max(1, cores)


class Settings(BaseSettings):
    """Configuration of the service.

    Each field ``name`` is read from the environment variable ``SKELPRUNE_NAME``
    (case-insensitive); unknown ``SKELPRUNE_*`` variables are ignored.
    """

    model_config = SettingsConfigDict(env_prefix="SKELPRUNE_", extra="ignore")

    host: str = Field("127.0.0.1", description="Interface to listen on.")
    port: int = Field(8000, ge=0, le=65535, description="TCP port to listen on.")
    workers: int = Field(
        default_factory=available_cores,
        ge=1,
        le=256,
        description="Worker processes that run pruning jobs (default: usable CPU cores).",
    )
    queue_size: int = Field(
        16,
        ge=0,
        le=100_000,
        description="Jobs that may wait for a free worker; one more gets 503 + Retry-After.",
    )
    job_timeout: float = Field(
        30.0, gt=0, description="Seconds a job may run before its worker is killed (504)."
    )
    long_job_timeout: float = Field(
        1800.0,
        gt=0,
        description="Seconds a long job (POST /v1/jobs, or Prefer: respond-async) may run "
        "before its worker is killed; its time estimate is screened against it.",
    )
    long_jobs: int = Field(
        8,
        ge=1,
        le=10_000,
        description="Long jobs queued or running at once; one more gets 503 "
        "(too-many-jobs, with Retry-After). Finished jobs do not count.",
    )
    long_job_workers: int | None = Field(
        None,
        ge=1,
        le=256,
        description="Workers long jobs may hold at once (default: all workers but one, at "
        "least one), so that synchronous requests always find a worker; the others wait "
        "their turn, queued.",
    )
    long_job_ttl: float = Field(
        3600.0,
        gt=0,
        description="Seconds a finished long job's status and result are kept (then 404).",
    )
    long_job_results_bytes: int = Field(
        256 * 2**20,
        ge=1,
        description="Bytes of finished long jobs' results kept in memory, all together: "
        "the oldest are dropped first; a result larger than this fails the job (413).",
    )
    startup_timeout: float = Field(
        300.0, gt=0, description="Seconds a worker may take to start and warm up."
    )
    warmup: bool = Field(True, description="Prune a tiny shape in each worker at start (JIT).")
    numba_cache_seed: str | None = Field(
        None,
        description="A numba cache built with the image: copied into an empty "
        "NUMBA_CACHE_DIR at start, so that workers load compiled code instead of compiling.",
    )
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
    job_memory_mb: int = Field(
        2048,
        ge=256,
        description="Resident memory a worker may hold for one job, MiB, its own ~250 MiB "
        "included: a job whose estimate (from its pixels, boundary, components and answer "
        "image) is over it gets 413 before any work; a worker that goes over it while a job "
        "runs is stopped and replaced (413), and one whose memory did not come back after a "
        "job is replaced.",
    )
    main_memory_mb: int = Field(
        1024,
        ge=128,
        description="Resident memory the main process (which reads and checks every "
        "request body) may hold, MiB: over it, a request that sends a body gets 503 "
        "(main-memory, with Retry-After) until the main process holds less.",
    )
    time_estimate_scale: float = Field(
        1.0,
        ge=0,
        description="Factor on the jobs' time estimates, which were measured on a busy "
        "two-core machine (below 1 on a faster one): a job whose scaled estimate is over "
        "SKELPRUNE_JOB_TIMEOUT gets 413 before any work; 0 turns this screen off and "
        "leaves the job time limit alone.",
    )
    header_timeout: float = Field(
        10.0,
        gt=0,
        description="Seconds a client may take to send a request line and its headers "
        "(408, connection closed); also how long a new connection may stay silent.",
    )
    body_timeout: float = Field(
        60.0,
        gt=0,
        description="Seconds a client may take to send a request body, from the end of "
        "its headers (408, connection closed).",
    )
    keep_alive_timeout: float = Field(
        5.0, gt=0, description="Seconds an idle kept-alive connection stays open."
    )
    max_header_bytes: int = Field(
        16 * 1024,
        ge=1024,
        description="Largest request line plus headers, bytes (431, connection closed).",
    )
    max_headers: int = Field(
        100, ge=8, description="Most header fields in one request (431, connection closed)."
    )
    polygon_longest_side: int | None = Field(
        None,
        ge=8,
        le=16384,
        description="Default raster size of a polygon's longer side, px (unset: a pixel "
        "size fitted to each polygon).",
    )
    mp_context: Literal["forkserver", "spawn"] = Field(
        "forkserver",
        description="multiprocessing start method for workers (forkserver: fast restarts).",
    )
    log_level: Literal["critical", "error", "warning", "info", "debug"] = Field(
        "info",
        description="Log level of the service and uvicorn (JSON lines on stderr; "
        "tracebacks only at debug).",
    )
    access_log: bool = Field(
        True,
        description="One JSON log line per request: method, path, status, "
        "duration_ms, request_id, client.",
    )
    api_key: SecretStr | None = Field(
        None,
        description="If set, every endpoint but /healthz and /readyz needs "
        "'Authorization: Bearer <key>' or 'X-API-Key: <key>' (401 otherwise). "
        "Empty = no key.",
    )
    cors_origins: Annotated[list[str], NoDecode] = Field(
        default_factory=list,
        description="Origins allowed to call the API from a browser "
        "(comma-separated, or * for any); empty = no CORS headers at all.",
    )
    shutdown_timeout: float = Field(
        50.0,
        gt=0,
        description="Seconds a graceful shutdown (SIGTERM) waits for requests "
        "in flight before closing them; keep it below the orchestrator's grace period.",
    )

    @property
    def estimate_seconds(self) -> float | None:
        """The time an unscaled estimate may reach (None: no time screen)."""
        if self.time_estimate_scale <= 0:
            return None
        return self.job_timeout / self.time_estimate_scale

    @property
    def long_job_slots(self) -> int:
        """Workers long jobs may hold at once: ``long_job_workers``, or all but one."""
        if self.long_job_workers is not None:
            return min(self.long_job_workers, self.workers)
        return max(1, self.workers - 1)

    @field_validator("api_key", mode="before")
    @classmethod
    def _empty_key_is_none(cls, value: Any) -> Any:
        if isinstance(value, str) and not value.strip():
            return None
        if isinstance(value, SecretStr) and not value.get_secret_value().strip():
            return None
        return value

    @field_validator("cors_origins", mode="before")
    @classmethod
    def _split_origins(cls, value: Any) -> Any:
        if isinstance(value, str):
            value = value.split(",")
        if isinstance(value, list | tuple):
            return [str(v).strip().rstrip("/") for v in value if str(v).strip()]
        return value


def settings_error(exc: ValidationError) -> str:
    """A settings error as the operator wrote it: the variable, its value and the rule.

    >>> try:
    ...     Settings(workers="abc")
    ... except ValidationError as exc:
    ...     print(settings_error(exc))
    SKELPRUNE_WORKERS='abc': Input should be a valid integer, unable to parse string as an integer
    """
    parts = []
    for e in exc.errors(include_url=False):
        name = "SKELPRUNE_" + "_".join(str(p) for p in e["loc"]).upper()
        value = e.get("input")
        shown = "" if isinstance(value, dict) or name.endswith("API_KEY") else f"={value!r}"
        parts.append(f"{name}{shown}: {e['msg'].removeprefix('Value error, ')}")
    return "; ".join(parts)
