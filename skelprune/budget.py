"""A job's memory and time, estimated from its input before any work starts, against
its budget.

Pruning needs memory and time in proportion to what the input can make it build: arrays
over every pixel (the mask, its distance transform, the crops), objects over every
skeleton point and boundary pixel, and over every component. A few kilobytes of PNG can
describe sixteen million pixels of noise, so the service counts these before it prunes
(one pass over the mask and a labelling) and refuses (413) a job whose memory estimate,
added to what the worker already holds, is over ``SKELPRUNE_JOB_MEMORY_MB``, or whose
time estimate is over ``SKELPRUNE_JOB_TIMEOUT``: such a job would otherwise hold a
worker for the whole time limit and end in a 504. The memory coefficients are above
the most seen per unit on the adversarial masks of ``python -m benchmarks adversarial``
(see ``docs/hostile-input.md``); the time coefficients are typical of a busy two-core
machine, so the estimate is a first screen and the time limit stays the hard stop.

The estimate is a screen, not the bound: what bounds a job is its worker's resident
set, which the pool samples while the job runs (:class:`service.worker.pool.WorkerPool`,
``memory_limit``): a worker over the budget is killed and replaced and the job answered
with the same 413. Virtual memory is not what a job uses (allocators and thread arenas
reserve far more address space than they touch), so it is not capped.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from .errors import InvalidPolygonError, JobTooLargeError

__all__ = [
    "BYTES_PER_ANSWER_PIXEL",
    "BYTES_PER_COMPONENT",
    "BYTES_PER_FACE",
    "BYTES_PER_INSIDE_VOXEL",
    "BYTES_PER_PIXEL",
    "BYTES_PER_PIXEL_LOCAL",
    "BYTES_PER_SKELETON_POINT",
    "BYTES_PER_VOXEL",
    "IMAGE_BASIS",
    "SECONDS_PER_COMPONENT",
    "SECONDS_PER_FACE",
    "SECONDS_PER_INSIDE_VOXEL",
    "SECONDS_PER_PART",
    "SECONDS_PER_PART_PAIR",
    "SECONDS_PER_PIXEL",
    "SECONDS_PER_PIXEL_LOCAL",
    "SECONDS_PER_POSITION",
    "SECONDS_PER_SKELETON_POINT",
    "SECONDS_PER_VOLUME_LABEL",
    "SECONDS_PER_VOXEL",
    "VOLUME_BASIS",
    "Estimate",
    "JobTooLargeError",
    "check_budget",
    "check_polygon",
    "estimate",
    "label_count",
    "mib",
    "out_of_memory",
    "polygon_estimate",
    "resident_bytes",
    "shape_counts",
    "volume_estimate",
]

# The memory coefficients are fitted so that what a warm worker holds plus the estimate
# is within 1.5x of the worker's measured peak on every mask of the adversarial corpus
# that runs and every silhouette of ``python -m benchmarks large`` (docs/hostile-input.md):
# a tight estimate refuses no job that fits; the resident-memory watchdog is the bound.
#: Bytes per input pixel: the PNG decoded, mask, distance transform, labels, crops
#: (4096² silhouettes: 13-37) ...
BYTES_PER_PIXEL = 32
#: With ``scope="local"`` no pass runs over the whole image at once but the cleaning and
#: the stitching: bytes per input pixel then (networks at 4096²-8192², cleaned, and
#: noise: the estimate 0.9-1.5x the measured peak, ``python -m benchmarks local_budget``).
BYTES_PER_PIXEL_LOCAL = 10
#: ... per pixel that can be a skeleton point, at most min(shape pixels, boundary
#: pixels): graph, branch lists and their copies (pixel noise, checkerboards: 400-1,000) ...
BYTES_PER_SKELETON_POINT = 768
#: ... per 8-connected component: its crop, result and document (isolated dots: ~13,000) ...
BYTES_PER_COMPONENT = 16 * 1024
#: ... and per pixel of an answer image (the overlay, RGB, and its PNG encoding).
BYTES_PER_ANSWER_PIXEL = 16
#: Seconds per input pixel (distance transform, medial axis, the pruning of a blob's full
#: axis): the estimate is above the CPU time of every large blob of ``python -m
#: benchmarks large`` at 2048² and 4096² (0.12-0.47 µs a pixel; the drawn heart, whose
#: axis runs off the frame, 0.72 and 1.02 µs: 17.1 s at 4096², estimated 17.8 s) ...
SECONDS_PER_PIXEL = 1.0e-6
#: ... with ``scope="local"`` (windows a few hundred pixels wide: no blob's full axis) ...
SECONDS_PER_PIXEL_LOCAL = 0.5e-6
#: ... per pixel that can be a skeleton point (pixel noise, checkerboards: 25–60 µs) ...
SECONDS_PER_SKELETON_POINT = 60e-6
#: ... and per component (isolated dots: 0.3–0.7 ms).
SECONDS_PER_COMPONENT = 0.7e-3
#: A polygon's cost before it has pixels: seconds per position (decoding, validation,
#: the geometry's construction; 100,000 positions: ~2 s on a busy machine) ...
SECONDS_PER_POSITION = 20e-6
#: ... per part (its validation, fitting, share of the union, and its pruning as a
#: component of the raster: ~2.3 ms a unit square) ...
SECONDS_PER_PART = 2.5e-3
#: ... and per pair of parts: the fitting and union of many parts grow faster than
#: their number (20,000 unit squares: ~20 s, 10,000: ~4 s).
SECONDS_PER_PART_PAIR = 60e-9
# A volume's coefficients are fitted on trees, balls and opened noise at 96³-256³
# (docs/volumes.md): the estimate is 0.85-1.35x the measured peak over a warm worker.
#: A volume's cost: bytes per voxel (the distance transform, labels, crops) ...
BYTES_PER_VOXEL = 8
#: ... per voxel inside (the balls' coverage, the thinning's state) ...
BYTES_PER_INSIDE_VOXEL = 32
#: ... and per boundary face (the thinning queue, skeleton voxels and their graph) ...
BYTES_PER_FACE = 150
#: ... seconds per voxel (the distance transform), per voxel inside and per boundary
#: face (the thinning: opened noise, all surface, ~10 µs a face).
SECONDS_PER_VOXEL = 0.04e-6
SECONDS_PER_INSIDE_VOXEL = 0.3e-6
SECONDS_PER_FACE = 12e-6
#: ... and per label of a label volume, each pruned alone (tiny labels: 1-1.9 ms each,
#: their crop, curve skeleton and pruning; memory as an image's component).
SECONDS_PER_VOLUME_LABEL = 2e-3
_EIGHT = np.ones((3, 3), bool)


def label_count(labels: np.ndarray) -> int:
    """Distinct non-zero values of a label image or volume: one count per value where
    the values are small and not negative, a sort otherwise.

    >>> label_count(np.array([[0, 3, 3], [9, 0, 3]]))
    2
    """
    flat = np.asarray(labels).ravel()
    if flat.size == 0:
        return 0
    if flat.dtype == np.bool_:
        return int(flat.any())
    low, top = int(flat.min()), int(flat.max())
    if low >= 0 and top < 1 << 24:
        present = np.bincount(flat.astype(np.intp, copy=False), minlength=1)
        return int(np.count_nonzero(present[1:]))
    values = np.unique(flat)
    return int(np.count_nonzero(values))


def shape_counts(mask: np.ndarray, labels: np.ndarray | None = None) -> tuple[int, int, int, int]:
    """``(pixels, shape pixels, boundary pixels, components)`` of a boolean mask.

    Boundary pixels are the 4-adjacent (shape, background) pairs, the image's edge
    counting as background; components are 8-connected. With ``labels`` (a label
    image: every label pruned alone) a pair of two labels is boundary to both, and
    every label is at least one component (a lower bound on its pieces).

    >>> m = np.zeros((4, 5), bool); m[1:3, 1:3] = True; m[0, 4] = True
    >>> shape_counts(m)
    (20, 5, 12, 2)
    >>> lab = m.astype(int); lab[1:3, 2] = 2
    >>> shape_counts(lab != 0, lab)
    (20, 5, 16, 2)
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
    if labels is not None:
        boundary += 2 * int(
            np.count_nonzero((labels[:, 1:] != labels[:, :-1]) & mask[:, 1:] & mask[:, :-1])
            + np.count_nonzero((labels[1:] != labels[:-1]) & mask[1:] & mask[:-1])
        )
        n_components = max(n_components, label_count(labels))
    return mask.size, fg, boundary, n_components


