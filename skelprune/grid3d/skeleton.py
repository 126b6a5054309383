"""The skeleton of one volume component: the volume grid's side of the pruning interface.

:class:`VolumeSkeleton` is what :func:`skelprune.pruning.bayesian.pruning_sequence` starts
from on a volume (a :class:`~skelprune.pruning.grid.GridAxis`): the component's voxels,
its curve skeleton with ball radii, and the branch graph saying which skeleton voxels are
still in it. Like the image :class:`~skelprune.skeleton.Skeleton`, stages never change a
skeleton they are given: they take :meth:`VolumeSkeleton.working_graph` and answer with
:meth:`VolumeSkeleton.with_graph`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..grid._roughness import volume_roughness
from ..pruning.branch_graph import AxisOnGraph
from ..pruning.normalisation import Normalisation, normalisation
from ._topology import OFFSETS, step_lengths
from .balls import reconstruction
from .coverage import VolumeCoverage
from .graph import VolumeBranchGraph
from .limbs import VolumeLimbs
from .medial_axis import curve_skeleton

__all__ = ["VolumeSkeleton"]


@dataclass(frozen=True, eq=False)
class VolumeSkeleton(AxisOnGraph[VolumeBranchGraph]):
    """A curve skeleton of one component, in the frame of its padded crop.

    Attributes
    ----------
    volume : (Z, Y, X) bool array
        The component's padded crop.
    z, y, x : (n,) int64 arrays
        Every curve-skeleton voxel and ...
    r2 : (n,) float64 array
        ... its squared ball radius, in physical units.
    spacing : (dz, dy, dx)
    graph : VolumeBranchGraph
        Which of those voxels are in this skeleton. Read it; never change it.
    origin : (int, int, int)
        ``(z, y, x)`` of the crop's corner in the whole volume.

    Examples
    --------
    A bar's curve skeleton: one branch along it, ``area`` its voxels inside.

    >>> v = np.zeros((12, 12, 30), bool); v[2:10, 2:10, 2:28] = True
    >>> (s := VolumeSkeleton.curve_skeleton(v)).area, s.n_endpoints, round(s.length, 2)
    (1664, 2, 22.46)
    """

    volume: np.ndarray
    z: np.ndarray
    y: np.ndarray
    x: np.ndarray
    r2: np.ndarray
    spacing: tuple[float, float, float]
    graph: VolumeBranchGraph
    origin: tuple[int, int, int] = (0, 0, 0)

    @classmethod
    def curve_skeleton(
        cls,
        crop: np.ndarray,
        spacing: tuple[float, float, float] = (1.0, 1.0, 1.0),
        origin: tuple[int, int, int] = (0, 0, 0),
    ) -> VolumeSkeleton:
        """The curve skeleton of a one-component crop (:func:`~.medial_axis.curve_skeleton`)
        and its branch graph."""
        sk = curve_skeleton(crop, spacing)
        graph = VolumeBranchGraph(sk.z, sk.y, sk.x, sk.spacing)
        volume = np.asarray(crop) != 0
        return cls(volume, sk.z, sk.y, sk.x, sk.r2, sk.spacing, graph, origin)

    # -- the grid interface (skelprune.pruning.grid) ------------------------------------
    @cached_property
    def area(self) -> int:
        """Voxels inside."""
        return int(np.count_nonzero(self.volume))

    @cached_property
    def step_weights(self) -> np.ndarray:
        """The seven step kinds' physical lengths."""
        return step_lengths(self.spacing)

    def coverage(
        self, graph: VolumeBranchGraph, labels: np.ndarray, n_labels: int
    ) -> VolumeCoverage:
        alive = graph.alive_points()
        return VolumeCoverage(
            self.volume,
            self.z[alive],
            self.y[alive],
            self.x[alive],
            self.r2[alive],
            labels[alive],
            n_labels,
            self.spacing,
        )

    def limb_test(self, graph: VolumeBranchGraph) -> VolumeLimbs:
        """The limbs of ``graph`` (docs/volumes.md, "Limbs")."""
        return VolumeLimbs(graph, self.volume, self.z, self.y, self.x, self.r2, self.spacing)

    @property
    def grid_step(self) -> float:
        """The smallest voxel side."""
        return float(min(self.spacing))

    def boundary_roughness(self) -> float:
        """Voxels a one-voxel opening and closing change, per boundary voxel."""
        return volume_roughness(self.volume)

    def lost_along(self, reach: float, removals: Sequence[np.ndarray]) -> np.ndarray:
        """Voxels of the shape no ball of this skeleton grown by ``reach`` (physical
        units) covers, then after each removal of ``removals`` in turn."""
        idx = self.points()
        labels = np.full(self.z.size, len(removals) + 1, np.int64)
        for i, pts in enumerate(removals):  # a removal's balls go together
            labels[pts] = i + 1
        grown = (np.sqrt(self.r2[idx]) + reach) ** 2
        cov = VolumeCoverage(
            self.volume,
            self.z[idx],
            self.y[idx],
            self.x[idx],
            grown,
            labels[idx],
            len(removals) + 2,
            self.spacing,
        )
        lost = [cov.lost]
        for i in range(len(removals)):
            lost.append(lost[-1] + cov.remove_label(i + 1))
        return np.asarray(lost, np.int64)

    # -- what the pipeline and the outputs ask ------------------------------------------
    def reconstruction(self) -> np.ndarray:
        """``R(S)``: the union of the skeleton's balls, in the crop's frame."""
        idx = self.points()
        return reconstruction(
            self.volume.shape, self.z[idx], self.y[idx], self.x[idx], self.r2[idx], self.spacing
        )

    def normalisation(self, beta: float) -> Normalisation:
        """Seed voxel (largest radius; ties: smallest ``(z, y, x)``), mean end-path length
        ``ℓ̄`` and ``α = β·log(L/ℓ̄)``, as on the image grid (docs/algorithm.md)."""
        coords = (self.z, self.y, self.x)
        return normalisation(self.graph, coords, self.r2, self._path_lengths, beta)

    def _path_lengths(self, seed: int) -> np.ndarray:
        """Shortest physical path lengths along the skeleton from ``seed``."""
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import dijkstra

        nbr = self.graph.nbr
        n = nbr.shape[0]
        rows, slots = np.nonzero(nbr >= 0)
        off = np.abs(OFFSETS[slots])
        kind = 4 * off[:, 0] + 2 * off[:, 1] + off[:, 2] - 1
        adj = coo_matrix((self.step_weights[kind], (rows, nbr[rows, slots])), shape=(n, n))
        return dijkstra(adj.tocsr(), indices=seed)
