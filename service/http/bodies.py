"""Request bodies: the content type, the guards, JSON bodies and multipart forms.

Every endpoint reads its body through here, so that a body is refused the same way
whichever endpoint it was sent to (the problems are mapped to statuses in
:data:`service.errors.PROBLEMS`).
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, TypeVar

from fastapi import Request
from fastapi.exceptions import RequestValidationError
from pydantic import ValidationError
from starlette.datastructures import QueryParams, UploadFile

from service.errors import BodyTooLargeError, UnsupportedMediaTypeError
from service.http.query import parse_query, validation_error
from service.http.scan import BatchItem, PolygonCounts, count_polygon, split_batch
from service.http.schemas import MatchPolygons, PolygonJob, PruneQuery, polygon_request_adapter
from skelprune.budget import check_polygon
from skelprune.errors import InvalidOptionError, InvalidPolygonError
from skelprune.io.input import check_image_size
from skelprune.volume import check_volume_size, is_volume

__all__ = [
    "BATCH_MAX_ITEMS",
    "BIG_JSON",
    "JSON_TYPES",
    "Form",
    "batch_size",
    "body_errors",
    "check_polygon_body",
    "check_upload",
    "check_values",
    "content_type",
    "declared_type",
    "measure_upload",
    "parse_batch",
    "parse_pair",
    "parse_polygon",
    "polygon_item",
    "read_form",
    "refuse_encoding",
    "validate_json",
]

T = TypeVar("T")

JSON_TYPES = ("application/json", "application/geo+json")
BIG_JSON = 256 * 1024  # bytes of JSON above which validation moves to a thread
#: Most shapes in one batch request (more: 413 before any is pruned).
BATCH_MAX_ITEMS = 32
#: Tags of the JSON body's union: pydantic puts them in error locations, the user's body
#: has no such level.
BODY_TAGS = frozenset({"Polygon", "MultiPolygon", "Feature", "FeatureCollection", "job"})


def content_type(request: Request) -> str:
    """The request's media type, lower case, without parameters (``""`` if none)."""
    return request.headers.get("content-type", "").split(";")[0].strip().lower()


def refuse_encoding(request: Request) -> None:
    """Refuse a compressed body: never decode what was meant to be inflated.

    Raises
    ------
    UnsupportedMediaTypeError
        When ``Content-Encoding`` is other than ``identity``.
    """
    encoding = request.headers.get("content-encoding", "").strip().lower()
    if encoding not in ("", "identity"):
        raise UnsupportedMediaTypeError(
            f"Content-Encoding {encoding!r} is not supported; send the body uncompressed"
        )


async def validate_json(
    parse: Callable[[bytes], T], body: bytes, check: Callable[[bytes], None] | None = None
) -> T:
    """``check(body)`` then ``parse(body)``; a big body takes a while to measure and
    validate: off the event loop, so that other requests (health checks included) keep
    being served meanwhile."""

    def run() -> T:
        if check is not None:
            check(body)
        return parse(body)

    if len(body) > BIG_JSON:
        return await asyncio.to_thread(run)
    return run()


#: The first bytes of each file type an image body may be, by its ``Content-Type``.
SIGNATURES = {
    "image/png": (b"\x89PNG\r\n\x1a\n",),
    "image/tiff": (b"II*\x00", b"MM\x00*", b"II+\x00", b"MM\x00+"),
    "image/gif": (b"GIF87a", b"GIF89a"),
    "application/x-npy": (b"\x93NUMPY",),
}


def declared_type(data: bytes, declared: str | None) -> None:
    """Refuse an image body whose bytes are another type than its ``Content-Type``
    declares (a ``.npy`` sent as ``image/png``); a body of no known type is left to
    the reader, which names what it is.

    Raises
    ------
    UnsupportedMediaTypeError
        Naming the type the bytes are and the one declared.
    """
    if declared is None or declared not in SIGNATURES:
        return
    head = bytes(data[:8])
    actual = next(
        (t for t, sigs in SIGNATURES.items() if any(head.startswith(s) for s in sigs)), None
    )
    if actual is not None and actual != declared:
        raise UnsupportedMediaTypeError(
            f"the body is {actual} but its Content-Type says {declared}; send it as "
            f"Content-Type: {actual}"
        )