@dataclass(frozen=True)
class Estimate:
    """What pruning one input is expected to cost at worst."""

    bytes: int
    seconds: float

    def __add__(self, other: Estimate) -> Estimate:
        return Estimate(self.bytes + other.bytes, self.seconds + other.seconds)


def estimate(
    mask: np.ndarray,
    answer_pixels: int = 0,
    scope: str = "global",
    labels: np.ndarray | None = None,
) -> Estimate:
    """Worst-case memory and time of pruning ``mask`` (and rendering ``answer_pixels``),
    with the scope's cost per pixel (:data:`BYTES_PER_PIXEL_LOCAL` and
    :data:`SECONDS_PER_PIXEL_LOCAL` for ``"local"``);
    ``labels``: a label image's labels, each pruned alone (:func:`shape_counts`)."""
    pixels, fg, boundary, n_components = shape_counts(mask, labels)
    skeleton = min(fg, boundary)
    local = scope == "local"
    per_pixel = BYTES_PER_PIXEL_LOCAL if local else BYTES_PER_PIXEL
    seconds_per_pixel = SECONDS_PER_PIXEL_LOCAL if local else SECONDS_PER_PIXEL
    return Estimate(
        bytes=per_pixel * pixels
        + BYTES_PER_SKELETON_POINT * skeleton
        + BYTES_PER_COMPONENT * n_components
        + BYTES_PER_ANSWER_PIXEL * answer_pixels,
        seconds=seconds_per_pixel * pixels
        + SECONDS_PER_SKELETON_POINT * skeleton
        + SECONDS_PER_COMPONENT * n_components,
    )


