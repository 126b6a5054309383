"""Pydantic v2 models of everything the service reads and writes.

Request bodies are validated strictly (no coercion; unknown fields refused). The
response models describe the output documents exactly (``extra="forbid"``), so the
OpenAPI schema is a contract that tests and schemathesis check the answers against.
The document's and the GeoJSON's models are built from the library's own types
(:mod:`skelprune.output.schema`), so that the two cannot drift.
"""

from __future__ import annotations

import functools
import json
import operator
from dataclasses import fields as dataclass_fields
from types import UnionType
from typing import (
    Annotated,
    Any,
    Literal,
    NotRequired,
    Union,
    get_args,
    get_origin,
    get_type_hints,
    is_typeddict,
)

from pydantic import (
    BaseModel,
    ConfigDict,
    Discriminator,
    Field,
    Tag,
    TypeAdapter,
    create_model,
    model_validator,
)

from skelprune.options import GROUPS, RasterOptions, ReadOptions, VolumeOptions
from skelprune.output import schema
from skelprune.output.schema import Doc, Len

__all__ = [
    "FiniteFloat",
    "GeoJSONInput",
    "Health",
    "MatchDocument",
    "MatchPolygons",
    "PolygonJob",
    "PolygonRequest",
    "Problem",
    "PruneDocument",
    "PruneQuery",
    "Readiness",
    "SkeletonGeoJSON",
    "Version",
    "polygon_request_adapter",
    "query_parameters",
]

STRICT = ConfigDict(strict=True, extra="forbid")
FiniteFloat = Annotated[float, Field(allow_inf_nan=False)]


# --------------------------------------------------------------------- input: options
def _option_models() -> tuple[type[BaseModel], dict[str, Any]]:
    """The query model and the body's option fields, from the library's option classes.

    Only the wire types are declared here (a number, a flag, one of the choices); the
    values are checked once, by the library's option classes, when the request builder
    makes them (:mod:`service.http.builder`), which locates each error where it was given.
    The checks' bounds are shown in the schema.
    """
    fields: dict[str, Any] = {}
    for group in GROUPS:
        if group is VolumeOptions:  # spacing: three numbers written DZ,DY,DX, below
            continue
        hints = get_type_hints(group)
        for f in dataclass_fields(group):
            choices = f.metadata["choices"]
            kind = hints[f.name]
            wire: Any = (
                Literal[choices]
                if choices
                else (
                    bool
                    if kind is bool
                    else int
                    if int in (kind, *get_args(kind))
                    else str
                    if str in (kind, *get_args(kind))
                    else FiniteFloat
                )
            )
            default = f.default if f.default is not None else "none" if choices else None
            text = f.metadata["help"]
            if default is not None and "default" not in text:
                text += f" Default `{json.dumps(default).strip(chr(34))}`."
            only = {RasterOptions: "Polygon", ReadOptions: "PNG"}.get(group)
            if only:
                text = f"{only} input only: " + text[0].lower() + text[1:]
            if f.name == "longest_side":
                text += " A server may set a default (`SKELPRUNE_POLYGON_LONGEST_SIDE`)."
            schema = getattr(f.metadata["check"], "schema", None)
            fields[f.name] = (wire | None, Field(None, description=text, json_schema_extra=schema))
    spacing = dataclass_fields(VolumeOptions)[0]
    fields[spacing.name] = (
        str | None,
        Field(
            None,
            description=spacing.metadata["help"]
            + " Written `dz,dy,dx` (`3,1,1`); for a `.npy` or TIFF stack body only.",
            json_schema_extra={"pattern": r"^[^,]+,[^,]+,[^,]+$", "examples": ["3,1,1"]},
        ),
    )
    query = create_model("PruneQuery", __config__=ConfigDict(extra="forbid"), **fields)
    query.__doc__ = "Options in the query string (all optional; unknown parameters are refused)."
    return query, fields


PruneQuery, _BODY_OPTIONS = _option_models()


def query_parameters(model: type[BaseModel]) -> list[dict[str, Any]]:
    """OpenAPI ``parameters`` for a query-options model whose fields are all optional.

    The route parses its query string itself (one validation of the whole model, see
    ``routes.parse_query``) instead of declaring the model to FastAPI, so the document
    gets the parameters from here, in the form FastAPI would give them.
    """
    properties = model.model_json_schema()["properties"]
    params = []
    for name, field in model.model_fields.items():
        key = field.alias or name
        schema = {k: v for k, v in properties[key].items() if not (k == "default" and v is None)}
        param: dict[str, Any] = {"name": key, "in": "query", "required": False, "schema": schema}
        if field.description:
            param["description"] = field.description
        params.append(param)
    return params


