"""Content negotiation: which answer the ``Accept`` header asks for."""

from __future__ import annotations

from service.errors import NotAcceptableError
from service.worker.jobs import Media

__all__ = ["NDJSON", "PRODUCES", "accept_json", "accept_ndjson", "negotiate"]

#: Media types ``POST /v1/prune`` can answer with, in the server's order of preference.
PRODUCES: dict[str, Media] = {
    "application/json": "json",
    "image/png": "png",
    "application/geo+json": "geojson",
    "text/csv": "csv",
    "application/graphml+xml": "graphml",
    "text/x-swc": "swc",
}
#: The batch's answer: one JSON document a line.
NDJSON = "application/x-ndjson"


def _ranges(accept: str) -> list[tuple[str, float]]:
    """The media ranges of an ``Accept`` header and their q-values (1 when not given,
    0 when unreadable)."""
    ranges: list[tuple[str, float]] = []
    for part in accept.split(","):
        fields = [f.strip() for f in part.split(";")]
        media = fields[0].lower()
        if not media:
            continue
        q = 1.0
        for param in fields[1:]:
            key, _, value = param.partition("=")
            if key.strip().lower() == "q":
                try:
                    q = float(value)
                except ValueError:
                    q = 0.0
        ranges.append((media, q))
    return ranges


def _quality(ranges: list[tuple[str, float]], candidate: str) -> float:
    """The q-value of ``candidate`` by its most specific matching range (0: none)."""
    main = candidate.split("/")[0]
    best, best_rank = 0.0, -1
    for media, q in ranges:
        rank = (
            2 if media == candidate else 1 if media == f"{main}/*" else 0 if media == "*/*" else -1
        )
        if rank > best_rank:
            best, best_rank = q, rank
    return best if best_rank >= 0 else 0.0


def negotiate(accept: str | None) -> Media:
    """Pick the output for an ``Accept`` header (q-values honoured; none means JSON).

    Raises
    ------
    NotAcceptableError
        When no producible type has q > 0.
    """
    if not accept or not accept.strip():
        return "json"
    ranges = _ranges(accept)
    if not ranges:  # only commas and blanks: no preference stated, as without the header
        return "json"
    scored = [(_quality(ranges, m), -i, out) for i, (m, out) in enumerate(PRODUCES.items())]
    q, _, out = max(scored)
    if q <= 0:
        raise NotAcceptableError(
            f"cannot produce any of {accept!r}; available: {', '.join(PRODUCES)}"
        )
    return out


def accept_ndjson(accept: str) -> None:
    """Refuse an ``Accept`` header that admits neither NDJSON nor JSON (q-values
    honoured, media types matched whole).

    Raises
    ------
    NotAcceptableError
        When the header states a preference and gives both q = 0 or leaves them out.

    Examples
    --------
    >>> accept_ndjson("application/x-ndjson, */*;q=0.1")
    >>> accept_ndjson("text/application/x-ndjson")  # a substring is not a match
    Traceback (most recent call last):
    ...
    service.errors.NotAcceptableError: cannot produce any of 'text/application/x-ndjson'; ...
    """
    ranges = _ranges(accept)
    if ranges and max(_quality(ranges, m) for m in (NDJSON, "application/json")) <= 0:
        raise NotAcceptableError(f"cannot produce any of {accept!r}; available: {NDJSON}")


def accept_json(accept: str | None) -> None:
    """Refuse an ``Accept`` header that admits no JSON (what ``/v1/match`` answers).

    Raises
    ------
    NotAcceptableError
        When the header states a preference and gives ``application/json`` q = 0 or
        leaves it out.

    >>> accept_json("*/*"), accept_json(None)
    (None, None)
    >>> accept_json("text/html")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    service.errors.NotAcceptableError: cannot produce any of 'text/html'; available: ...
    """
    ranges = _ranges(accept or "")
    if ranges and _quality(ranges, "application/json") <= 0:
        raise NotAcceptableError(f"cannot produce any of {accept!r}; available: application/json")