def volume_estimate(volume: np.ndarray, answer_pixels: int = 0) -> Estimate:
    """Worst-case memory and time of pruning a volume (and rendering ``answer_pixels``).

    The cost grows with the voxels, the voxels inside and the boundary faces (a face
    between a voxel inside and one outside or the volume's edge).

    >>> v = np.zeros((64, 64, 64), bool); v[8:56, 30:34, 30:34] = True
    >>> e = volume_estimate(v); e.bytes // 2**20, round(e.seconds, 3)
    (2, 0.02)
    """
    inside = np.asarray(volume) != 0
    n_inside = int(np.count_nonzero(inside))
    labels = 0 if volume.dtype == np.bool_ else label_count(volume)
    labels = 0 if labels <= 1 else labels  # a 0/1 volume is one shape
    faces = sum(
        int(np.count_nonzero(np.diff(inside, axis=axis)))
        + int(np.count_nonzero(np.take(inside, 0, axis=axis)))
        + int(np.count_nonzero(np.take(inside, -1, axis=axis)))
        for axis in range(inside.ndim)
    )
    return Estimate(
        bytes=BYTES_PER_VOXEL * inside.size
        + BYTES_PER_INSIDE_VOXEL * n_inside
        + BYTES_PER_FACE * faces
        + BYTES_PER_COMPONENT * labels
        + BYTES_PER_ANSWER_PIXEL * answer_pixels,
        seconds=SECONDS_PER_VOXEL * inside.size
        + SECONDS_PER_INSIDE_VOXEL * n_inside
        + SECONDS_PER_FACE * faces
        + SECONDS_PER_VOLUME_LABEL * labels,
    )


