"""``POST /v1/match``: the request model, the job a worker runs, and the answer's schema."""

from __future__ import annotations

import time
from dataclasses import dataclass

from pydantic import BaseModel, ConfigDict, Field

from service.http.schemas import GeoJSONInput
from service.worker.jobs import Job, dumps, read_job
from skelprune.budget import check_budget, estimate, out_of_memory

__all__ = [
    "MatchDocument",
    "MatchJob",
    "MatchPolygons",
    "run_match_job",
]


class MatchPolygons(BaseModel):
    """Two GeoJSON shapes to match (options go in the query)."""

    model_config = ConfigDict(strict=True, extra="forbid")
    a: GeoJSONInput
    b: GeoJSONInput


class MatchedEndpoint(BaseModel):
    model_config = ConfigDict(extra="forbid")
    component: int = Field(
        description="Component of the shape whose skeleton is matched (the largest)."
    )
    node: int = Field(
        description="Node id in that component's skeleton, as `POST /v1/prune` numbers them."
    )
    x: float
    y: float


class MatchedPair(BaseModel):
    model_config = ConfigDict(extra="forbid")
    a: MatchedEndpoint
    b: MatchedEndpoint


class MatchDocument(BaseModel):
    """Path similarity of two skeletons (see docs/matching.md)."""

    model_config = ConfigDict(extra="forbid")
    distance: float = Field(ge=0, description="0 for the same skeleton; symmetric.")
    mirrored: bool = Field(
        description="The correspondence runs along b's boundary in the "
        "opposite sense (as for a mirror image)."
    )
    endpoints: list[int] = Field(
        min_length=2, max_length=2, description="Endpoint counts of a and b."
    )
    correspondence: list[MatchedPair]


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
        raise out_of_memory(job.a.memory_budget) from None


def _run_match_job(job: MatchJob) -> MatchResult:
    import skelprune
    from skelprune.api import prune_input

    a, b = read_job(job.a), read_job(job.b)
    check_budget(estimate(a.mask) + estimate(b.mask), job.a.memory_budget, job.a.time_budget)
    t0 = time.perf_counter()
    ra, rb = prune_input(a, job.a.options, job.a.shown), prune_input(b, job.b.options, job.b.shown)
    elapsed = time.perf_counter() - t0
    # each result's own frame maps its positions (a polygon's coordinates)
    body = dumps(skelprune.match(ra, rb).to_dict())
    return MatchResult(body=body, media_type="application/json", prune_seconds=elapsed)
