"""What the pruning core asks of a grid: the interface both grids provide.

The greedy sequence, the choice rule and the margins never see a coordinate, a disk or
a ball. They speak to the grid through three objects (docs/algorithm.md, "The grid
interface"):

- an **axis** (:class:`GridAxis`): the shape's medial axis as points with radii, which
  makes the other two, knows the shape's size in its unit (pixels, voxels), and turns
  integer step counts into lengths (:attr:`GridAxis.step_weights`);
- a **graph** (:class:`GridGraph`) over the axis points: branches and junctions as lists
  of point indices, the end branches, removal of an end branch with the junction it
  leaves dissolved, and the step counts per kind of each branch;
- a **coverage** (:class:`GridCoverage`): per owner (a label: a branch or a junction
  cluster), the shape elements its points alone cover, kept up to date as owners are
  removed and merged, and the elements no point covers.

The pixel grid (:class:`skelprune.skeleton.Skeleton`, :class:`~skelprune.grid.graph.BranchGraph`,
:class:`~skelprune.grid.coverage.Coverage`) and the volume grid
(:class:`skelprune.grid3d.skeleton.VolumeSkeleton`, its graph and coverage) both satisfy
these protocols. Lengths stay integer counts per step kind (two in the plane, seven in a
volume) until :func:`path_length` turns them into one number, in one fixed order, so that
two implementations that make the same removals agree bit for bit.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol, Self, TypeVar

import numpy as np
from numba import njit

__all__ = [
    "GridAxis",
    "GridCoverage",
    "GridGraph",
    "LimbTest",
    "path_length",
    "path_lengths",
]


class PointSet(Protocol):
    """A branch or a junction cluster: its point indices and whether it is still there."""

    points: list[int]
    alive: bool


class GridGraph(Protocol):
    """A mutable branch graph over the axis points (indices into the axis)."""

    @property
    def branches(self) -> Sequence[PointSet]:
        """Every branch ever made, by id (removed ones with ``alive`` false)."""
        ...

    @property
    def junctions(self) -> Sequence[PointSet]:
        """Every junction cluster ever made, by id."""
        ...

    #: Ids of the current end branches (one free end, one junction end).
    ends: set[int]

    @property
    def coords(self) -> tuple[np.ndarray, ...]:
        """The points' integer coordinates, one array per axis of the grid, in the order
        that breaks ties between end branches (``(row, col)``; ``(z, y, x)``)."""
        ...

    def is_end_branch(self, b: int) -> bool: ...

    def endpoint(self, b: int) -> int:
        """The point at the free end of end branch ``b``."""
        ...

    def alive_points(self) -> np.ndarray:
        """Sorted indices of the points still in the skeleton."""
        ...

    def branch_steps(self, b: int) -> tuple[int, ...]:
        """Branch ``b``'s steps of each kind."""
        ...

    def total_steps(self) -> tuple[int, ...]:
        """The skeleton's steps of each kind."""
        ...

    def counts_without(self, b: int) -> tuple[int, ...]:
        """The skeleton's steps of each kind once end branch ``b`` is removed (its
        junction dissolved), without removing it."""
        ...

    def remove_end_branch(self, b: int) -> tuple[int, int, int] | None:
        """Remove end branch ``b``; ``(kept, absorbed, junction)`` when its junction was
        dissolved and its points and branch ``absorbed`` became part of ``kept``."""
        ...


class GridCoverage(Protocol):
    """Incremental coverage of the shape by the points' disks or balls, by owner label."""

    #: Shape elements no point covers.
    lost: int
    #: Per label: the elements only that label's points cover (exact for live labels).
    exclusive: np.ndarray

    def remove_label(self, old: int) -> int:
        """Remove every point labelled ``old``; returns the elements newly uncovered."""
        ...

    def merge_label(self, old: int, new: int) -> None:
        """Give every point labelled ``old`` the label ``new``."""
        ...

    def uncovered(self) -> np.ndarray:
        """Flat indices of the shape's elements no point covers."""
        ...


class LimbTest(Protocol):
    """The limbs a grid can recognise (docs/algorithm.md, "Limbs")."""

    limb: np.ndarray

    def is_limb(self, b: int, exclusive: int) -> bool: ...

    def removed(self, b: int) -> None: ...

    def merged(self, kept: int, absorbed: int) -> None: ...


#: The graph type of one grid (an axis takes only its own grid's graphs).
G = TypeVar("G", bound="GridGraph")


class GridAxis(Protocol[G]):
    """A skeleton of one component on its grid: what the sequence starts from."""

    @property
    def area(self) -> int:
        """Elements of the shape (pixels, voxels): the denominator of ``AR``."""
        ...

    @property
    def step_weights(self) -> np.ndarray:
        """Length of each step kind, in the order of the graph's step counts."""
        ...

    def working_graph(self) -> G:
        """A copy of the skeleton's graph that the core may change."""
        ...

    def with_graph(self, graph: G) -> Self:
        """The same shape and points with another graph over them."""
        ...

    def coverage(self, graph: G, labels: np.ndarray, n_labels: int) -> GridCoverage:
        """The coverage of the shape by the points alive in ``graph``, ``labels[p]``
        being point ``p``'s owner label (``1 .. n_labels - 1``)."""
        ...

    def limb_test(self, graph: G) -> LimbTest | None:
        """The grid's limb test on ``graph`` (read, never changed), or ``None``."""
        ...

    @property
    def grid_step(self) -> float:
        """The grid's finest step, in the unit of the radii (a pixel; the smallest
        voxel side)."""
        ...

    def boundary_roughness(self) -> float:
        """Elements a one-step opening and closing of the shape change, per boundary
        element (about 0.03-0.15 for a clean digital boundary, 0.3-0.7 for a noisy one)."""
        ...

    def lost_along(self, reach: float, removals: Sequence[np.ndarray]) -> np.ndarray:
        """Elements of the shape that no point of this skeleton covers with its disk
        (ball) grown by ``reach``, then the same after each removal of ``removals``
        (point indices) in turn: ``len(removals) + 1`` counts."""
        ...


def path_length(steps: Sequence[int], weights: np.ndarray) -> float:
    """``Σ steps[k]·weights[k]``, summed in the order of the kinds.

    In the plane (weights 1 and √2) this is ``na + nd·√2`` bit for bit.

    >>> path_length((3, 2), np.array([1.0, 2.0 ** 0.5]))
    5.82842712474619
    """
    total = 0.0
    for c, w in zip(steps, weights.tolist(), strict=True):
        total += c * w
    return total


def path_lengths(steps: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """:func:`path_length` of every row of an ``(n, k)`` array of step counts."""
    total = np.zeros(steps.shape[0])
    for k in range(steps.shape[1]):
        total = total + steps[:, k] * float(weights[k])
    return total


@njit(cache=True, inline="always")
def compiled_length(steps, weights):
    """:func:`path_length` in compiled code (one row of counts)."""
    total = 0.0
    for k in range(weights.size):
        total += steps[k] * weights[k]
    return total