def measure_upload(data: bytes, max_pixels: int | None, declared: str | None = None) -> None:
    """An uploaded image or volume's type and size from its header, refused before it
    is queued (what the service checks of every file in the main process: bounded, and
    run off the event loop by :func:`check_upload`)."""
    declared_type(data, declared)
    if is_volume(data):
        check_volume_size(data, max_pixels)  # voxels count as pixels
    else:
        check_image_size(data, max_pixels)


async def check_upload(data: bytes, max_pixels: int | None, declared: str | None = None) -> None:
    """:func:`measure_upload` in a thread: a file's structure (a TIFF's pages and tags,
    a ``.npy`` header) is read off the event loop, so that health checks and other
    requests are served meanwhile."""
    await asyncio.to_thread(measure_upload, data, max_pixels, declared)


def check_polygon_body(
    max_vertices: int | None, seconds: float | None, shapes: int = 1
) -> Callable[[bytes], None]:
    """The check of a JSON body holding ``shapes`` polygons: their positions counted on
    the bytes, refused over ``shapes × max_vertices`` or when reading them would take
    longer than ``seconds`` (:func:`skelprune.budget.check_polygon`), before any object
    is built."""

    def check(body: bytes) -> None:
        counts = count_polygon(body)
        limit = None if max_vertices is None else max_vertices * shapes
        check_values(counts, limit)
        check_polygon(counts.parts, counts.positions, limit, seconds)

    return check


#: Values (numbers, strings, objects: commas + 1) a polygon body may hold per allowed
#: position: three coordinates and room for the rest. Parsing a JSON body holds the
#: interpreter for its whole length, and a value costs an object, so a body of
#: millions of values (a flat list of numbers, a bulky property) is refused on its
#: bytes, before it is parsed.
VALUES_PER_POSITION = 4
#: ... and the values a body may hold in any case (properties of a small polygon).
VALUES_ALLOWED = 65_536


def check_values(counts: PolygonCounts, max_positions: int | None) -> None:
    """Refuse a body of more values than its positions could need.

    Raises
    ------
    InvalidPolygonError
        Naming the count and the limit.
    """
    if max_positions is None:
        return
    limit = VALUES_PER_POSITION * max_positions + VALUES_ALLOWED
    if counts.values > limit:
        raise InvalidPolygonError(
            f"the body holds about {counts.values} JSON values, more than the {limit} a "
            f"polygon of at most {max_positions} positions needs (a GeoJSON polygon's "
            "coordinates are arrays of rings of [x, y] positions)"
        )


def body_errors(errors: list[Any]) -> list[dict[str, Any]]:
    """Validation errors located in the user's body, without pydantic's union tags."""
    shown = []
    for e in errors:
        loc = tuple(p for p in e.get("loc", ()) if p not in BODY_TAGS)
        if e.get("type") == "union_tag_invalid":
            given = (e.get("ctx") or {}).get("tag")
            e = {
                **e,
                "msg": f"GeoJSON type {given!r} is not accepted: send a Polygon, "
                "MultiPolygon, Feature or FeatureCollection, or "
                '{"geojson": <one of those>, <options>}',
            }
        elif e.get("type") == "model_type":  # pydantic names the model class here
            e = {**e, "msg": "Input should be a JSON object"}
        shown.append({**e, "loc": loc})
    return shown


def parse_polygon(body: bytes) -> tuple[PolygonJob | None, dict[str, Any]]:
    """Validate a JSON body: (envelope with options or None, GeoJSON as plain data)."""
    try:
        parsed = polygon_request_adapter.validate_json(body)
    except ValidationError as exc:
        raise validation_error(body_errors(exc.errors(include_url=False)), ("body",)) from None
    envelope = parsed if isinstance(parsed, PolygonJob) else None
    shape = parsed.geojson if envelope is not None else parsed
    return envelope, shape.model_dump(mode="json", exclude_none=True)


def parse_pair(body: bytes) -> tuple[dict[str, Any], dict[str, Any]]:
    """Validate the JSON body of a match: the GeoJSON of ``a`` and ``b`` as plain data."""
    try:
        parsed = MatchPolygons.model_validate_json(body)
    except ValidationError as exc:
        raise validation_error(exc.errors(include_url=False), ("body",)) from None
    return (
        parsed.a.model_dump(mode="json", exclude_none=True),
        parsed.b.model_dump(mode="json", exclude_none=True),
    )


