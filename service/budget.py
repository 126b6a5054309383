"""A job's memory and time, estimated from its input before any work starts, against
its budget: the library's :mod:`skelprune.budget`, which the service's jobs use (and so
does :func:`skelprune.parallel.prune_many`, with the same limits). Names kept here for
the service's modules and tests.
"""

from __future__ import annotations

from skelprune.budget import (
    BYTES_PER_ANSWER_PIXEL,
    BYTES_PER_COMPONENT,
    BYTES_PER_PIXEL,
    BYTES_PER_SKELETON_POINT,
    SECONDS_PER_COMPONENT,
    SECONDS_PER_PIXEL,
    SECONDS_PER_SKELETON_POINT,
    Estimate,
    cap_address_space,
    check_budget,
    estimate,
    out_of_memory,
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
    "SECONDS_PER_PIXEL",
    "SECONDS_PER_SKELETON_POINT",
    "Estimate",
    "JobTooLargeError",
    "cap_address_space",
    "check_budget",
    "estimate",
    "out_of_memory",
    "resident_bytes",
    "shape_counts",
]
