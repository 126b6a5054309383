"""A job's memory and time, estimated from its input before any work starts, against
its budget: the library's :mod:`skelprune.budget`, which the service's jobs use (and so
does :func:`skelprune.parallel.prune_many`, with the same limits). The names are kept
here for the service's modules; what bounds a running job is the pool's resident-memory
watchdog (:mod:`service.pool`).
"""

from __future__ import annotations

from skelprune.budget import (
    BYTES_PER_ANSWER_PIXEL,
    BYTES_PER_COMPONENT,
    BYTES_PER_PIXEL,
    BYTES_PER_SKELETON_POINT,
    SECONDS_PER_COMPONENT,
    SECONDS_PER_PART,
    SECONDS_PER_PART_PAIR,
    SECONDS_PER_PIXEL,
    SECONDS_PER_POSITION,
    SECONDS_PER_SKELETON_POINT,
    Estimate,
    check_budget,
    check_polygon,
    estimate,
    out_of_memory,
    polygon_estimate,
    resident_bytes,
    shape_counts,
)
from skelprune.errors import JobTooLargeError

__all__ = [
    "BYTES_PER_ANSWER_PIXEL",
    "BYTES_PER_COMPONENT",
    "BYTES_PER_PIXEL",
    "BYTES_PER_SKELETON_POINT",
    "SECONDS_PER_COMPONENT",
    "SECONDS_PER_PART",
    "SECONDS_PER_PART_PAIR",
    "SECONDS_PER_PIXEL",
    "SECONDS_PER_POSITION",
    "SECONDS_PER_SKELETON_POINT",
    "Estimate",
    "JobTooLargeError",
    "check_budget",
    "check_polygon",
    "estimate",
    "out_of_memory",
    "polygon_estimate",
    "resident_bytes",
    "shape_counts",
]
