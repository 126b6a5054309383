"""The volume grid: digital geometry on voxels with anisotropic spacing, compiled.

What the pruning needs from a 3-D volume, mirroring :mod:`skelprune.grid` for images:
the exact squared distance transform with ``spacing = (dz, dy, dx)``, the curve skeleton
(the 3-D medial axis) with a ball radius at every voxel, reconstruction as the union of
balls with its coverage counts and lost volume, and the branch graph traced from the
skeleton. How the two grids meet one interface: docs/volumes.md. Modules with a
leading underscore are used only inside this package; the names below are its public
face, each imported on first use. Not exported from :mod:`skelprune` yet.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_exports

if TYPE_CHECKING:
    from ._topology import OFFSETS, STEP_KINDS, step_lengths
    from .balls import ball_counts, exclusive_volume, lost_volume, reconstruction
    from .distance import squared_distance
    from .graph import VolumeGraph
    from .medial_axis import CurveSkeleton, curve_skeleton

#: The names each module of this package exports, imported on first use.
_MODULES = {
    "_topology": ("OFFSETS", "STEP_KINDS", "step_lengths"),
    "distance": ("squared_distance",),
    "graph": ("VolumeGraph",),
    "medial_axis": ("CurveSkeleton", "curve_skeleton"),
    "balls": ("ball_counts", "exclusive_volume", "lost_volume", "reconstruction"),
}
_LAZY = {name: module for module, names in _MODULES.items() for name in names}

__getattr__, __dir__ = lazy_exports(__name__, _LAZY)

__all__ = [
    "OFFSETS",
    "STEP_KINDS",
    "CurveSkeleton",
    "VolumeGraph",
    "ball_counts",
    "curve_skeleton",
    "exclusive_volume",
    "lost_volume",
    "reconstruction",
    "squared_distance",
    "step_lengths",
]
