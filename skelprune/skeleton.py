"""The skeleton of one shape component: the one type every stage of the pipeline passes on.

A :class:`Skeleton` holds the shape it came from (the padded crop, in its canonical
orientation, with where that crop sits in the image), the medial-axis pixels with their
squared radii, and the branch graph saying which of those pixels are still in it. The
medial axis is a ``Skeleton``; the coarse stage turns one into another; the Bayesian
sequence starts from one and answers with one for any of its steps. Stages never change
a skeleton they are given: each works on its own copy of the graph
(:meth:`Skeleton.working_graph`) and returns a new ``Skeleton``.

The pixel arrays are shared by every skeleton derived from the same medial axis (no
stage adds a pixel), so a derived skeleton costs only its graph.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING, ClassVar

import numpy as np
from numba import njit
from scipy import ndimage

if TYPE_CHECKING:
    from .grid.limbs import LimbGuard

from .grid import IDENTITY_ORIENTATION, Orientation, oriented
from .grid._intervals import owner_runs
from .grid._label import holes
from .grid._open_edge import open_edge, open_extension
from .grid._roughness import boundary_roughness
from .grid._rowcover import cover_counts, last_losses, uncover_count
from .grid.coverage import Coverage
from .grid.graph import SQRT2, BranchGraph
from .grid.medial_axis import MedialAxis, oriented_medial_axis, squared_distance
from .grid.reconstruction import reconstruction
from .pruning.branch_graph import AxisOnGraph
from .pruning.choice import noise_depth
from .pruning.normalisation import Normalisation
from .pruning.normalisation import normalisation as shared_normalisation

__all__ = ["Skeleton", "normalisation"]


def normalisation(graph: BranchGraph, r2: np.ndarray, beta: float) -> Normalisation:
    """Seed ``o`` (largest radius; ties: smallest (row, col)), ``ℓ̄`` and ``α`` of a pixel
    skeleton (:func:`skelprune.pruning.normalisation.normalisation`)."""
    return shared_normalisation(
        graph, (graph.rows, graph.cols), r2, lambda seed: _path_lengths(graph.nbr, seed), beta
    )


@njit(cache=True)
def _path_lengths(nbr, seed):
    """Shortest path lengths along the skeleton from ``seed`` (Dijkstra; steps 1, √2).

    Neighbour slots follow :data:`skelprune.grid.medial_axis.NEIGHBOURS`: even slots are
    diagonal.
    """
    dist = np.full(nbr.shape[0], np.inf)
    dist[seed] = 0.0
    heap = [(0.0, seed)]
    while heap:
        d, u = heapq.heappop(heap)
        if d > dist[u]:
            continue
        for i in range(8):
            q = nbr[u, i]
            if q < 0:
                continue
            nd = d + (SQRT2 if i % 2 == 0 else 1.0)
            if nd < dist[q]:
                dist[q] = nd
                heapq.heappush(heap, (nd, q))
    return dist


def _homotopic(rows: np.ndarray, cols: np.ndarray, shape: np.ndarray) -> bool:
    """Whether the pixels are one non-empty 8-connected set with the holes of
    ``shape`` (a padded one-component crop): an axis with its topology."""
    if rows.size == 0:
        return False
    img = np.zeros(shape.shape, bool)
    img[rows, cols] = True
    if int(ndimage.label(img, np.ones((3, 3), bool))[1]) != 1:
        return False
    return holes(img) == holes(shape)


def _beyond(shape: tuple[int, ...], origin: tuple[int, int], image_shape: tuple[int, int]) -> bool:
    """Whether a crop of ``shape`` with its corner at ``origin`` reaches past the image
    (a padded crop does where its component touches the image's border)."""
    return bool(
        origin[0] < 0
        or origin[1] < 0
        or origin[0] + shape[0] > image_shape[0]
        or origin[1] + shape[1] > image_shape[1]
    )


def grown_r2(r2: np.ndarray, reach: float) -> np.ndarray:
    """Integer squared radii of the disks ``|p − s| < r + reach``: with integer squared
    distances, ``d² < x`` is ``d² < ⌈x⌉`` (a hair below an integer counts as it, so
    that rounding never moves a pixel in or out).

    >>> grown_r2(np.array([0, 1, 2, 4]), 1.0).tolist()
    [1, 4, 6, 9]
    """
    grown = (np.sqrt(np.asarray(r2, np.float64)) + reach) ** 2
    return np.ceil(grown - 1e-9).astype(np.int64)


@dataclass(frozen=True, eq=False)
class Skeleton(AxisOnGraph[BranchGraph]):
    """A skeleton of one component, in the canonical frame of its padded crop.

    Attributes
    ----------
    mask : (H, W) bool array
        The shape ``D``: the component's padded crop, seen in ``orientation``.
    rows, cols, r2 : (n,) int64 arrays
        Every medial-axis pixel of the shape and its squared radius (shared by all
        skeletons derived from the same axis).
    graph : BranchGraph
        Which of those pixels are in this skeleton, as branches and junctions. Read it;
        never change it (take :meth:`working_graph` for that).
    orientation : Orientation
        How ``mask`` is turned from the crop as it lies in the image.
    origin : (int, int)
        (row, col) of the crop's corner in the image.

    Examples
    --------
    >>> m = np.zeros((12, 22), bool); m[2:10, 2:20] = True
    >>> s = Skeleton.medial_axis(m)
    >>> s.n_endpoints, s.area, round(s.length, 2)
    (4, 144, 24.31)
    """

    mask: np.ndarray
    rows: np.ndarray
    cols: np.ndarray
    r2: np.ndarray
    graph: BranchGraph
    orientation: Orientation = IDENTITY_ORIENTATION
    origin: tuple[int, int] = (0, 0)
    #: Where the shape runs off the image: per pixel next to an open run (its open edge,
    #: seen in ``orientation``, grown by a pixel), that run's number from 1, else 0. One
    #: end at each run is kept whole. None: no such edge.
    open_near: np.ndarray | None = None

    @classmethod
    def medial_axis(
        cls,
        crop: np.ndarray,
        origin: tuple[int, int] = (0, 0),
        image_shape: tuple[int, int] | None = None,
    ) -> Skeleton:
        """The medial axis of a padded one-component crop, in the crop's canonical
        orientation: the frame every stage works in (ties included), so that a turned or
        mirrored shape gets the turned or mirrored result. With ``image_shape`` (the
        crop's corner at ``origin`` in that image), a shape cut by the image's border
        goes on across it (:mod:`skelprune.grid._open_edge`)."""
        shape, orientation = oriented(crop)
        r2 = squared_distance(shape)
        edge = None
        if image_shape is not None and _beyond(crop.shape, origin, image_shape):
            noise = noise_depth(boundary_roughness(crop), 1.0)
            edge = open_edge(crop, origin, image_shape, noise)
        if edge is None:
            axis = oriented_medial_axis(shape, r2)
            graph = BranchGraph(axis.rows, axis.cols, shape.shape)
            return cls(shape, axis.rows, axis.cols, axis.r2, graph, orientation, origin)
        edge = np.ascontiguousarray(orientation.apply(edge))
        # the axis of the shape gone on beyond the image, cut back at the border
        ext, o = open_extension(shape, edge)
        far = oriented_medial_axis(ext, squared_distance(ext))
        rows, cols = far.rows - o, far.cols - o
        h, w = shape.shape
        inside = (rows >= 0) & (rows < h) & (cols >= 0) & (cols < w)
        inside[inside] = shape[rows[inside], cols[inside]]
        rows, cols = rows[inside], cols[inside]
        # the cut split it, or opened a cycle round a hole: keep the plain one
        if not _homotopic(rows, cols, shape):
            axis = oriented_medial_axis(shape, r2)
            graph = BranchGraph(axis.rows, axis.cols, shape.shape)
            return cls(shape, axis.rows, axis.cols, axis.r2, graph, orientation, origin)
        axis = MedialAxis(rows, cols, r2[rows, cols])
        graph = BranchGraph(axis.rows, axis.cols, shape.shape)
        runs = ndimage.label(ndimage.binary_dilation(edge, np.ones((5, 5), bool)))[0] * edge
        near = ndimage.grey_dilation(runs, size=(3, 3))
        return cls(shape, axis.rows, axis.cols, axis.r2, graph, orientation, origin, near)

    def open_ends(self, points: Sequence[int]) -> set[int]:
        """Of these end points, those that end the shape where it runs off the image: at
        each open run, the end nearest to the run's middle (the structure's own end;
        others there are judged as any end)."""
        near = self.open_near
        if near is None:
            return set()
        best: dict[int, tuple[float, int]] = {}
        centres = ndimage.center_of_mass(near > 0, near, range(1, int(near.max()) + 1))
        for p in points:
            run = int(near[self.rows[p], self.cols[p]])
            if run:
                cy, cx = centres[run - 1]
                d = float((self.rows[p] - cy) ** 2 + (self.cols[p] - cx) ** 2)
                if run not in best or (d, p) < best[run]:
                    best[run] = (d, p)
        return {p for _, p in best.values()}

    # -- the grid interface (skelprune.pruning.grid) ------------------------------------
    #: Axial and diagonal steps: 1 and √2.
    step_weights: ClassVar[np.ndarray] = np.array([1.0, SQRT2])

    def coverage(self, graph: BranchGraph, labels: np.ndarray, n_labels: int) -> Coverage:
        """The incremental coverage of the shape by the disks of ``graph``'s points."""
        alive = graph.alive_points()
        return Coverage(
            self.mask, self.rows[alive], self.cols[alive], self.r2[alive], labels[alive], n_labels
        )

    def limb_test(self, graph: BranchGraph) -> LimbGuard:
        """The limbs of ``graph`` (docs/algorithm.md, "Limbs")."""
        from .grid.limbs import LimbGuard

        guard = LimbGuard(graph, self.mask, self.r2)
        if self.open_near is not None:  # where the shape runs off the image, its end stays
            ends = sorted(graph.ends)
            kept = self.open_ends([graph.endpoint(b) for b in ends])
            for b in ends:
                guard.limb[b] |= graph.endpoint(b) in kept
        return guard

    #: A pixel.
    grid_step: ClassVar[float] = 1.0

    def boundary_roughness(self) -> float:
        """Pixels a one-pixel opening and closing change, per boundary pixel."""
        return boundary_roughness(self.mask)

    def lost_along(self, reach: float, removals: Sequence[np.ndarray]) -> np.ndarray:
        """Pixels of the shape no disk of this skeleton grown by ``reach`` covers, then
        after each removal of ``removals`` in turn (the grid interface)."""
        pad = math.ceil(reach) + 1  # grown disks stay on the canvas
        shape = np.pad(self.mask, pad)
        rows, cols, r2 = self.rows + pad, self.cols + pad, grown_r2(self.r2, reach)
        idx = self.points()
        # Each pixel is lost at the removal of the last disk covering it: one pass
        # claims every pixel for its last removal, when the removals are distinct points.
        drop = np.full(rows.size, len(removals), np.int64)  # never removed
        for i, pts in enumerate(removals):
            drop[pts] = i
        taken = sum(len(pts) for pts in removals)
        if np.count_nonzero(drop[idx] < len(removals)) == taken:
            runs, offsets = owner_runs(rows[idx], cols[idx], r2[idx], drop[idx], len(removals) + 1)
            loss, covered = last_losses(shape, runs, offsets, len(removals))
            first = int(np.count_nonzero(shape)) - int(covered)
            return np.concatenate([[first], first + np.cumsum(loss)]).astype(np.int64)
        c = cover_counts(shape.shape[0], shape.shape[1], rows[idx], cols[idx], r2[idx])
        lost = [int(np.count_nonzero(shape & (c == 0)))]
        for pts in removals:
            lost.append(lost[-1] + uncover_count(c, shape, rows[pts], cols[pts], r2[pts]))
        return np.asarray(lost, np.int64)

    # -- what the stages ask --------------------------------------------------------
    @cached_property
    def area(self) -> int:
        """Pixels of the shape."""
        return int(self.mask.sum())

    @property
    def n_branches(self) -> int:
        return sum(1 for b in self.graph.branches if b.alive)

    def normalisation(self, beta: float) -> Normalisation:
        """Seed point, mean end-path length ``ℓ̄`` and ``α = β·log(L/ℓ̄)`` (docs/algorithm.md)."""
        return normalisation(self.graph, self.r2, beta)

    def reconstruction(self) -> np.ndarray:
        """``R(S)``: the union of the skeleton's maximal disks, in the frame of ``shape``."""
        idx = self.points()
        return reconstruction(self.mask.shape, self.rows[idx], self.cols[idx], self.r2[idx])

    def image_coordinates(
        self, rows: np.ndarray, cols: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Rows and columns of pixels of ``shape`` in the image frame: back to the crop's
        own orientation, then ``+ origin``."""
        rows, cols = self.orientation.points_back(rows, cols, self.mask.shape)
        return rows + self.origin[0], cols + self.origin[1]