# ---------------------------------------------------------------- input: GeoJSON
#: GeoJSON objects may carry foreign members (RFC 7946 §6.1: ``crs``, ``name``, …, as GDAL
#: and geopandas write them): kept, and passed on to the library, which reads ``crs``.
GEOJSON = ConfigDict(strict=True, extra="allow")
#: Option names, refused as foreign members: an option there would be ignored silently
#: (but ``crs``, which is the GeoJSON's own member too).
_OPTION_NAMES = frozenset(f.name for group in GROUPS for f in dataclass_fields(group)) - {"crs"}


class _GeoJSONObject(BaseModel):
    model_config = GEOJSON

    @model_validator(mode="after")
    def _no_options(self) -> Any:
        misplaced = sorted(_OPTION_NAMES & set(self.model_extra or ()))
        if misplaced:
            raise ValueError(
                f"{', '.join(misplaced)}: an option inside the GeoJSON object; options go in "
                'the query, or beside it: {"geojson": ..., "beta": ...}'
            )
        return self


# fail_fast: a list stops at its first invalid item, so that a body of a million wrong
# numbers makes one validation error, not a million (each an object, and a line of the
# answer).
Position = Annotated[list[FiniteFloat], Field(min_length=2, max_length=3, fail_fast=True)]
LinearRing = Annotated[list[Position], Field(min_length=4, fail_fast=True)]
BBox = Annotated[list[FiniteFloat], Field(min_length=4, max_length=6, fail_fast=True)]


class PolygonGeometry(_GeoJSONObject):
    """GeoJSON Polygon: exterior ring first, then holes; rings closed."""

    type: Literal["Polygon"]
    coordinates: Annotated[list[LinearRing], Field(min_length=1, fail_fast=True)]
    bbox: BBox | None = None


class MultiPolygonGeometry(_GeoJSONObject):
    """GeoJSON MultiPolygon."""

    type: Literal["MultiPolygon"]
    coordinates: Annotated[
        list[Annotated[list[LinearRing], Field(min_length=1, fail_fast=True)]],
        Field(min_length=1, fail_fast=True),
    ]
    bbox: BBox | None = None


Geometry = Annotated[PolygonGeometry | MultiPolygonGeometry, Field(discriminator="type")]


class Feature(_GeoJSONObject):
    """GeoJSON Feature holding a Polygon or MultiPolygon, or none (``geometry: null``: the
    feature is skipped, with a warning)."""

    type: Literal["Feature"]
    geometry: Geometry | None
    properties: dict[str, Any] | None = None
    id: str | int | FiniteFloat | None = None
    bbox: BBox | None = None


class FeatureCollection(_GeoJSONObject):
    """GeoJSON FeatureCollection; the union of its polygons is the shape."""

    type: Literal["FeatureCollection"]
    features: Annotated[list[Feature], Field(min_length=1, fail_fast=True)]
    bbox: BBox | None = None


GeoJSONInput = Annotated[
    PolygonGeometry | MultiPolygonGeometry | Feature | FeatureCollection,
    Field(discriminator="type"),
]


PolygonJob = create_model(
    "PolygonJob",
    __config__=STRICT,
    geojson=(GeoJSONInput, ...),
    **_BODY_OPTIONS,
)
PolygonJob.__doc__ = (
    "A GeoJSON shape with options in the body (each also allowed in the query, not both)."
)


def _request_tag(value: Any) -> str:
    kind = value.get("type") if isinstance(value, dict) else getattr(value, "type", None)
    return kind if isinstance(kind, str) else "job"


PolygonRequest = Annotated[
    Annotated[PolygonGeometry, Tag("Polygon")]
    | Annotated[MultiPolygonGeometry, Tag("MultiPolygon")]
    | Annotated[Feature, Tag("Feature")]
    | Annotated[FeatureCollection, Tag("FeatureCollection")]
    | Annotated[PolygonJob, Tag("job")],
    Discriminator(_request_tag),
]
polygon_request_adapter: TypeAdapter[Any] = TypeAdapter(PolygonRequest)


# ----------------------------------------------------------- output: document, GeoJSON
def _wire(hint: Any) -> Any:
    """A library type hint as a pydantic one: each ``TypedDict`` its model, ``Doc`` and
    ``Len`` metadata as ``Field`` constraints; everything else as it is."""
    if is_typeddict(hint):
        return _model(hint)
    origin, args = get_origin(hint), get_args(hint)
    if origin is Annotated:
        return Annotated[_wire(args[0]), _field_info(args[1:])]
    if origin is list:
        return list[_wire(args[0])]  # type: ignore[misc]
    if origin in (UnionType, Union):
        return functools.reduce(operator.or_, (_wire(a) for a in args))
    return hint


