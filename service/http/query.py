"""The query options of a request, validated as one model."""

from __future__ import annotations

from typing import Any, get_args

from fastapi.exceptions import RequestValidationError
from pydantic import ValidationError
from starlette.datastructures import QueryParams

from service.http.schemas import PruneQuery

__all__ = ["QUERY_OPTIONS", "parse_query", "validation_error"]

#: Validation errors kept of one request.
MAX_KEPT = 100
QUERY_OPTIONS = frozenset(PruneQuery.model_fields)  # no aliases: field name = parameter
#: The options whose values are numbers, or lists of numbers (spacing).
NUMBER_OPTIONS = frozenset(
    name
    for name, f in PruneQuery.model_fields.items()
    if name == "spacing"
    or any(t in (int, float) for t in get_args(f.annotation))
    or any(t in (int, float) for a in get_args(f.annotation) for t in (a, *get_args(a)))
)


def _plain_values(params: QueryParams) -> list[dict[str, Any]]:
    """The errors of options given more than once or numbers not written in plain ASCII
    decimal (Python and pydantic would read ``1_0`` as 10)."""
    errors: list[dict[str, Any]] = []
    counts: dict[str, int] = {}
    for key, _ in params.multi_items():
        counts[key] = counts.get(key, 0) + 1
    for key, n in counts.items():
        if n > 1 and key in QUERY_OPTIONS:
            errors.append(
                {
                    "loc": ("query", key),
                    "type": "repeated",
                    "msg": f"given {n} times; give an option once",
                }
            )
        elif key in NUMBER_OPTIONS and (not params[key].isascii() or "_" in params[key]):
            errors.append(
                {
                    "loc": ("query", key),
                    "type": "number_format",
                    "msg": "write numbers in plain ASCII decimal (digits 0-9, '.', 'e'), "
                    "without '_'",
                }
            )
    return errors


def validation_error(
    errors: list[dict[str, Any]], prefix: tuple[str, ...]
) -> RequestValidationError:
    """Validation errors located under ``prefix`` (``("query",)``, ``("body",)``); the
    first :data:`MAX_KEPT` of them (what an answer can list, and a few over, so that the
    answer says there were more)."""
    return RequestValidationError(
        [{**e, "loc": (*prefix, *e.get("loc", ()))} for e in errors[:MAX_KEPT]]
    )


def parse_query(params: QueryParams) -> PruneQuery:
    """The query options, validated as one model.

    Does what FastAPI does for a parameter ``Annotated[PruneQuery, Query()]`` (any other
    parameter goes to the model too, a list if repeated, where ``extra="forbid"``
    refuses it; errors are located at ``("query", name)``), without its per-field
    dependency machinery, which took about a third of the application's own CPU time
    per request. An option given twice is refused (which one was meant is not known),
    and so is a number written other than in plain ASCII decimal digits (``1_0``,
    Arabic-Indic digits).

    Raises
    ------
    RequestValidationError
        When an option is invalid or unknown.
    """
    errors = _plain_values(params)
    if errors:
        raise RequestValidationError(errors)
    data: dict[str, Any] = {name: params[name] for name in QUERY_OPTIONS if name in params}
    extras: dict[str, list[str]] = {}
    for key, value in params.multi_items():
        if key not in QUERY_OPTIONS:
            extras.setdefault(key, []).append(value)
    data.update((key, v[0] if len(v) == 1 else v) for key, v in extras.items())
    try:
        return PruneQuery.model_validate(data)
    except ValidationError as exc:
        raise validation_error(exc.errors(include_url=False), ("query",)) from None
