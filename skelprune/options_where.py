"""Where each option applies, read from its own definition, and the one check of it.

Every option's field says the inputs it applies to and, for each, the answers
(``where`` in :func:`skelprune.options_checks._option`). :func:`refuse_misplaced` is the
one check: :func:`skelprune.prune` runs it on what it is given, and the service runs it
on a request before queueing its work, so that every front refuses the same options with
the same words.
"""

from __future__ import annotations

from collections.abc import Collection, Iterable
from dataclasses import fields

from .errors import InvalidOptionError
from .options import GROUPS
from .options_checks import INPUT_KINDS

__all__ = [
    "ANSWERS",
    "ANSWERS_OF",
    "INPUT_KINDS",
    "missing_answer",
    "option_where",
    "refuse_misplaced",
]

#: What each answer is called in a message (the media type in brackets).
ANSWERS = {
    "json": "the JSON document (application/json)",
    "png": "the overlay image (image/png)",
    "overlay": "overlay=true",
    "geojson": "the GeoJSON answer (application/geo+json)",
    "csv": "the CSV tables (text/csv)",
    "graphml": "the GraphML graph (application/graphml+xml)",
    "swc": "the SWC answer (text/x-swc)",
}
#: The answers each kind of input has.
ANSWERS_OF = {
    "image": ("json", "png", "geojson", "csv", "graphml"),
    "polygon": ("json", "png", "geojson", "csv", "graphml"),
    "volume": ("json", "png", "csv", "swc"),
}
#: Why an input has not an answer, where a reason helps.
WHY_NOT = {
    ("volume", "geojson"): "its points are voxel indices in three dimensions, it has no "
    "map coordinates",
}
_INPUTS = {
    "image": "image input (PNG or TIFF)",
    "polygon": "polygon input (GeoJSON)",
    "volume": "volume input (a .npy file or a TIFF stack)",
}
_WHERE = {f.name: f.metadata["where"] for group in GROUPS for f in fields(group)}


def missing_answer(subject: str, kind: str, answer: str) -> str:
    """The words that refuse ``answer`` to an input of ``kind`` (``subject``: what it is
    called), with the reason where there is one (:data:`WHY_NOT`), naming the answers it
    has: the one wording of the option checks, :func:`skelprune.encode` and a volume's
    ``to_geojson``.

    >>> missing_answer("a volume", "volume", "graphml")  # doctest: +NORMALIZE_WHITESPACE
    'a volume has no GraphML graph (application/graphml+xml); its answers: the JSON
     document (application/json), the overlay image (image/png), the CSV tables
     (text/csv), the SWC answer (text/x-swc)'
    """
    why = WHY_NOT.get((kind, answer))
    because = f": {why}" if why else ""
    return (
        f"{subject} has no {ANSWERS[answer].replace('the ', '', 1)}{because}; its answers: "
        + ", ".join(ANSWERS[a] for a in ANSWERS_OF[kind])
    )


def option_where(name: str) -> dict[str, tuple[str, ...] | None]:
    """Where option ``name`` applies: ``{input kind: its answers, or None for all}``.

    >>> option_where("foreground"), option_where("table")
    ({'image': None}, {'image': ('csv',), 'polygon': ('csv',)})
    """
    return _WHERE[name]


def _answers(answers: Iterable[str]) -> str:
    return " or ".join(ANSWERS[a] for a in answers)


def _places(where: dict[str, tuple[str, ...] | None]) -> str:
    """Where an option applies, in words."""
    kinds = list(where)
    answers = set(where.values())
    if len(answers) == 1:
        only = next(iter(answers))
        inputs = " or ".join(_INPUTS[k].split(" input")[0] for k in kinds) + " input"
        if len(kinds) == 1:
            inputs = _INPUTS[kinds[0]]
        return inputs if only is None else f"{_answers(only)} of {inputs}"
    return ", or ".join(
        _INPUTS[k] if a is None else f"{_INPUTS[k]} with {_answers(a)}" for k, a in where.items()
    )


def refuse_misplaced(
    given: Iterable[str],
    kind: str,
    answers: str | Collection[str] | None = None,
    overlay: bool = False,
) -> None:
    """Refuse the options given where they do not apply.

    Parameters
    ----------
    given : names of the options given (a value other than the default, or named in a
        request)
    kind : ``"image"``, ``"polygon"`` or ``"volume"``
    answers : the answer asked for, or several (keys of :data:`ANSWERS`): an option
        applies when it applies to one of them; None when every answer may be asked of
        the result later (the library's result)
    overlay : the JSON document carries the overlay image (``overlay=true``)

    Raises
    ------
    InvalidOptionError
        Naming the options and where they apply.

    Examples
    --------
    >>> refuse_misplaced(["beta", "foreground"], "image", "json")
    >>> refuse_misplaced(["table"], "image", ("json", "csv"))
    >>> def refused(*args):
    ...     try:
    ...         refuse_misplaced(*args)
    ...     except InvalidOptionError as exc:
    ...         return str(exc)
    >>> refused(["foreground", "fill_holes"], "polygon")
    'option(s) foreground, fill_holes only apply to image input (PNG or TIFF)'
    >>> refused(["simplify"], "image", "csv")  # doctest: +NORMALIZE_WHITESPACE
    'option(s) simplify only apply to the GeoJSON answer (application/geo+json) of image
     input (PNG or TIFF), not to the CSV tables (text/csv)'
    >>> refused(["pixel_size"], "image", "json")  # doctest: +NORMALIZE_WHITESPACE
    'option(s) pixel_size only apply to the CSV tables (text/csv) or the GraphML graph
     (application/graphml+xml) of image input (PNG or TIFF), not to the JSON document
     (application/json)'
    >>> refused(["pixel_size"], "volume", "json")  # doctest: +NORMALIZE_WHITESPACE
    'option(s) pixel_size only apply to polygon input (GeoJSON), or image input (PNG or
     TIFF) with the CSV tables (text/csv) or the GraphML graph (application/graphml+xml)'
    >>> refused([], "volume", "geojson")  # doctest: +NORMALIZE_WHITESPACE
    'volume input (a .npy file or a TIFF stack) has no GeoJSON answer
     (application/geo+json): its points are voxel indices in three dimensions, it has no
     map coordinates; its answers: the JSON document (application/json), the
     overlay image (image/png), the CSV tables (text/csv), the SWC answer (text/x-swc)'
    """
    asked = None if answers is None else {answers} if isinstance(answers, str) else set(answers)
    for answer in sorted(asked or ()):
        if answer not in ANSWERS_OF[kind]:
            raise InvalidOptionError(missing_answer(_INPUTS[kind], kind, answer))
    if asked is not None and "json" in asked and overlay:
        asked.add("overlay")
    wrong_input: dict[str, list[str]] = {}
    wrong_answer: dict[str, list[str]] = {}
    for name in given:
        where = _WHERE[name]
        if kind not in where:
            wrong_input.setdefault(_places(where), []).append(name)
            continue
        applies = where[kind]
        if asked is not None and applies is not None and not asked & set(applies):
            wrong_answer.setdefault(f"{_answers(applies)} of {_INPUTS[kind]}", []).append(name)
    for place, names in wrong_input.items():
        raise InvalidOptionError(f"option(s) {', '.join(names)} only apply to {place}")
    for place, names in wrong_answer.items():
        shown = " or ".join(ANSWERS[a] for a in sorted(asked or ()) if a != "overlay")
        raise InvalidOptionError(
            f"option(s) {', '.join(names)} only apply to {place}, not to {shown}"
        )
