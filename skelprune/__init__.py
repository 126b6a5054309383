"""skelprune: parameter-free Bayesian skeleton pruning.

Shen, Bai, Yang & Latecki, "Skeleton pruning as trade-off between skeleton
simplicity and reconstruction error", Science China Information Sciences, 2013.

>>> import numpy as np, skelprune
>>> m = np.zeros((30, 60), bool); m[5:25, 5:55] = True
>>> doc = skelprune.prune(m).to_dict()
>>> sorted(doc)  # doctest: +NORMALIZE_WHITESPACE
['beta', 'choice', 'coarse', 'components', 'foreground', 'height', 'method', 'trim',
 'version', 'width']
>>> doc["version"] == {"library": skelprune.__version__, "algorithm": ALGORITHM_VERSION}
True
"""

from ._version import ALGORITHM_VERSION
from ._version import __version__ as __version__
from .api import components, prune
from .errors import (
    EmptyMaskError,
    ImageTooLargeError,
    InvalidImageError,
    InvalidOptionError,
    InvalidPolygonError,
    SkelpruneError,
)
from .graph import BranchGraph
from .io.frame import PixelFrame
from .matching import Match, SkeletonDescriptor, UnmatchableShapeError, describe, match
from .medial_axis import MedialAxis, medial_axis, squared_distance
from .output.document import ComponentResult, PruneResult
from .reconstruction import reconstruction, reconstruction_error

__all__ = [
    "ALGORITHM_VERSION",
    "BranchGraph",
    "ComponentResult",
    "EmptyMaskError",
    "ImageTooLargeError",
    "InvalidImageError",
    "InvalidOptionError",
    "InvalidPolygonError",
    "Match",
    "MedialAxis",
    "PixelFrame",
    "PruneResult",
    "SkeletonDescriptor",
    "SkelpruneError",
    "UnmatchableShapeError",
    "components",
    "describe",
    "match",
    "medial_axis",
    "prune",
    "reconstruction",
    "reconstruction_error",
    "squared_distance",
]
