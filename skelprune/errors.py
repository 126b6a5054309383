"""Domain exceptions of skelprune.

Every error a caller can cause derives from :class:`SkelpruneError` (itself a
``ValueError``), so that a service can map each kind to one HTTP status without
ever letting an unexpected exception through as a bad-input answer.
"""

from __future__ import annotations

__all__ = [
    "EmptyMaskError",
    "ImageTooLargeError",
    "InvalidImageError",
    "InvalidOptionError",
    "InvalidPolygonError",
    "SkelpruneError",
]


class SkelpruneError(ValueError):
    """Base class of every error caused by the caller's input."""


class InvalidImageError(SkelpruneError):
    """The bytes are not a decodable PNG (bad signature, truncated, corrupt)."""


class ImageTooLargeError(SkelpruneError):
    """The image has more pixels than the configured limit."""


class EmptyMaskError(SkelpruneError):
    """The mask has no foreground pixel, so there is no shape to skeletonise."""


class InvalidPolygonError(SkelpruneError):
    """A polygon is malformed (unclosed ring, non-finite coordinates, too many vertices)."""


class InvalidOptionError(SkelpruneError):
    """An option is out of range or unknown (beta <= 0, unknown method, ...)."""
