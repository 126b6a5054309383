"""One rule for numbers that are not finite in every answer: such a number is null.

An answer's number that came out NaN or infinite (an undefined junction angle, a
length past the float range) is written as null in every encoding: ``None`` in a
document (JSON and GeoJSON ``null``), an empty CSV cell, a GraphML value left out, the
word ``null`` in a PNG answer's header list. Options that would make every number
overflow are refused up front instead (their ranges, in :mod:`skelprune.options`).
Every encoder reads its numbers through :func:`finite` or :func:`finite_tree`.
"""

from __future__ import annotations

import math
from typing import Any

__all__ = ["finite", "finite_text", "finite_tree"]


def finite(value: Any) -> Any:
    """``value``, or None where it is a float (or a numpy float) that is not finite.

    >>> finite(1.5), finite(float("nan")), finite(float("-inf")), finite("x"), finite(3)
    (1.5, None, None, 'x', 3)
    """
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def finite_tree(doc: Any) -> Any:
    """A document (dicts, lists, tuples of plain values) with every non-finite float
    made None; the document itself where it holds none (no copy).

    >>> finite_tree({"a": [1.0, float("inf")], "b": (float("nan"), "x")})
    {'a': [1.0, None], 'b': [None, 'x']}
    >>> d = {"a": [1.0, 2]}; finite_tree(d) is d
    True
    """
    return doc if _is_finite(doc) else _replaced(doc)


def finite_text(value: Any) -> str:
    """A number as a header list writes it: ``repr`` of the float, ``null`` where it is
    not finite (or missing).

    >>> finite_text(2.0), finite_text(float("nan")), finite_text(None)
    ('2.0', 'null', 'null')
    """
    number = None if value is None else finite(float(value))
    return "null" if number is None else repr(number)


def _is_finite(doc: Any) -> bool:
    stack = [doc]
    while stack:
        item = stack.pop()
        if isinstance(item, float):
            if not math.isfinite(item):
                return False
        elif isinstance(item, dict):
            stack.extend(item.values())
        elif isinstance(item, list | tuple):
            stack.extend(item)
    return True


def _replaced(doc: Any) -> Any:
    if isinstance(doc, float):
        return finite(doc)
    if isinstance(doc, dict):
        return {k: _replaced(v) for k, v in doc.items()}
    if isinstance(doc, list | tuple):
        return [_replaced(v) for v in doc]
    return doc
