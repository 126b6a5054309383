"""The grid layer: digital geometry on the pixel grid, compiled.

What the pruning needs from pixels: the exact distance transform and medial axis, disks
and their row runs, reconstruction and coverage counts, boundary tracing, component
labelling, the eight orientations of the grid, and the branch graph traced from a
one-pixel-wide skeleton. The stages that hold in the plane only live here too: the
coarse DCE stage (:mod:`.coarse`), Discrete Curve Evolution and ``method="dce"``
(:mod:`.dce`), the tips' cut (:mod:`.tips`), the limbs' test (:mod:`.limbs`) and the
sequence replayed for a viewer (:mod:`.replay`). Modules with a leading underscore are
used only inside this package; the names below are its public face, each imported on
first use.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_exports

if TYPE_CHECKING:
    from ._contours import boundary_polygons, trace_boundaries
    from ._digital import disk_half_width, isqrt
    from ._label import components8, holes, label8
    from ._orientation import IDENTITY_ORIENTATION, Orientation, oriented
    from .coverage import Coverage
    from .graph import BranchGraph
    from .medial_axis import MedialAxis, medial_axis, oriented_medial_axis, squared_distance
    from .reconstruction import count_covered, reconstruction, reconstruction_error

#: Where each name lives (a module of this package).
_LAZY = {
    "boundary_polygons": "_contours",
    "trace_boundaries": "_contours",
    "disk_half_width": "_digital",
    "isqrt": "_digital",
    "components8": "_label",
    "holes": "_label",
    "label8": "_label",
    "IDENTITY_ORIENTATION": "_orientation",
    "Orientation": "_orientation",
    "oriented": "_orientation",
    "BranchGraph": "graph",
    "MedialAxis": "medial_axis",
    "medial_axis": "medial_axis",
    "oriented_medial_axis": "medial_axis",
    "squared_distance": "medial_axis",
    "Coverage": "coverage",
    "count_covered": "reconstruction",
    "reconstruction": "reconstruction",
    "reconstruction_error": "reconstruction",
}

__getattr__, __dir__ = lazy_exports(__name__, _LAZY)

__all__ = [
    "IDENTITY_ORIENTATION",
    "BranchGraph",
    "Coverage",
    "MedialAxis",
    "Orientation",
    "boundary_polygons",
    "components8",
    "count_covered",
    "disk_half_width",
    "holes",
    "isqrt",
    "label8",
    "medial_axis",
    "oriented",
    "oriented_medial_axis",
    "reconstruction",
    "reconstruction_error",
    "squared_distance",
    "trace_boundaries",
]