def _field_info(meta: tuple[Any, ...], **kw: Any) -> Any:
    for m in meta:
        if isinstance(m, Doc):
            kw["description"] = m.text
        elif isinstance(m, Len):
            kw.update(
                {k: v for k, v in (("min_length", m.min), ("max_length", m.max)) if v is not None}
            )
    return Field(**kw)


_MODELS: dict[type, type[BaseModel]] = {}


def _model(td: type) -> type[BaseModel]:
    """The strict response model of a library ``TypedDict`` (memoised: one model a type).

    A key the library may leave out (``NotRequired``) is optional and nullable here."""
    if td in _MODELS:
        return _MODELS[td]
    fields: dict[str, Any] = {}
    for key, hint in get_type_hints(td, include_extras=True).items():
        # (NotRequired read from the hint: with postponed annotations, the TypedDict's
        # own __required_keys__ holds every key)
        required = get_origin(hint) is not NotRequired
        if not required:
            (hint,) = get_args(hint)
        meta: tuple[Any, ...] = ()
        if get_origin(hint) is Annotated:
            hint, *rest = get_args(hint)
            meta = tuple(rest)
        kind = _wire(hint)
        if required:
            fields[key] = (kind, _field_info(meta))
        else:
            fields[key] = (kind | None, _field_info(meta, default=None))
    model = create_model(
        td.__name__.removesuffix("Doc"), __config__=STRICT, __doc__=td.__doc__, **fields
    )
    _MODELS[td] = model
    return model


#: The output document (:class:`skelprune.output.schema.PruneDocument`).
PruneDocument = _model(schema.PruneDocument)
#: The skeleton's GeoJSON (:class:`skelprune.output.schema.SkeletonGeoJSON`).
SkeletonGeoJSON = _model(schema.SkeletonGeoJSON)


# ------------------------------------------------------------------- output: misc
class ValidationItem(BaseModel):
    model_config = STRICT
    loc: list[str]
    msg: str
    type: str


class Problem(BaseModel):
    """RFC 9457 problem details."""

    model_config = STRICT
    type: str = Field(
        description="Problem type URI: `urn:skelprune:problem:<slug>` or "
        "`about:blank` for plain HTTP errors."
    )
    title: str
    status: int
    detail: str
    instance: str | None = None
    request_id: str | None = Field(
        None, description="The request's ID, also in the `X-Request-ID` response header."
    )
    errors: list[ValidationItem] | None = Field(
        None, description="Validation errors (422): the first 20."
    )
    error_count: int | None = Field(
        None, description="How many validation errors the request has (422)."
    )


class Health(BaseModel):
    model_config = STRICT
    status: Literal["ok"]
    version: str = Field(description="The service version.")
    algorithm: str = Field(description="The results' version (see GET /v1/version).")


class Version(BaseModel):
    model_config = STRICT
    service: str = Field(description="The service version (the skelprune package's).")
    library: str = Field(description="The skelprune library version.")
    algorithm: str = Field(
        description="The results' version: it changes whenever the same "
        "input and options may give a different skeleton or numbers, "
        "and only then."
    )


class Readiness(BaseModel):
    model_config = STRICT
    status: Literal["ready"]
    workers: int = Field(description="Worker processes alive.")
    busy: int = Field(description="Workers running a job.")
    queued: int = Field(description="Jobs waiting for a worker.")
    queue_size: int = Field(description="Most jobs that may wait.")


# --- POST /v1/match ------------------------------------------------------------------


class MatchPolygons(BaseModel):
    """Two GeoJSON shapes to match (options go in the query)."""

    model_config = ConfigDict(strict=True, extra="forbid")
    a: GeoJSONInput
    b: GeoJSONInput


class MatchedEndpoint(BaseModel):
    model_config = ConfigDict(extra="forbid")
    component: int = Field(
        description="Component of the shape whose skeleton is matched (the largest)."
    )
    node: int = Field(
        description="Node id in that component's skeleton, as `POST /v1/prune` numbers them."
    )
    x: float
    y: float


class MatchedPair(BaseModel):
    model_config = ConfigDict(extra="forbid")
    a: MatchedEndpoint
    b: MatchedEndpoint


class MatchDocument(BaseModel):
    """Path similarity of two skeletons (see docs/matching.md)."""

    model_config = ConfigDict(extra="forbid")
    distance: float = Field(ge=0, description="0 for the same skeleton; symmetric.")
    mirrored: bool = Field(
        description="The correspondence runs along b's boundary in the "
        "opposite sense (as for a mirror image)."
    )
    endpoints: list[int] = Field(
        min_length=2, max_length=2, description="Endpoint counts of a and b."
    )
    correspondence: list[MatchedPair]
