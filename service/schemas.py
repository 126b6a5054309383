"""Pydantic v2 models of everything the service reads and writes.

Request bodies are validated strictly (no coercion; unknown fields refused). The
response models describe the output documents exactly (``extra="forbid"``), so the
OpenAPI schema is a contract that tests and schemathesis check the answers against.
"""

from __future__ import annotations

import json
from dataclasses import fields as dataclass_fields
from typing import Annotated, Any, Literal, get_args, get_type_hints

from pydantic import (
    BaseModel,
    ConfigDict,
    Discriminator,
    Field,
    Tag,
    TypeAdapter,
    create_model,
)

from skelprune.options import GROUPS, RasterOptions, ReadOptions

__all__ = [
    "POLYGON_ONLY",
    "FiniteFloat",
    "GeoJSONInput",
    "Health",
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
#: Options that only apply to polygon (JSON) input.
POLYGON_ONLY = tuple(f.name for f in dataclass_fields(RasterOptions))


def _option_models() -> tuple[type[BaseModel], dict[str, Any]]:
    """The query model and the body's option fields, from the library's option classes.

    Only the wire types are declared here (a number, a flag, one of the choices); the
    values are checked once, by the library's option classes, when the request builder
    makes them (:mod:`service.builder`), which locates each error where it was given.
    The checks' bounds are shown in the schema.
    """
    fields: dict[str, Any] = {}
    for group in GROUPS:
        hints = get_type_hints(group)
        for f in dataclass_fields(group):
            choices = f.metadata["choices"]
            kind = hints[f.name]
            wire: Any = (
                Literal[choices]
                if choices
                else (
                    bool if kind is bool else int if int in (kind, *get_args(kind)) else FiniteFloat
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
Position = Annotated[list[FiniteFloat], Field(min_length=2, max_length=3)]
LinearRing = Annotated[list[Position], Field(min_length=4)]
BBox = Annotated[list[FiniteFloat], Field(min_length=4, max_length=6)]


class PolygonGeometry(BaseModel):
    """GeoJSON Polygon: exterior ring first, then holes; rings closed."""

    model_config = STRICT
    type: Literal["Polygon"]
    coordinates: Annotated[list[LinearRing], Field(min_length=1)]
    bbox: BBox | None = None


class MultiPolygonGeometry(BaseModel):
    """GeoJSON MultiPolygon."""

    model_config = STRICT
    type: Literal["MultiPolygon"]
    coordinates: Annotated[
        list[Annotated[list[LinearRing], Field(min_length=1)]], Field(min_length=1)
    ]
    bbox: BBox | None = None


Geometry = Annotated[PolygonGeometry | MultiPolygonGeometry, Field(discriminator="type")]


class Feature(BaseModel):
    """GeoJSON Feature holding a Polygon or MultiPolygon."""

    model_config = STRICT
    type: Literal["Feature"]
    geometry: Geometry
    properties: dict[str, Any] | None = None
    id: str | int | None = None
    bbox: BBox | None = None


class FeatureCollection(BaseModel):
    """GeoJSON FeatureCollection; the union of its polygons is the shape."""

    model_config = STRICT
    type: Literal["FeatureCollection"]
    features: Annotated[list[Feature], Field(min_length=1)]
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


# ----------------------------------------------------------------- output: document
Point3 = Annotated[list[float], Field(min_length=3, max_length=3, description="[x, y, radius]")]


class Node(BaseModel):
    model_config = STRICT
    id: int
    x: float
    y: float
    radius: float
    kind: Literal["endpoint", "junction", "loop"]
    points: list[Point3] = Field(description="Pixels of a junction cluster; empty otherwise.")


class Branch(BaseModel):
    model_config = STRICT
    id: int
    source: int
    target: int
    length: float = Field(
        description="Step length of the path (1 axial, √2 diagonal), "
        "with the step into each junction cluster and a loop's closing step."
    )
    points: list[Point3] = Field(
        description="The path, in order from the source node to the "
        "target node; consecutive points are 8-neighbours."
    )
    off_path: list[Point3] = Field(
        description="Skeleton pixels of the branch beside its path "
        "(kept for reconstruction), sorted by (x, y)."
    )
    margin: float | None = Field(
        description="How clearly the trade-off keeps the branch: "
        "λ(Ŝ − E) − λ(Ŝ) for an end branch E, λ at the step that "
        "removes it minus λ(Ŝ) for an inner one; null if never "
        "removed, for method=dce and degenerate shapes."
    )
    removed_at: int | None = Field(
        description="Step of the pruning sequence that removes the branch (null: never)."
    )


class Skeleton(BaseModel):
    model_config = STRICT
    length: float
    nodes: list[Node]
    branches: list[Branch]
    endpoints: list[int]


class MedialAxisSummary(BaseModel):
    model_config = STRICT
    rer: float
    length: float
    endpoints: int
    branches: int


class CurveStep(BaseModel):
    model_config = STRICT
    step: int
    length: float
    ar: float
    lr: float
    objective: float


Point2 = Annotated[list[float], Field(min_length=2, max_length=2, description="[x, y]")]


class SequenceNode(Node):
    """A node of the sequence's starting skeleton S(0), and what the sequence does to it."""

    removed_at: int | None = Field(
        None,
        description="Junctions only: step whose removal takes the cluster's pixels (null: never).",
    )
    dissolved_at: int | None = Field(
        None,
        description="Junctions only: step at which it "
        "stops being a junction (two branch ends left).",
    )
    dissolved_into: int | None = Field(
        None, description="Junctions only: the sequence branch its pixels then belong to."
    )


class SequenceBranch(BaseModel):
    """A branch of S(0) and what the sequence does to it."""

    model_config = STRICT
    id: int
    source: int
    target: int
    length: float
    points: list[Point3] = Field(description="Its path in S(0), from source to target.")
    off_path: list[Point3]
    removed_at: int | None = Field(
        description="Step whose removal takes its pixels "
        "(its own, or that of the branch it became part of); "
        "null: never."
    )
    absorbed_at: int | None = Field(
        description="Step at which it became part of another "
        "branch (a junction dissolved between them); null: never."
    )
    absorbed_into: int | None = Field(description="The branch it became part of.")


class SequenceFrame(BaseModel):
    """Pixel centre (col, row) -> (x, y) of this document: x = x0 + col·pixel_size,
    y = y0 ∓ row·pixel_size (minus when flip_y)."""

    model_config = STRICT
    x0: float
    y0: float
    pixel_size: float
    flip_y: bool


class Sequence(BaseModel):
    """The pruning sequence S(0) … S(n), one entry per step of ``curve``: S(k) is S(0)
    without the pixels of every branch and junction whose ``removed_at`` ≤ k."""

    model_config = STRICT
    start: Literal["medial_axis", "coarse"] = Field(
        description="What S(0) is: the medial axis, or the coarse skeleton (coarse=dce)."
    )
    nodes: list[SequenceNode]
    branches: list[SequenceBranch]
    uncovered: list[Point2] = Field(
        description="Pixels of the shape S(0) does not reconstruct (the error of step 0)."
    )
    coarse_removed: list[Point3] = Field(
        description="Medial-axis pixels the coarse stage "
        "removed before step 0 (empty if S(0) is the "
        "medial axis)."
    )
    frame: SequenceFrame


class Component(BaseModel):
    model_config = STRICT
    area: int = Field(description="Λ(D) in pixels of the raster.")
    alpha: float | None
    rer: float
    ss: float
    objective: float
    medial_axis: MedialAxisSummary
    skeleton: Skeleton
    curve: list[CurveStep] | None = Field(None, description="Absent when curve=false.")
    chosen_step: int
    sequence: Sequence | None = Field(None, description="Only with sequence=true.")


class ForegroundTaken(BaseModel):
    """What was taken as the shape."""

    model_config = STRICT
    rule: Literal["auto", "nonzero", "zero"] | None = Field(
        description="The rule asked for; null for polygon input."
    )
    shape: Literal["nonzero", "zero", "light", "dark", "opaque", "polygon"] = Field(
        description="Pixels taken: non-zero / zero ones, grey values above (`light`) or at "
        "or below (`dark`) `threshold`, alpha above `threshold` (`opaque`), or the polygon."
    )
    threshold: float | None = Field(description="The mid-range split, for light/dark/opaque.")
    border: float | None = Field(
        description="Share of the image border on the background side (auto, grey values)."
    )


class Versions(BaseModel):
    """What made an answer."""

    model_config = STRICT
    library: str = Field(description="The skelprune package version.")
    algorithm: str = Field(
        description="The results' version: it changes whenever the same "
        "input and options may give a different skeleton or numbers."
    )


#: The pruning options the document records as applied: the method's default filled in,
#: null where the method does not use the option.
_APPLIED = {
    "min_margin": "As applied: the margin below which the answer's end branches went "
    "(method=bayesian; null for method=dce).",
    "dce_threshold": "As applied: the DCE stop threshold (method=dce; null for method=bayesian).",
}


class RasterInfo(BaseModel):
    """How a polygon was rasterised (polygon input only)."""

    model_config = STRICT
    pixel_size: float = Field(description="Side of a pixel, in the polygon's units.")
    width: int
    height: int
    fitted: bool = Field(
        description="True when the pixel size was fitted to the polygon (neither "
        "pixel_size nor longest_side given)."
    )
    parts: int = Field(description="Parts of the (repaired) polygon.")
    longest_side: int | None = Field(description="The option as given (null: not given).")
    pixels_per_width: float = Field(description="The option (used when fitted).")
    pixel_budget: int = Field(description="The option (used when fitted).")
    repair: bool = Field(description="Whether invalid geometry was to be repaired.")


class RasterWarningItem(BaseModel):
    """A part of the polygon that the raster does not hold as it is."""

    model_config = STRICT
    kind: Literal["vanished", "split", "merged", "holes"]
    message: str
    part: int | None = Field(description="The polygon part meant, if one is.")
    pixel_size: float | None = Field(
        description="A pixel size that holds it (null: none found within the limits)."
    )


class PruneDocument(BaseModel):
    """The output document."""

    model_config = STRICT
    version: Versions
    width: int
    height: int
    method: Literal["bayesian", "dce"]
    beta: float
    coarse: Literal["dce"] | None
    choice: Literal["argmin", "noise-floor"] = Field(
        description="How the answer was chosen from the pruning sequence."
    )
    trim: bool = Field(description="Whether the answer's end branches were cut back at their tips.")
    min_margin: float | None = Field(description=_APPLIED["min_margin"])
    dce_threshold: float | None = Field(description=_APPLIED["dce_threshold"])
    foreground: ForegroundTaken
    components: list[Component]
    raster: RasterInfo | None = Field(None, description="Polygon input only.")
    warnings: list[RasterWarningItem] | None = Field(
        None,
        description="Polygon input only: parts the raster does not hold as they are "
        "(vanished, split, merged with another, holes lost or added); empty when it holds "
        "them all.",
    )
    overlay_png: str | None = Field(None, description="Base64 PNG; only with overlay=true.")


# ------------------------------------------------------------------ output: GeoJSON
class LineString(BaseModel):
    model_config = STRICT
    type: Literal["LineString"]
    coordinates: Annotated[
        list[Annotated[list[float], Field(min_length=2, max_length=2)]], Field(min_length=2)
    ]


class PointGeometry(BaseModel):
    model_config = STRICT
    type: Literal["Point"]
    coordinates: Annotated[list[float], Field(min_length=2, max_length=2)]


class BranchProperties(BaseModel):
    model_config = STRICT
    component: int
    kind: Literal["branch"]
    id: int
    source: int
    target: int
    length: float
    radii: list[float]
    margin: float | None
    removed_at: int | None
    rer: float = Field(description="RER of the feature's component.")
    ss: float = Field(description="SS of the feature's component.")


class NodeProperties(BaseModel):
    model_config = STRICT
    component: int
    kind: Literal["endpoint", "junction", "loop"]
    id: int
    radius: float
    rer: float = Field(description="RER of the feature's component.")
    ss: float = Field(description="SS of the feature's component.")


class BranchFeature(BaseModel):
    model_config = STRICT
    type: Literal["Feature"]
    geometry: LineString
    properties: BranchProperties


class NodeFeature(BaseModel):
    model_config = STRICT
    type: Literal["Feature"]
    geometry: PointGeometry
    properties: NodeProperties


class ComponentSummary(BaseModel):
    model_config = STRICT
    component: int
    area: int
    alpha: float | None
    rer: float
    ss: float
    objective: float


class CollectionProperties(BaseModel):
    """The document's options and numbers (a foreign member of the collection)."""

    model_config = STRICT
    width: int
    height: int
    method: Literal["bayesian", "dce"]
    beta: float
    coarse: Literal["dce"] | None
    choice: Literal["argmin", "noise-floor"]
    trim: bool
    min_margin: float | None = Field(description=_APPLIED["min_margin"])
    dce_threshold: float | None = Field(description=_APPLIED["dce_threshold"])
    simplify: float = Field(description="How far each line was simplified, in pixels.")
    cut_ends: bool = Field(description="Whether cut reaches end straight across.")
    components: list[ComponentSummary]
    warnings: list[RasterWarningItem] | None = Field(
        None, description="Polygon input only, as in the JSON document."
    )


class SkeletonGeoJSON(BaseModel):
    """The skeleton as GeoJSON: branches as LineStrings, nodes as Points."""

    model_config = STRICT
    type: Literal["FeatureCollection"]
    properties: CollectionProperties
    features: list[BranchFeature | NodeFeature]


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
    errors: list[ValidationItem] | None = Field(None, description="Validation errors (422).")


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
