"""One function writes every answer: :func:`encode`.

The command line, the service and data-set runs write their answers with it, so the same
input and options give the same bytes through all of them. Numbers that are not finite
are null (:mod:`skelprune.output.finite`): every answer is valid JSON, CSV or XML.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from ..errors import InvalidOptionError
from ..options_where import ANSWERS, ANSWERS_OF, missing_answer
from .finite import finite_json

if TYPE_CHECKING:
    from .document import PruneResult
    from .volume import VolumeResult

__all__ = ["MEDIA_TYPES", "encode", "json_bytes"]

#: The media type of each answer.
MEDIA_TYPES = {
    "json": "application/json",
    "geojson": "application/geo+json",
    "csv": "text/csv; charset=utf-8",
    "graphml": "application/graphml+xml",
    "png": "image/png",
    "swc": "text/x-swc",
}


def json_bytes(doc: Any) -> bytes:
    """A document as compact JSON (no spaces), UTF-8; non-finite numbers null
    (:func:`skelprune.output.finite.finite_json`, the one rule).

    >>> json_bytes({"a": [1, 2.5, float("nan")], "b": "é"})
    b'{"a":[1,2.5,null],"b":"\\\\u00e9"}'
    """
    return finite_json(doc)


def encode(result: PruneResult | VolumeResult, answer: str = "json") -> bytes:
    """One answer of a result, as bytes.

    Parameters
    ----------
    result : PruneResult or VolumeResult
        What :func:`skelprune.prune` returned; its output options (``curve``,
        ``overlay``, ``simplify``, ``table``, ...) say what each answer holds.
    answer : {"json", "geojson", "csv", "graphml", "png", "swc"}
        The JSON document, the GeoJSON lines, the CSV table (``table``: one row a
        branch or a component), the GraphML graph, the overlay image (a volume's: its
        three projections) or the SWC skeleton (volumes).

    Raises
    ------
    InvalidOptionError
        For an answer this kind of result has not (a volume's GeoJSON).

    Examples
    --------
    >>> import numpy as np, skelprune
    >>> m = np.zeros((30, 60), bool); m[5:25, 5:55] = True
    >>> res = skelprune.prune(m)
    >>> encode(res)[:10], encode(res, "png")[:4], encode(res, "csv").split(b",")[0]
    (b'{"width":6', b'\\x89PNG', b'component')
    """
    from .volume import VolumeResult

    kind = "volume" if isinstance(result, VolumeResult) else "image"
    if answer not in ANSWERS or answer == "overlay":
        raise InvalidOptionError(
            f"unknown answer {answer!r}; the answers: {', '.join(MEDIA_TYPES)}"
        )
    if answer not in ANSWERS_OF[kind]:
        subject = "a volume" if kind == "volume" else "a shape"
        raise InvalidOptionError(missing_answer(subject, kind, answer))
    if isinstance(result, VolumeResult):
        if answer == "png":
            return result.overlay_png()
        if answer == "csv":
            return result.to_csv().encode()
        if answer == "swc":
            return result.to_swc().encode()
        return json_bytes(result.to_dict())
    if answer == "png":
        return result.overlay_png()
    if answer == "geojson":
        return json_bytes(result.to_geojson())
    if answer == "csv":
        return result.to_csv().encode()
    if answer == "graphml":
        return result.to_graphml().encode()
    return json_bytes(result.to_dict())
