"""One rule for numbers that are not finite in every answer: such a number is null.

An answer's number that came out NaN or infinite (an undefined junction angle, a
length past the float range) is written as null in every encoding: ``None`` in a
document (JSON and GeoJSON ``null``: :func:`finite_tree`, :func:`finite_json`), an
empty CSV cell (:func:`finite_cell`), a GraphML value left out, the word ``null`` in a
PNG answer's header list (:func:`finite_text`), a map line's property null. Options
that would make every number overflow are refused up front instead (their ranges, in
:mod:`skelprune.options`); a format with no null (SWC, whose numbers are voxel
positions times a bounded spacing) refuses a number that is not finite as an overflow
(:func:`finite_number`). Every encoder reads its numbers through this module.
"""

from __future__ import annotations

import csv
import io
import json
import math
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

from ..errors import SkelpruneError

__all__ = [
    "OVERFLOW",
    "finite",
    "finite_cell",
    "finite_json",
    "finite_number",
    "finite_text",
    "finite_tree",
    "rows_csv",
    "rows_frame",
]

#: Why an answer in a format without null cannot be written: a number overflowed.
OVERFLOW = (
    "the answer would hold a number JSON cannot write (an overflow); scale the input "
    "coordinates down"
)


def finite(value: Any) -> Any:
    """``value``, or None where it is a float (or a numpy float) that is not finite.

    >>> finite(1.5), finite(float("nan")), finite(float("-inf")), finite("x"), finite(3)
    (1.5, None, None, 'x', 3)
    >>> finite(np.float32("nan")) is None
    True
    """
    if isinstance(value, float | np.floating) and not math.isfinite(value):
        return None
    return value


def finite_cell(value: Any) -> Any:
    """A CSV cell: ``value``, or the empty string for null and a number not finite.

    >>> finite_cell(2.5), finite_cell(float("nan")), finite_cell(None), finite_cell("end")
    (2.5, '', '', 'end')
    """
    number = finite(value)
    return "" if number is None else number


def rows_csv(rows: Iterable[dict[str, Any]], columns: Sequence[str]) -> str:
    """Table rows as CSV text: a header row of ``columns``, empty cells for null
    (:func:`finite_cell`); an image's tables and a volume's.

    >>> rows_csv([{"a": 1, "b": float("nan")}, {"a": None, "b": 2.5}], ("a", "b"))
    'a,b\\n1,\\n,2.5\\n'
    """
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=list(columns), lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({k: finite_cell(v) for k, v in row.items()})
    return buf.getvalue()


def rows_frame(rows: list[dict[str, Any]], columns: Sequence[str]) -> Any:
    """Table rows as a pandas ``DataFrame`` of ``columns`` when pandas is installed,
    else the rows themselves."""
    try:
        import pandas as pd
    except ImportError:
        return rows
    return pd.DataFrame(rows, columns=list(columns))


def finite_json(doc: Any) -> bytes:
    """A document as compact JSON bytes (no spaces), every number not finite null.

    >>> finite_json({"a": [1.0, float("nan")], "b": "x"})
    b'{"a":[1.0,null],"b":"x"}'
    """
    # allow_nan=False only guards the rule: finite_tree has made every such number null
    return json.dumps(finite_tree(doc), separators=(",", ":"), allow_nan=False).encode()


def finite_number(value: Any) -> str:
    """A number as a format without null writes it (``%g``); one that is not finite can
    only be an overflow, refused.

    >>> finite_number(2.0), finite_number(np.float64(0.125))
    ('2', '0.125')
    >>> finite_number(float("inf"))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    skelprune.errors.SkelpruneError: the answer would hold a number JSON cannot write ...
    """
    if finite(float(value)) is None:
        raise SkelpruneError(OVERFLOW)
    return f"{float(value):g}"


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
        if isinstance(item, float | np.floating):
            if not math.isfinite(item):
                return False
        elif isinstance(item, dict):
            stack.extend(item.values())
        elif isinstance(item, list | tuple):
            stack.extend(item)
    return True


def _replaced(doc: Any) -> Any:
    if isinstance(doc, float | np.floating):
        return finite(doc)
    if isinstance(doc, dict):
        return {k: _replaced(v) for k, v in doc.items()}
    if isinstance(doc, list | tuple):
        return [_replaced(v) for v in doc]
    return doc