def parse_batch(body: bytes) -> list[BatchItem]:
    """A batch's JSON body: its items, split on the bytes and measured, not decoded
    (each item is decoded and validated alone: one bad item fails alone).

    Raises
    ------
    RequestValidationError
        Not UTF-8, or not a JSON list.
    BodyTooLargeError
        More than :data:`BATCH_MAX_ITEMS` items (the rest is not read).
    InvalidOptionError
        An empty list.
    """
    try:
        items = split_batch(body, BATCH_MAX_ITEMS)
    except OverflowError:
        raise BodyTooLargeError(
            f"a batch holds at most {BATCH_MAX_ITEMS} shapes; this one holds more"
        ) from None
    batch_size(items)
    return items


def polygon_item(item: Any) -> dict[str, Any]:
    """One batch item validated as a GeoJSON object, as plain data.

    Raises
    ------
    InvalidPolygonError
        When it is not a valid GeoJSON shape (the first error, located in the item).
    InvalidOptionError
        When it is an envelope with options (a batch's options go in the query).
    """
    try:
        shape = polygon_request_adapter.validate_python(item)
    except ValidationError as exc:
        first = body_errors(exc.errors(include_url=False))[0]
        where = ".".join(str(p) for p in first["loc"])
        raise InvalidPolygonError(f"{where or 'shape'}: {first['msg']}") from None
    if isinstance(shape, PolygonJob):
        raise InvalidOptionError("a batch item is a GeoJSON object; options go in the query")
    return shape.model_dump(mode="json", exclude_none=True)


def batch_size(items: list[Any]) -> None:
    """Refuse an empty batch, and one over :data:`BATCH_MAX_ITEMS` shapes (a multipart
    batch; a JSON batch is counted as it is split, :func:`parse_batch`)."""
    if not items:
        raise InvalidOptionError("the batch is empty: send at least one shape")
    if len(items) > BATCH_MAX_ITEMS:
        raise BodyTooLargeError(f"a batch holds at most {BATCH_MAX_ITEMS} shapes, got {len(items)}")


@dataclass(frozen=True)
class Form:
    """A multipart form as read: each field in order, an uploaded file as its bytes and a
    text field as its string."""

    items: tuple[tuple[str, bytes | str], ...]

    def get(self, name: str) -> bytes | str | None:
        """The field's last value (as a form's lookup gives it)."""
        found = [v for k, v in self.items if k == name]
        return found[-1] if found else None

    def names(self) -> list[str]:
        """The field names, each once."""
        return list(dict.fromkeys(k for k, _ in self.items))

    def files(self, name: str) -> list[bytes]:
        """The files uploaded in the (repeated) field ``name``, in order."""
        return [v for k, v in self.items if k == name and isinstance(v, bytes)]

    def uploads(self, names: tuple[str, ...], what: str) -> list[bytes]:
        """The file of each named field.

        Raises
        ------
        RequestValidationError
            Naming every field that holds no file ("multipart field 'a' with ``what``
            is required").
        """
        missing = [k for k in names if not isinstance(self.get(k), bytes)]
        if missing:
            raise RequestValidationError(
                [
                    {
                        "loc": ("body", k),
                        "type": "missing",
                        "msg": f"multipart field {k!r} with {what} is required",
                    }
                    for k in missing
                ]
            )
        return [v for v in map(self.get, names) if isinstance(v, bytes)]

    def options(self, files: str) -> PruneQuery:
        """The text fields other than ``files``, read as options as the query's are
        (unknown ones refused; errors located in the body)."""
        fields = QueryParams([(k, v) for k, v in self.items if k != files and isinstance(v, str)])
        try:
            return parse_query(fields)
        except RequestValidationError as exc:
            raise RequestValidationError(
                [{**e, "loc": ("body", *e["loc"][1:])} for e in exc.errors()]
            ) from None


async def read_form(request: Request, max_files: int) -> Form:
    """The request's multipart form, at most ``max_files`` files and 16 text fields."""
    items: list[tuple[str, bytes | str]] = []
    async with request.form(max_files=max_files, max_fields=16) as form:
        for key, value in form.multi_items():
            items.append((key, await value.read() if isinstance(value, UploadFile) else value))
    return Form(tuple(items))
