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

``__all__`` is what a user needs: :func:`prune` and :func:`encode` (every front's way
through: the command line, the service and data-set runs call these two), the
:class:`Limits` an input is held to, :func:`read_input`, :func:`match` (with
:func:`describe`), the options classes, the result types (:class:`PruneResult`,
:class:`ComponentResult`, :class:`Skeleton`, :class:`Match`, :class:`Input`), the paper's
medial axis, and the errors. The graph, the kernels, the frame and the other readers are
reached through their modules (``skelprune.grid.graph.BranchGraph``,
``skelprune.io.frame.PixelFrame``, ``skelprune.io.png.read_mask``, ...).

>>> skelprune.encode(skelprune.prune(m), "geojson")[:28]
b'{"type":"FeatureCollection",'
>>> len(skelprune.__all__) <= 25
True

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
    from .grid.medial_axis import medial_axis
    from .io.input import Input, read_input
    from .limits import Limits
    from .matching import Match, describe, match
    from .output.component import ComponentResult
    from .output.document import PruneResult
    from .output.encode import encode
    from .skeleton import Skeleton

#: Where each lazily imported name lives (a submodule of this package).
_LAZY = {
    "prune": "api",
    "encode": "output.encode",
    "Limits": "limits",
    "Input": "io.input",
    "read_input": "io.input",
    "Match": "matching",
    "describe": "matching",
    "match": "matching",
    "medial_axis": "grid.medial_axis",
    "ComponentResult": "output.component",
    "PruneResult": "output.document",
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
    "Limits",
    "Match",
    "OutputOptions",
    "PruneOptions",
    "PruneResult",
    "RasterOptions",
    "ReadOptions",
    "Skeleton",
    "SkelpruneError",
    "VolumeOptions",
    "describe",
    "encode",
    "match",
    "medial_axis",
    "prune",
    "read_input",
]
