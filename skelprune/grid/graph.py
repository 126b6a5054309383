"""The pixel grid's skeleton graph (docs/algorithm.md, "The skeleton graph").

A skeleton is a set of pixels, each joined to its 8-neighbours by an axial or a diagonal
step. :class:`BranchGraph` is the one branch graph of every grid
(:class:`~skelprune.pruning.branch_graph.PointGraph`) over the pixels' 8-neighbour table:
endpoints, junction clusters, branches and loops, with lengths kept as exact integer
counts of axial and diagonal steps, so that two implementations that do the same
removals get bit-identical lengths.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..pruning.branch_graph import GridSteps, PointGraph
from ._digital import NEIGHBOURS

__all__ = ["PIXEL_STEPS", "SQRT2", "BranchGraph"]

SQRT2 = math.sqrt(2.0)

#: The pixel grid's steps: slot ``i`` of the 8-neighbour table (:data:`._digital.NEIGHBOURS`)
#: is axial (kind 0, length 1) or diagonal (kind 1, length √2).
PIXEL_STEPS = GridSteps(np.abs(NEIGHBOURS).sum(axis=1) - 1, np.array([1.0, SQRT2]))


@njit(cache=True)
def point_index(rows, cols, shape):
    """The point index of every pixel of an array of ``shape`` (-1: none)."""
    index = np.full(shape, -1, dtype=np.int64)
    for k in range(rows.size):
        index[rows[k], cols[k]] = k
    return index


@njit(cache=True)
def neighbour_table(rows, cols, index):
    """(n, 8) 8-neighbour point indices, in the slot order of ``NEIGHBOURS`` (-1: none)."""
    n = rows.size
    nbr = np.full((n, 8), -1, dtype=np.int64)
    for k in range(n):
        for i in range(8):
            nbr[k, i] = index[rows[k] + NEIGHBOURS[i, 0], cols[k] + NEIGHBOURS[i, 1]]
    return nbr


class BranchGraph(PointGraph):
    """Mutable branch graph of a skeleton given as pixel coordinates.

    Parameters
    ----------
    rows, cols : (n,) int arrays
        Skeleton pixels (one pixel thin, 8-connected components).
    shape : tuple
        Shape of the array the coordinates index; the border must be empty.

    Examples
    --------
    >>> rows = np.array([1, 1, 1, 1, 1, 2, 3]); cols = np.array([1, 2, 3, 4, 5, 3, 3])
    >>> g = BranchGraph(rows, cols, (5, 7))
    >>> len(g.end_branches()), g.total_steps()
    (3, (3, 0))
    """

    def __init__(self, rows: np.ndarray, cols: np.ndarray, shape: tuple[int, int]) -> None:
        self.rows = np.asarray(rows, dtype=np.int64)
        self.cols = np.asarray(cols, dtype=np.int64)
        self.shape = (int(shape[0]), int(shape[1]))
        index = point_index(self.rows, self.cols, shape)
        super().__init__(neighbour_table(self.rows, self.cols, index), PIXEL_STEPS)

    @property
    def coords(self) -> tuple[np.ndarray, np.ndarray]:
        """``(rows, cols)``: the points' coordinates, in the order that breaks ties."""
        return self.rows, self.cols
