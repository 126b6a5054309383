"""The contour partition that DCE makes of a shape's boundary (docs/algorithm.md).

A module of its own because both :mod:`.dce`, which makes it, and :mod:`._generating`,
which scans it, need the type, and neither should import the other for it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["BoundaryPartition"]


@dataclass(frozen=True)
class BoundaryPartition:
    """Boundary points of a shape with the contour segment each belongs to.

    Attributes
    ----------
    points : (k, 2) int array
        Background pixels 4-adjacent to the shape, (row, col) in the input frame (may be
        -1 or the image size for shapes touching the border). A pixel adjacent to the
        shape on several sides appears once per side.
    segment : (k,) int array
        Segment id of each point, unique across all boundaries of the shape.
    polygon_id : (k,) int array
        Which boundary polygon the point lies on (0 = first traced).
    vertices : list of (m, 2) float arrays
        The evolved polygon of each boundary (crack coordinates, row/col).
    convex : list of (m,) bool arrays
        Whether each evolved vertex is convex with respect to the shape.
    n_segments : int
        Number of segments in total.
    """

    points: np.ndarray
    segment: np.ndarray
    polygon_id: np.ndarray
    vertices: list[np.ndarray]
    convex: list[np.ndarray]
    n_segments: int
