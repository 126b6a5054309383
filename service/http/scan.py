"""JSON bodies measured before they are decoded: positions, polygon parts, batch items.

Decoding a polygon builds objects per position (Python lists and floats, then the
request's models): about 500 bytes and 10 µs a position in all. So a body's positions
are counted on its bytes first, in memory bounded by the body, and a polygon over
``SKELPRUNE_MAX_VERTICES`` or over the job's time budget is refused before any object
is built. A batch is split into its items the same way, so that the item limit applies
while the list is read and each item is measured before it is decoded.

What is counted is an upper bound that is exact on GeoJSON: a *position* is an array
whose first item is a number (a ``bbox`` counts as one too), a *part* an array holding
an array of positions (a polygon's rings).
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from typing import Any

from fastapi.exceptions import RequestValidationError

__all__ = ["BatchItem", "count_polygon", "split_batch"]

_BLANKS = b" \t\r\n"
_NUMBER_STARTS = [bytes([c]) for c in b"-0123456789"]
_STRING = rb'"(?:[^"\\]|\\.)*"'
#: An array of flat arrays (a ring of positions) or one flat array: one token, so that
#: the split below steps over a polygon's coordinates ring by ring, not number by number.
_FLAT = rb'\[\s*(?:\[[^\[\]{}"]*+\]\s*(?:,\s*)?)*+\]|\[[^\[\]{}"]*+\]'
#: Inside an item: what changes the nesting depth (runs of brackets at once).
_INNER = re.compile(rb"%s|%s|[\[{]+|[\]}]+" % (_STRING, _FLAT))
#: Between items: the same, and the comma that ends an item.
_OUTER = re.compile(rb"%s|%s|[\[{]+|[\]}]+|," % (_STRING, _FLAT))
_SPACE = re.compile(rb"\s*")


@dataclass(frozen=True)
class PolygonCounts:
    """What a polygon body holds: its parts, positions and values (commas + 1, an
    upper bound on its numbers, strings and objects)."""

    parts: int
    positions: int
    values: int = 0


def count_polygon(body: bytes) -> PolygonCounts:
    """Parts and positions of a GeoJSON body, counted on its bytes (no decoding).

    >>> count_polygon(b'{"type":"Polygon","coordinates":[[[0,0],[1,0],[1,1],[0,0]]]}')
    PolygonCounts(parts=1, positions=4, values=9)
    """
    # One copy without blanks, then C-speed counts of "[" before a number's first
    # character: no object per match (a regex's matches would cost ~100 B each).
    tight = body.translate(None, _BLANKS)
    return PolygonCounts(
        sum(tight.count(b"[[[" + c) for c in _NUMBER_STARTS),
        sum(tight.count(b"[" + c) for c in _NUMBER_STARTS),
        tight.count(b",") + 1,
    )


def _invalid(message: str) -> RequestValidationError:
    return RequestValidationError([{"loc": ("body",), "type": "json_invalid", "msg": message}])


@dataclass(frozen=True)
class BatchItem:
    """One item of a batch: its JSON text and counts (decoded later, if it is let in)."""

    text: bytes
    counts: PolygonCounts

    def decode(self) -> Any:
        """The item as plain data.

        Raises
        ------
        RequestValidationError
            Invalid JSON, or nested deeper than the parser's stack (the whole batch's
            problem, as a body that does not parse).
        """
        try:
            return json.loads(self.text)
        except ValueError as exc:
            raise _invalid(f"invalid JSON: {exc}") from None
        except RecursionError:
            raise _invalid("invalid JSON: nested too deep") from None


def split_batch(body: bytes, max_items: int) -> list[BatchItem]:
    """The items of a JSON list, split on its bytes; at most ``max_items`` of them.

    Raises
    ------
    RequestValidationError
        Not UTF-8, not a JSON list, or a list that does not end.
    OverflowError
        More than ``max_items`` items (found while reading: the rest is not read).

    >>> [i.text for i in split_batch(b' [{"a": [1, 2]}, 3 ,"x,]"] ', 8)]
    [b'{"a": [1, 2]}', b'3', b'"x,]"']
    """
    try:
        body.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise _invalid(f"invalid JSON: not UTF-8 (byte {exc.start})") from None
    pos = _SPACE.match(body).end()  # type: ignore[union-attr]
    if body[pos : pos + 1] != b"[":
        raise RequestValidationError(
            [
                {
                    "loc": ("body",),
                    "type": "list_type",
                    "msg": "a batch is a JSON list of GeoJSON objects",
                }
            ]
        )
    pos += 1
    items: list[BatchItem] = []

    def add(text: bytes) -> None:
        items.append(_item(text))
        if len(items) > max_items:
            raise OverflowError(len(items))

    start, depth = pos, 0
    while True:
        found = (_OUTER if depth == 0 else _INNER).search(body, pos)
        if found is None:
            raise _invalid("invalid JSON: the list does not end")
        token, pos = found.group(), found.end()
        first = token[:1]
        if first == b'"':
            pass
        elif first in b"[{":
            if first == b"[" and token[-1:] == b"]":
                continue  # a flat array, whole
            depth += len(token)
        elif first in b"]}":
            if depth >= len(token):
                depth -= len(token)
                continue
            end = found.start() + depth  # where the run closes the list itself
            if token[depth : depth + 1] != b"]":
                raise _invalid("invalid JSON: unbalanced brackets")
            pos = end + 1
            text = body[start:end].strip()
            if text or items:
                add(text)
            if body[pos:].strip():
                raise _invalid("invalid JSON: extra data after the list")
            return items
        elif token == b",":
            add(body[start : found.start()].strip())
            start = pos


def _item(text: bytes) -> BatchItem:
    if not text:
        raise _invalid("invalid JSON: an empty item in the list")
    return BatchItem(text, count_polygon(text))
