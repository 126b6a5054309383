"""Domain exceptions of skelprune.

Every error a caller can cause derives from :class:`SkelpruneError` (itself a
``ValueError``), so that a service can map each kind to one HTTP status without
ever letting an unexpected exception through as a bad-input answer. Each class names its
problem ``kind`` (the service's problem type, ``urn:skelprune:problem:KIND``), so that
whoever records a failure (the service, :func:`skelprune.parallel.prune_many`) says it
the same way: :func:`problem_kind`.
"""

from __future__ import annotations

import re
from typing import Any

__all__ = [
    "EmptyMaskError",
    "ImageTooLargeError",
    "InvalidImageError",
    "InvalidOptionError",
    "InvalidPolygonError",
    "JobTooLargeError",
    "SkelpruneError",
    "plain_text",
    "problem_kind",
    "shown",
]


class SkelpruneError(ValueError):
    """Base class of every error caused by the caller's input."""

    kind = "invalid-input"


class InvalidImageError(SkelpruneError):
    """The bytes are not a decodable PNG (bad signature, truncated, corrupt)."""

    kind = "invalid-image"


class ImageTooLargeError(SkelpruneError):
    """The image has more pixels than the configured limit."""

    kind = "image-too-large"


class EmptyMaskError(SkelpruneError):
    """The mask has no foreground pixel, so there is no shape to skeletonise."""

    kind = "empty-mask"


class InvalidPolygonError(SkelpruneError):
    """A polygon is malformed (unclosed ring, non-finite coordinates, too many vertices)."""

    kind = "invalid-polygon"


class InvalidOptionError(SkelpruneError):
    """An option is out of range or unknown (beta <= 0, unknown method, ...).

    ``errors`` lists ``(option, message)`` for each option refused on its own (every one
    of an options value, so that a caller can name each where it was given); it is empty
    when options are refused together (two that exclude each other).
    """

    kind = "invalid-option"

    def __init__(self, message: str, errors: list[tuple[str, str]] | None = None) -> None:
        super().__init__(message)
        self.errors = errors or []


class JobTooLargeError(SkelpruneError):
    """The job's estimated memory or time is over its budget, or it ran out of memory
    (:mod:`skelprune.budget`)."""

    kind = "job-too-large"


def problem_kind(exc: BaseException) -> str | None:
    """The problem kind of a caller's error (``None`` for any other exception).

    >>> problem_kind(EmptyMaskError("no shape")), problem_kind(KeyError("x"))
    ('empty-mask', None)
    """
    return exc.kind if isinstance(exc, SkelpruneError) else None


def shown(value: Any) -> str:
    """A value as an error message shows it: short, and a huge integer by its size (it
    has no repr past 4300 digits).

    >>> shown(10**400), shown(0.5), shown("x" * 50)
    ('<integer of 1329 bits>', '0.5', "'xxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxx...")
    """
    if isinstance(value, int) and not isinstance(value, bool):
        try:
            float(value)
        except OverflowError:
            return f"{'-' if value < 0 else ''}<integer of {value.bit_length()} bits>"
    text = plain_text(repr(value))
    return text if len(text) <= 40 else text[:37] + "..."


_NUMPY_SCALAR = re.compile(r"\bnp\.(?:float|int|uint|bool|str)_?\d*\(([^()]*)\)")
_ADDRESS = re.compile(r"<([^<>]*?) at 0x[0-9a-fA-F]+>")


def plain_text(text: str) -> str:
    """A message without the interpreter's internals: numpy scalars as their value
    (``np.float64(2.0)``: ``2.0``), an object's address dropped (``<ast.BinOp object at
    0x7f…>``: ``<ast.BinOp object>``). Every error answer's detail goes through it.

    >>> plain_text("got (np.float64(2.5), np.int64(3)) and <ast.BinOp object at 0x7f00>")
    'got (2.5, 3) and <ast.BinOp object>'
    """
    return _ADDRESS.sub(r"<\1>", _NUMPY_SCALAR.sub(r"\1", text))
