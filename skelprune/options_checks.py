"""How an option's value is checked: the field factory the option classes declare their
fields with (default, help text, spellings and check), and the checks themselves, a
check's bounds attached to it as a JSON-schema fragment for documents that show them.
The classes are in :mod:`skelprune.options` and :mod:`skelprune.options_input`.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from dataclasses import field, fields
from typing import Any

from .errors import InvalidOptionError, shown

#: The kinds of input (:mod:`skelprune.options_where` says which answers each has).
INPUT_KINDS = ("image", "polygon", "volume")
#: Where an option applies when its definition says nothing: every input, every answer.
EVERYWHERE: dict[str, tuple[str, ...] | None] = dict.fromkeys(INPUT_KINDS)


def _option(
    default: Any,
    help: str,
    check: Callable[[str, Any], Any],
    choices: tuple[str, ...] | None = None,
    where: dict[str, tuple[str, ...] | None] | None = None,
) -> Any:
    """An option's field: its default, help text, check, spellings, and ``where`` it
    applies: ``{input kind: the answers it applies to, or None for every answer}``
    (the kinds left out are the inputs it does not apply to)."""
    metadata = {"help": help, "choices": choices, "check": check, "where": where or EVERYWHERE}
    return field(default=default, metadata=metadata)


def _with_schema(check: Callable[[str, Any], Any], **schema: Any) -> Callable[[str, Any], Any]:
    """Attach the check's bounds as a JSON-schema fragment, for documents that show them."""
    check.schema = schema  # type: ignore[attr-defined]
    return check


def _number(low: float, strict: bool, high: float | None = None) -> Callable[[str, Any], float]:
    def check(name: str, value: Any) -> float:
        try:
            finite = (
                not isinstance(value, bool)
                and isinstance(value, int | float)
                and math.isfinite(value)
            )
        except OverflowError:  # an integer too large for a float
            finite = False
        if (
            not finite
            or value < low
            or (strict and value == low)
            or (high is not None and value > high)
        ):
            upper = "" if high is None else f" and <= {high:g}"
            raise InvalidOptionError(
                f"{name} must be a finite number {'>' if strict else '>='} {low:g}{upper}, "
                f"got {shown(value)}"
            )
        return float(value)

    schema: dict[str, float] = {"exclusiveMinimum" if strict else "minimum": low}
    if high is not None:
        schema["maximum"] = high
    return _with_schema(check, **schema)


def _integer(low: int, high: int) -> Callable[[str, Any], int]:
    def check(name: str, value: Any) -> int:
        if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
            raise InvalidOptionError(
                f"{name} must be an integer from {low} to {high}, got {shown(value)}"
            )
        return value

    return _with_schema(check, minimum=low, maximum=high)


def _choice(choices: tuple[str, ...]) -> Callable[[str, Any], str]:
    def check(name: str, value: Any) -> str:
        if value not in choices:
            raise InvalidOptionError(
                f"{name} must be one of {', '.join(choices)}; got {shown(value)}"
            )
        return value

    return check


def _flag(name: str, value: Any) -> bool:
    if not isinstance(value, bool):
        raise InvalidOptionError(f"{name} must be true or false, got {shown(value)}")
    return value


def _crs_name(name: str, value: Any) -> str:
    if not isinstance(value, str):
        raise InvalidOptionError(f"{name} must be a CRS name (e.g. EPSG:4326), got {shown(value)}")
    from .io.crs import PLANAR, check_crs

    if value == PLANAR:
        return value
    return check_crs(value, name)  # a map CRS of the Earth pyproj knows, or which not


def _check_fields(options: Any) -> None:
    """Check (and normalise) every field of a frozen options object in place; a field
    whose default is None may be left unset. Every refused field is named in the error
    (:attr:`InvalidOptionError.errors`), not only the first."""
    errors: list[tuple[str, str]] = []
    for f in fields(options):
        value = getattr(options, f.name)
        if value is None and f.default is None:
            continue
        try:
            object.__setattr__(options, f.name, f.metadata["check"](f.name, value))
        except InvalidOptionError as exc:
            errors.append((f.name, str(exc)))
    if errors:
        raise InvalidOptionError("; ".join(message for _, message in errors), errors)


#: A number as text is read: plain ASCII decimal (Python's float() also reads "1_0" and
#: other scripts' digits).
PLAIN_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?", re.ASCII)
#: The range of a pixel's or voxel's size: past it, lengths, areas and volumes would
#: overflow or vanish in floating point (a 1e308 spacing makes every length infinite).
SCALE_RANGE = (1e-12, 1e12)


def _scale(name: str, value: Any) -> float:
    """A pixel's size: a finite number within :data:`SCALE_RANGE`."""
    low, high = SCALE_RANGE
    try:
        ok = not isinstance(value, bool) and isinstance(value, int | float) and low <= value <= high
    except OverflowError:
        ok = False
    if not ok:
        raise InvalidOptionError(
            f"{name} must be a finite number from {low:g} to {high:g}, got {shown(value)}"
        )
    return float(value)


_with_schema(_scale, minimum=SCALE_RANGE[0], maximum=SCALE_RANGE[1])


def _spacing(name: str, value: Any) -> tuple[float, float, float]:
    try:
        if isinstance(value, str):  # "dz,dy,dx", as a query or the CLI writes it
            parts = value.split(",")
            if not all(PLAIN_NUMBER.fullmatch(v.strip()) for v in parts):
                raise ValueError(value)  # "1_0" and other digits than ASCII: refused
            values: tuple[Any, ...] = tuple(float(v) for v in parts)
        else:
            values = tuple(value)
    except (TypeError, ValueError):
        values = ()
    low, high = SCALE_RANGE
    if len(values) != 3 or not all(
        not isinstance(v, bool) and isinstance(v, int | float) and low <= v <= high for v in values
    ):
        raise InvalidOptionError(
            f"{name} must be three finite numbers > 0 (dz, dy, dx), each from {low:g} to "
            f"{high:g}, got {shown(value)}"
        )
    return (float(values[0]), float(values[1]), float(values[2]))


_with_schema(
    _spacing,
    type="array",
    items={"type": "number", "exclusiveMinimum": 0},
    minItems=3,
    maxItems=3,
)
