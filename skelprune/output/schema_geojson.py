"""The skeleton's GeoJSON as types (:class:`SkeletonGeoJSON` and its parts): branches as
LineStrings, nodes as Points, the document's options and numbers as the collection's
properties. Importable from :mod:`skelprune.output.schema`.
"""

# No `from __future__ import annotations`: the annotations are evaluated, as in
# schema_document.
from typing import Annotated, Literal, NotRequired, TypedDict

from .schema_document import (
    DCE_THRESHOLD_APPLIED,
    MIN_MARGIN_APPLIED,
    SCOPE_APPLIED,
    WINDOW_APPLIED,
    Choice,
    Coarse,
    Doc,
    Len,
    Method,
    NodeKind,
    RasterWarningItemDoc,
    Scope,
)


class LineStringDoc(TypedDict):
    type: Literal["LineString"]
    coordinates: Annotated[list[Annotated[list[float], Len(2, 2)]], Len(2)]


class PointGeometryDoc(TypedDict):
    type: Literal["Point"]
    coordinates: Annotated[list[float], Len(2, 2)]


class BranchPropertiesDoc(TypedDict):
    component: int
    kind: Literal["branch"]
    id: int
    source: int
    target: int
    length: float
    radii: list[float]
    margin: float | None
    removed_at: int | None
    rer: Annotated[float, Doc("RER of the feature's component.")]
    ss: Annotated[float, Doc("SS of the feature's component.")]
    # the branch table's numbers (docs/tables.md), in the result's unit
    label: NotRequired[Annotated[int, Doc("The component's label (label images only).")]]
    branch_kind: Annotated[
        Literal["end-end", "end-junction", "junction-junction", "loop"],
        Doc("The branch's kind by its nodes (the table's `kind`)."),
    ]
    chord: float
    tortuosity: Annotated[float | None, Doc("Smoothed length / chord; null for a loop.")]
    width_mean: float
    width_median: float
    width_min: float
    width_max: float
    width_std: float
    angle_source: Annotated[float | None, Doc("Degrees, leaving the source node.")]
    angle_target: Annotated[float | None, Doc("Degrees, leaving the target node.")]
    junction_angle_source: float | None
    junction_angle_target: float | None
    strahler: Annotated[
        int | None, Doc("Horton–Strahler order (null: off the widest spanning tree).")
    ]


class NodePropertiesDoc(TypedDict):
    component: int
    kind: NodeKind
    id: int
    radius: float
    rer: Annotated[float, Doc("RER of the feature's component.")]
    ss: Annotated[float, Doc("SS of the feature's component.")]
    label: NotRequired[Annotated[int, Doc("The component's label (label images only).")]]


class BranchFeatureDoc(TypedDict):
    type: Literal["Feature"]
    geometry: LineStringDoc
    properties: BranchPropertiesDoc


class NodeFeatureDoc(TypedDict):
    type: Literal["Feature"]
    geometry: PointGeometryDoc
    properties: NodePropertiesDoc


class ComponentSummaryDoc(TypedDict):
    component: int
    area: int
    alpha: float | None
    rer: float
    ss: float
    objective: float


class CollectionPropertiesDoc(TypedDict):
    """The document's options and numbers (a foreign member of the collection)."""

    width: int
    height: int
    method: Method
    beta: float
    coarse: Coarse
    choice: Choice
    trim: bool
    min_margin: Annotated[float | None, Doc(MIN_MARGIN_APPLIED)]
    dce_threshold: Annotated[float | None, Doc(DCE_THRESHOLD_APPLIED)]
    scope: NotRequired[Annotated[Scope, Doc(SCOPE_APPLIED)]]
    window: NotRequired[Annotated[int, Doc(WINDOW_APPLIED)]]
    simplify: Annotated[float, Doc("How far each line was simplified, in pixels.")]
    cut_ends: Annotated[bool, Doc("Whether cut reaches end straight across.")]
    components: list[ComponentSummaryDoc]
    warnings: NotRequired[
        Annotated[list[RasterWarningItemDoc], Doc("Polygon input only, as in the JSON document.")]
    ]
    crs: NotRequired[
        Annotated[str, Doc("The coordinates' CRS, where the input named one (else absent).")]
    ]


class CrsNamePropertiesDoc(TypedDict):
    name: str


class CrsDoc(TypedDict):
    """The 2008 GeoJSON ``crs`` member, which GDAL and geopandas read."""

    type: Literal["name"]
    properties: CrsNamePropertiesDoc


class SkeletonGeoJSON(TypedDict):
    """The skeleton as GeoJSON: branches as LineStrings, nodes as Points."""

    type: Literal["FeatureCollection"]
    properties: CollectionPropertiesDoc
    features: list[BranchFeatureDoc | NodeFeatureDoc]
    crs: NotRequired[
        Annotated[CrsDoc, Doc("The coordinates' CRS, where the input named one (else absent).")]
    ]
