"""A job's memory and time, estimated from its input before any work starts, against
its budget (the service's jobs and :func:`skelprune.parallel.prune_many`'s tasks).

Pruning needs memory and time in proportion to what the input can make it build: arrays
over every pixel (the mask, its distance transform, the crops), objects over every
skeleton point and boundary pixel, and over every component. A few kilobytes of PNG can
describe sixteen million pixels of noise, so a caller counts these before it prunes
(one pass over the mask and a labelling): the service refuses (413) a job whose memory estimate,
added to what the worker already holds, is over ``SKELPRUNE_JOB_MEMORY_MB``, or whose
time estimate is over ``SKELPRUNE_JOB_TIMEOUT``: such a job would otherwise hold a
worker for the whole time limit and end in a 504. The memory coefficients are above
the most seen per unit on the adversarial masks of ``python -m benchmarks adversarial``
(see ``docs/hostile-input.md``); the time coefficients are typical of a busy two-core
machine, so the estimate is a first screen and the time limit stays the hard stop.

As a backstop, each worker's address space is capped at what it holds when warm plus the
budget (:func:`cap_address_space`): an allocation the estimate missed fails with
``MemoryError``, which the job answers as the same 413, instead of the machine's
out-of-memory killer ending the worker (or a neighbour).
"""

from __future__ import annotations

import os
import resource
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from .errors import JobTooLargeError

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

#: Bytes per input pixel: mask, distance transform, labels, crops (4096² blobs: ~45) ...
BYTES_PER_PIXEL = 64
#: ... per pixel that can be a skeleton point, at most min(shape pixels, boundary
#: pixels): graph, branch lists and their copies (pixel noise: ~1,100) ...
BYTES_PER_SKELETON_POINT = 1536
#: ... per 8-connected component: its crop, result and document (isolated dots: ~9,000) ...
BYTES_PER_COMPONENT = 16 * 1024
#: ... and per pixel of an answer image (the overlay, RGB, and its PNG encoding).
BYTES_PER_ANSWER_PIXEL = 16
#: Seconds per input pixel (distance transform, medial axis: ~0.3 µs for 4096² blobs) ...
SECONDS_PER_PIXEL = 0.5e-6
#: ... per pixel that can be a skeleton point (pixel noise, checkerboards: 25–60 µs) ...
SECONDS_PER_SKELETON_POINT = 60e-6
#: ... and per component (isolated dots: 0.3–0.7 ms).
SECONDS_PER_COMPONENT = 0.7e-3
_EIGHT = np.ones((3, 3), bool)


def shape_counts(mask: np.ndarray) -> tuple[int, int, int, int]:
    """``(pixels, shape pixels, boundary pixels, components)`` of a boolean mask.

    Boundary pixels are the 4-adjacent (shape, background) pairs, the image's edge
    counting as background; components are 8-connected.

    >>> m = np.zeros((4, 5), bool); m[1:3, 1:3] = True; m[0, 4] = True
    >>> shape_counts(m)
    (20, 5, 12, 2)
    """
    mask = np.asarray(mask, dtype=bool)
    fg = int(np.count_nonzero(mask))
    boundary = int(
        np.count_nonzero(mask[:, 1:] != mask[:, :-1])
        + np.count_nonzero(mask[1:] != mask[:-1])
        + np.count_nonzero(mask[0])
        + np.count_nonzero(mask[-1])
        + np.count_nonzero(mask[:, 0])
        + np.count_nonzero(mask[:, -1])
    )
    n_components = int(ndimage.label(mask, structure=_EIGHT)[1]) if fg else 0
    return mask.size, fg, boundary, n_components


@dataclass(frozen=True)
class Estimate:
    """What pruning one input is expected to cost at worst."""

    bytes: int
    seconds: float

    def __add__(self, other: Estimate) -> Estimate:
        return Estimate(self.bytes + other.bytes, self.seconds + other.seconds)


def estimate(mask: np.ndarray, answer_pixels: int = 0) -> Estimate:
    """Worst-case memory and time of pruning ``mask`` (and rendering ``answer_pixels``)."""
    pixels, fg, boundary, n_components = shape_counts(mask)
    skeleton = min(fg, boundary)
    return Estimate(
        bytes=BYTES_PER_PIXEL * pixels
        + BYTES_PER_SKELETON_POINT * skeleton
        + BYTES_PER_COMPONENT * n_components
        + BYTES_PER_ANSWER_PIXEL * answer_pixels,
        seconds=SECONDS_PER_PIXEL * pixels
        + SECONDS_PER_SKELETON_POINT * skeleton
        + SECONDS_PER_COMPONENT * n_components,
    )


def resident_bytes() -> int:
    """This process's resident set now, bytes (0 where ``/proc`` is missing)."""
    try:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        return 0


def _mib(n: float) -> str:
    return f"{n / 2**20:,.0f} MiB"


def check_budget(cost: Estimate, memory: int | None, seconds: float | None = None) -> None:
    """Refuse a job whose estimate (:func:`estimate`) is over its budget: ``memory``
    bytes on top of what this worker holds now, or ``seconds`` (the job time limit).

    Raises
    ------
    JobTooLargeError
        Naming the estimate and the limit.
    """
    advice = "send fewer pixels or a cleaner mask (noise, one-pixel patterns and scattered "
    advice += "dots cost the most)"
    if memory is not None:
        held = resident_bytes()
        if held + cost.bytes > memory:
            raise JobTooLargeError(
                f"this input would need about {_mib(cost.bytes)} to prune (judged by its "
                f"pixels, boundary and components; a worker holds {_mib(held)} already), "
                f"over the memory budget of {_mib(memory)} a job: {advice}"
            )
    if seconds is not None and cost.seconds > seconds:
        raise JobTooLargeError(
            f"this input would take about {cost.seconds:.0f} s to prune (judged by its "
            f"pixels, boundary and components), over the job time limit of {seconds:g} s: "
            f"{advice}"
        )


def out_of_memory(budget: int | None) -> JobTooLargeError:
    """The error of a job that ran out of memory all the same."""
    limit = f"the memory budget of {_mib(budget)} a job" if budget else "the memory available"
    return JobTooLargeError(f"this input needs more than {limit}: send fewer pixels")


def cap_address_space(budget: int) -> None:
    """Cap this process's address space at its current size plus what the budget leaves
    above its resident set (virtual memory is larger than resident: the cap only stops
    what the estimate missed). Silently nothing where the limit cannot be set."""
    try:
        with open("/proc/self/statm") as f:
            size_pages, resident_pages = (int(v) for v in f.read().split()[:2])
        page = os.sysconf("SC_PAGE_SIZE")
        cap = (size_pages - resident_pages) * page + budget
        _, hard = resource.getrlimit(resource.RLIMIT_AS)
        if hard != resource.RLIM_INFINITY:
            cap = min(cap, hard)
        resource.setrlimit(resource.RLIMIT_AS, (cap, hard))
    except (OSError, ValueError, AttributeError):
        pass
