"""skelprune: parameter-free Bayesian skeleton pruning.

Shen, Bai, Yang & Latecki, "Skeleton pruning as trade-off between skeleton
simplicity and reconstruction error", Science China Information Sciences, 2013.

>>> import numpy as np, skelprune
>>> m = np.zeros((30, 60), bool); m[5:25, 5:55] = True
>>> doc = skelprune.prune(m).to_dict()
>>> sorted(doc)  # doctest: +NORMALIZE_WHITESPACE
['beta', 'choice', 'coarse', 'components', 'dce_threshold', 'foreground', 'height',
 'method', 'min_margin', 'trim', 'version', 'width']

A polygon in one call, answered in its own coordinates:

>>> strip = {"type": "Polygon",
...          "coordinates": [[[0, 0], [100, 0], [100, 10], [0, 10], [0, 0]]]}
>>> skelprune.prune(strip).to_geojson()["features"][0]["geometry"]["type"]
'LineString'

Options travel as one value each (:mod:`skelprune.options`), or as keywords:

>>> skelprune.prune(m, skelprune.PruneOptions(beta=3.0)).to_dict()["beta"]
3.0
>>> doc["version"] == {"library": skelprune.__version__, "algorithm": ALGORITHM_VERSION}
True

``__all__`` is what a user needs: :func:`prune`, :func:`read_input` and :func:`match`
(with :func:`describe`), the options classes, the result types (:class:`PruneResult`,
:class:`ComponentResult`, :class:`Skeleton`, :class:`Match`, :class:`Input` with its
:class:`PixelFrame`), the paper's medial axis and reconstruction, and the errors. The
graph, the kernels and the other readers are reached through their modules
(``skelprune.grid.graph.BranchGraph``, ``skelprune.io.png.read_mask``, ...).

The names below are imported when first used (``import skelprune`` alone loads neither
numba nor scipy): a command line that prints its help, or a program that only needs the
errors, does not pay for the pipeline.
"""

from typing import TYPE_CHECKING

from ._lazy import lazy_exports
from ._version import ALGORITHM_VERSION
from ._version import __version__ as __version__
from .errors import (
    EmptyMaskError,
    ImageTooLargeError,
    InvalidImageError,
    InvalidOptionError,
    InvalidPolygonError,
    JobTooLargeError,
    SkelpruneError,
)
from .options import OutputOptions, PruneOptions, RasterOptions, ReadOptions, VolumeOptions

if TYPE_CHECKING:
    from .api import prune
    from .grid.medial_axis import MedialAxis, medial_axis
    from .grid.reconstruction import reconstruction, reconstruction_error
    from .io.frame import PixelFrame
    from .io.input import Input, read_input
    from .matching import Match, SkeletonDescriptor, UnmatchableShapeError, describe, match
    from .output.component import ComponentResult
    from .output.document import PruneResult
    from .skeleton import Skeleton

#: Where each lazily imported name lives (a submodule of this package).
_LAZY = {
    "prune": "api",
    "PixelFrame": "io.frame",
    "Input": "io.input",
    "read_input": "io.input",
    "Match": "matching",
    "SkeletonDescriptor": "matching",
    "UnmatchableShapeError": "matching",
    "describe": "matching",
    "match": "matching",
    "MedialAxis": "grid.medial_axis",
    "medial_axis": "grid.medial_axis",
    "ComponentResult": "output.component",
    "PruneResult": "output.document",
    "reconstruction": "grid.reconstruction",
    "reconstruction_error": "grid.reconstruction",
    "Skeleton": "skeleton",
}


__getattr__, __dir__ = lazy_exports(__name__, _LAZY, submodules=True)


__all__ = [
    "ALGORITHM_VERSION",
    "ComponentResult",
    "EmptyMaskError",
    "ImageTooLargeError",
    "Input",
    "InvalidImageError",
    "InvalidOptionError",
    "InvalidPolygonError",
    "JobTooLargeError",
    "Match",
    "MedialAxis",
    "OutputOptions",
    "PixelFrame",
    "PruneOptions",
    "PruneResult",
    "RasterOptions",
    "ReadOptions",
    "Skeleton",
    "SkeletonDescriptor",
    "SkelpruneError",
    "UnmatchableShapeError",
    "VolumeOptions",
    "describe",
    "match",
    "medial_axis",
    "prune",
    "read_input",
    "reconstruction",
    "reconstruction_error",
]
