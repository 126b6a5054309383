"""``POST /v1/match``'s job, as a worker runs it (its request and answer models are in
:mod:`service.http.schemas`)."""

from __future__ import annotations

import time
from dataclasses import dataclass

from service.worker.jobs import Job, dumps, read_job
from skelprune.budget import check_budget, estimate, out_of_memory

__all__ = ["MatchJob", "run_match_job"]


@dataclass(frozen=True)
class MatchJob:
    """Two shapes to prune and match, as sent to a worker (picklable); each job carries
    the request's options values."""

    a: Job
    b: Job


@dataclass(frozen=True)
class MatchResult:
    body: bytes
    media_type: str
    prune_seconds: float


def run_match_job(job: MatchJob) -> MatchResult:
    """Decode both inputs, prune them and answer the match as JSON (memory checked
    and serialised as :func:`service.worker.jobs.run_job` does)."""
    try:
        return _run_match_job(job)
    except MemoryError:
        raise out_of_memory(job.a.limits.memory) from None


def _run_match_job(job: MatchJob) -> MatchResult:
    import skelprune
    from skelprune.api import prune_input

    a, b = read_job(job.a), read_job(job.b)
    limits = job.a.limits
    check_budget(estimate(a.mask) + estimate(b.mask), limits.memory, limits.seconds)
    t0 = time.perf_counter()
    ra, rb = (
        prune_input(a, job.a.options, job.a.output),
        prune_input(b, job.b.options, job.b.output),
    )
    elapsed = time.perf_counter() - t0
    # each result's own frame maps its positions (a polygon's coordinates)
    body = dumps(skelprune.match(ra, rb).to_dict())
    return MatchResult(body=body, media_type="application/json", prune_seconds=elapsed)