def polygon_estimate(parts: int, positions: int) -> Estimate:
    """Time to read, fit and union a polygon of ``parts`` parts and ``positions``
    positions, before its pixels exist (their cost is :func:`estimate`'s, after).

    >>> round(polygon_estimate(20_000, 100_000).seconds)
    76
    """
    seconds = (
        SECONDS_PER_POSITION * positions
        + SECONDS_PER_PART * parts
        + SECONDS_PER_PART_PAIR * parts * parts
    )
    return Estimate(bytes=0, seconds=seconds)


def check_polygon(
    parts: int, positions: int, max_vertices: int | None, seconds: float | None
) -> None:
    """Refuse a polygon over the vertex limit, or whose reading alone
    (:func:`polygon_estimate`) would take longer than ``seconds``, before any work.

    Raises
    ------
    InvalidPolygonError
        More than ``max_vertices`` positions.
    JobTooLargeError
        Estimated over the time limit.
    """
    if max_vertices is not None and positions > max_vertices:
        raise InvalidPolygonError(
            f"too many vertices: {positions} positions, more than {max_vertices} allowed"
        )
    cost = polygon_estimate(parts, positions)
    if seconds is not None and cost.seconds > seconds:
        raise JobTooLargeError(
            f"this polygon would take about {cost.seconds:.0f} s to read, fit and combine "
            f"(judged by its {parts} parts and {positions} positions), over the job time "
            f"limit of {seconds:g} s: send fewer parts (merge touching ones) or fewer "
            "vertices"
        )


def resident_bytes(pid: int | None = None) -> int:
    """Resident set of process ``pid`` (this one by default), bytes; 0 where ``/proc``
    cannot say (another OS, the process gone)."""
    try:
        with open(f"/proc/{pid or 'self'}/statm", "rb") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        return 0


def mib(n: float) -> str:
    """Bytes as the messages say them.

    >>> mib(3 * 2**30)
    '3,072 MiB'
    """
    return f"{n / 2**20:,.0f} MiB"


#: What an image's estimate is judged by, and what to send instead of a refused one.
IMAGE_BASIS = (
    "its pixels, boundary and components (each label's, for a label image)",
    "send fewer pixels or a cleaner mask (noise, one-pixel patterns and scattered dots cost "
    "the most)",
)
#: The same for a volume's (:func:`volume_estimate`).
VOLUME_BASIS = (
    "its voxels, the voxels inside and its labels",
    "send fewer voxels (a crop of the volume, or a coarser one)",
)


def check_budget(
    cost: Estimate,
    memory: int | None,
    seconds: float | None = None,
    basis: tuple[str, str] = IMAGE_BASIS,
) -> None:
    """Refuse a job whose estimate (:func:`estimate`) is over its budget: ``memory``
    bytes on top of what this worker holds now, or ``seconds`` (the job time limit).
    ``basis``: what the estimate is judged by and the advice, for the message.

    Raises
    ------
    JobTooLargeError
        Naming the estimate and the limit.
    """
    judged, advice = basis
    if memory is not None:
        held = resident_bytes()
        if held + cost.bytes > memory:
            raise JobTooLargeError(
                f"this input would need about {mib(cost.bytes)} to prune (judged by "
                f"{judged}; a worker holds {mib(held)} already), "
                f"over the memory budget of {mib(memory)} a job: {advice}"
            )
    if seconds is not None and cost.seconds > seconds:
        raise JobTooLargeError(
            f"this input would take about {cost.seconds:.0f} s to prune (judged by "
            f"{judged}), over the job time limit of {seconds:g} s: "
            f"{advice}"
        )


def out_of_memory(budget: int | None) -> JobTooLargeError:
    """The error of a job that ran out of memory all the same."""
    limit = f"the memory budget of {mib(budget)} a job" if budget else "the memory available"
    return JobTooLargeError(f"this input needs more than {limit}: send fewer pixels")
