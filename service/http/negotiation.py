"""Content negotiation: which answer the ``Accept`` header asks for."""

from __future__ import annotations

from service.errors import NotAcceptableError
from service.jobs import Output

__all__ = ["NDJSON", "PRODUCES", "accept_ndjson", "negotiate"]

#: Media types ``POST /v1/prune`` can answer with, in the server's order of preference.
PRODUCES: dict[str, Output] = {
    "application/json": "json",
    "image/png": "png",
    "application/geo+json": "geojson",
    "text/csv": "csv",
    "application/graphml+xml": "graphml",
}
#: The batch's answer: one JSON document a line.
NDJSON = "application/x-ndjson"


def negotiate(accept: str | None) -> Output:
    """Pick the output for an ``Accept`` header (q-values honoured; none means JSON).

    Raises
    ------
    NotAcceptableError
        When no producible type has q > 0.
    """
    if not accept or not accept.strip():
        return "json"
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

    def quality(candidate: str) -> float:
        main = candidate.split("/")[0]
        best, best_rank = 0.0, -1
        for media, q in ranges:
            rank = (
                2
                if media == candidate
                else 1
                if media == f"{main}/*"
                else 0
                if media == "*/*"
                else -1
            )
            if rank > best_rank:
                best, best_rank = q, rank
        return best if best_rank >= 0 else 0.0

    if not ranges:  # only commas and blanks: no preference stated, as without the header
        return "json"
    scored = [(quality(m), -i, out) for i, (m, out) in enumerate(PRODUCES.items())]
    q, _, out = max(scored)
    if q <= 0:
        raise NotAcceptableError(
            f"cannot produce any of {accept!r}; available: {', '.join(PRODUCES)}"
        )
    return out


def accept_ndjson(accept: str) -> None:
    """Refuse an ``Accept`` header that admits neither NDJSON nor JSON.

    Raises
    ------
    NotAcceptableError
        When the header is given and names none of them (nor ``*/*``).
    """
    if accept.strip() and not any(m in accept for m in (NDJSON, "application/json", "*/*")):
        raise NotAcceptableError(f"cannot produce any of {accept!r}; available: {NDJSON}")
