"""The output document's types (:class:`PruneDocument` and its parts), with the markers
their fields are described with (:class:`Doc`, :class:`Len`) and the literal types the
GeoJSON's types share. Importable from :mod:`skelprune.output.schema`, which says how
they are read.

One schema describes an image's (or a polygon's) document and a volume's: a volume's
nodes have a ``z``, its points are ``[x, y, z, radius]``, and its keys of its own
(``dimensions``, ``depth``, ``spacing``; per component ``volume``, ``lbar``, ``steps``,
``tips_trimmed``) are ``NotRequired``, as are an image's that a volume's document has not
(``version``, ``foreground``, ``dce_threshold``; per component ``area``).
"""

# No `from __future__ import annotations`: the annotations are evaluated, so that
# __required_keys__ knows the NotRequired keys at run time.
from dataclasses import dataclass
from typing import Annotated, Literal, NotRequired, TypedDict


@dataclass(frozen=True)
class Doc:
    """A field's (or a list item's) description."""

    text: str


@dataclass(frozen=True)
class Len:
    """Bounds of a list's length (None: no bound)."""

    min: int | None = None
    max: int | None = None


Point3 = Annotated[list[float], Len(3, 3), Doc("[x, y, radius]")]
Point2 = Annotated[list[float], Len(2, 2), Doc("[x, y]")]
Point = Annotated[list[float], Len(3, 4), Doc("[x, y, radius]; a volume's [x, y, z, radius]")]
NodeKind = Literal["endpoint", "junction", "loop"]
Method = Literal["bayesian", "dce"]
Coarse = Literal["dce"] | None
Choice = Literal["argmin", "noise-floor"]
Scope = Literal["global", "local"]


# ------------------------------------------------------------------------ the document
class NodeDoc(TypedDict):
    id: int
    x: float
    y: float
    z: NotRequired[
        Annotated[float, Doc("A volume's nodes only: the voxel's index along the first axis.")]
    ]
    radius: float
    kind: NodeKind
    points: Annotated[
        list[Point], Doc("Pixels (a volume's voxels) of a junction cluster; empty otherwise.")
    ]


class BranchDoc(TypedDict):
    id: Annotated[
        int, Doc("Counted from 0; in a volume's document, the branch graph's own (with gaps).")
    ]
    source: Annotated[int | None, Doc("Null only for a volume's loop without junction.")]
    target: Annotated[int | None, Doc("Null only for a volume's loop without junction.")]
    length: Annotated[
        float,
        Doc(
            "Step length of the path (1 axial, √2 diagonal; a volume's in the units of "
            "spacing), with the step into each junction cluster and a loop's closing step."
        ),
    ]
    points: Annotated[
        list[Point],
        Doc(
            "The path, in order from the source node to the "
            "target node; consecutive points are 8-neighbours (a volume's 26-neighbours)."
        ),
    ]
    off_path: Annotated[
        list[Point],
        Doc(
            "Skeleton pixels of the branch beside its path "
            "(kept for reconstruction), sorted by (x, y); a volume's voxels in the "
            "graph's order."
        ),
    ]
    margin: Annotated[
        float | None,
        Doc(
            "How clearly the trade-off keeps the branch: "
            "λ(Ŝ − E) − λ(Ŝ) for an end branch E, λ at the step that "
            "removes it minus λ(Ŝ) for an inner one; null if never "
            "removed, for method=dce and degenerate shapes."
        ),
    ]
    removed_at: Annotated[
        int | None,
        Doc("Step of the pruning sequence that removes the branch (null: never)."),
    ]


class SkeletonDoc(TypedDict):
    length: float
    nodes: list[NodeDoc]
    branches: list[BranchDoc]
    endpoints: list[int]


class MedialAxisSummaryDoc(TypedDict):
    rer: float
    length: float
    endpoints: int
    branches: int


class CurveStepDoc(TypedDict):
    step: int
    length: float
    ar: float
    lr: float
    objective: float


class SequenceNodeDoc(NodeDoc):
    """A node of the sequence's starting skeleton S(0), and what the sequence does to it."""

    removed_at: NotRequired[
        Annotated[
            int | None,
            Doc("Junctions only: step whose removal takes the cluster's pixels (null: never)."),
        ]
    ]
    dissolved_at: NotRequired[
        Annotated[
            int | None,
            Doc("Junctions only: step at which it stops being a junction (two branch ends left)."),
        ]
    ]
    dissolved_into: NotRequired[
        Annotated[int | None, Doc("Junctions only: the sequence branch its pixels then belong to.")]
    ]


class SequenceBranchDoc(TypedDict):
    """A branch of S(0) and what the sequence does to it."""

    id: int
    source: int
    target: int
    length: float
    points: Annotated[list[Point3], Doc("Its path in S(0), from source to target.")]
    off_path: list[Point3]
    removed_at: Annotated[
        int | None,
        Doc(
            "Step whose removal takes its pixels "
            "(its own, or that of the branch it became part of); "
            "null: never."
        ),
    ]
    absorbed_at: Annotated[
        int | None,
        Doc(
            "Step at which it became part of another "
            "branch (a junction dissolved between them); null: never."
        ),
    ]
    absorbed_into: Annotated[int | None, Doc("The branch it became part of.")]


class SequenceFrameDoc(TypedDict):
    """Pixel centre (col, row) -> (x, y) of this document: x = x0 + col·pixel_size,
    y = y0 ∓ row·pixel_size (minus when flip_y)."""

    x0: float
    y0: float
    pixel_size: float
    flip_y: bool


class SequenceDoc(TypedDict):
    """The pruning sequence S(0) … S(n), one entry per step of ``curve``: S(k) is S(0)
    without the pixels of every branch and junction whose ``removed_at`` ≤ k."""

    start: Annotated[
        Literal["medial_axis", "coarse"],
        Doc("What S(0) is: the medial axis, or the coarse skeleton (coarse=dce)."),
    ]
    nodes: list[SequenceNodeDoc]
    branches: list[SequenceBranchDoc]
    uncovered: Annotated[
        list[Point2], Doc("Pixels of the shape S(0) does not reconstruct (the error of step 0).")
    ]
    coarse_removed: Annotated[
        list[Point3],
        Doc(
            "Medial-axis pixels the coarse stage "
            "removed before step 0 (empty if S(0) is the "
            "medial axis)."
        ),
    ]
    frame: SequenceFrameDoc


class ComponentDoc(TypedDict):
    label: NotRequired[
        Annotated[
            int | None,
            Doc(
                "The component's label (label images only, labels=true; always in a "
                "volume's document, null for a mask's component)."
            ),
        ]
    ]
    area: NotRequired[Annotated[int, Doc("Λ(D) in pixels of the raster (not for a volume).")]]
    volume: NotRequired[Annotated[int, Doc("A volume's component only: its voxels.")]]
    alpha: float | None
    lbar: NotRequired[
        Annotated[float, Doc("A volume's component only: ℓ̄, the mean end-path length.")]
    ]
    rer: float
    ss: float
    objective: float
    medial_axis: MedialAxisSummaryDoc
    skeleton: SkeletonDoc
    curve: NotRequired[
        Annotated[list[CurveStepDoc], Doc("Absent when curve=false (and for a volume).")]
    ]
    chosen_step: int
    steps: NotRequired[
        Annotated[int, Doc("A volume's component only: the pruning sequence's removals.")]
    ]
    tips_trimmed: NotRequired[
        Annotated[bool, Doc("A volume's component only: whether the answer's tips were cut.")]
    ]
    sequence: NotRequired[Annotated[SequenceDoc, Doc("Only with sequence=true.")]]


class ForegroundTakenDoc(TypedDict):
    """What was taken as the shape."""

    rule: Annotated[
        Literal["auto", "nonzero", "zero"] | None,
        Doc("The rule asked for; null for polygon input."),
    ]
    shape: Annotated[
        Literal["nonzero", "zero", "light", "dark", "opaque", "polygon", "labels"],
        Doc(
            "Pixels taken: non-zero / zero ones, grey values above (`light`) or at "
            "or below (`dark`) `threshold`, alpha above `threshold` (`opaque`), the polygon, "
            "or every non-zero value its own shape (`labels`, with labels=true)."
        ),
    ]
    threshold: Annotated[float | None, Doc("The mid-range split, for light/dark/opaque.")]
    border: Annotated[
        float | None, Doc("Share of the image border on the background side (auto, grey values).")
    ]
    fill_holes: NotRequired[
        Annotated[int, Doc("Holes of fewer pixels than this were filled (only when given).")]
    ]
    min_area: NotRequired[
        Annotated[int, Doc("Components of fewer pixels than this were dropped (only when given).")]
    ]


class VersionsDoc(TypedDict):
    """What made an answer."""

    library: Annotated[str, Doc("The skelprune package version.")]
    algorithm: Annotated[
        str,
        Doc(
            "The results' version: it changes whenever the same "
            "input and options may give a different skeleton or numbers."
        ),
    ]


#: The pruning options the document records as applied: the method's default filled in,
#: null where the method does not use the option.
SCOPE_APPLIED = (
    "Where the trade-off was taken: local (over windows, stitched); absent for the "
    "paper's global scope."
)
WINDOW_APPLIED = "scope=local: the window's side in pixels, as applied (its halo a quarter of it)."
MIN_MARGIN_APPLIED = (
    "As applied: the margin below which the answer's end branches went "
    "(method=bayesian; null for method=dce)."
)
DCE_THRESHOLD_APPLIED = "As applied: the DCE stop threshold (method=dce; null for method=bayesian)."


class RasterInfoDoc(TypedDict):
    """How a polygon was rasterised (polygon input only)."""

    pixel_size: Annotated[float, Doc("Side of a pixel, in the polygon's units.")]
    width: int
    height: int
    fitted: Annotated[
        bool,
        Doc(
            "True when the pixel size was fitted to the polygon (neither "
            "pixel_size nor longest_side given)."
        ),
    ]
    parts: Annotated[int, Doc("Parts of the (repaired) polygon.")]
    longest_side: Annotated[int | None, Doc("The option as given (null: not given).")]
    pixels_per_width: Annotated[float, Doc("The option (used when fitted).")]
    pixel_budget: Annotated[int, Doc("The option (used when fitted).")]
    repair: Annotated[bool, Doc("Whether invalid geometry was to be repaired.")]
    crs: Annotated[str | None, Doc("The coordinates' CRS (null: none given, planar).")]
    projection: NotRequired[
        Annotated[
            str,
            Doc(
                "Geographic coordinates: the local azimuthal equidistant projection (PROJ "
                "string) the polygon was pruned in; the document's coordinates, lengths and "
                "radii are in its metres, the GeoJSON's lines back in the input's CRS."
            ),
        ]
    ]


class RasterWarningItemDoc(TypedDict):
    """A part of the polygon that the raster does not hold as it is."""

    kind: Literal["vanished", "split", "merged", "holes", "skipped", "crs"]
    message: str
    part: Annotated[int | None, Doc("The polygon part meant, if one is.")]
    pixel_size: Annotated[
        float | None, Doc("A pixel size that holds it (null: none found within the limits).")
    ]


class GeoreferenceDoc(TypedDict):
    """Where a GeoTIFF mask's pixels lie on the map."""

    crs: Annotated[str | None, Doc("The raster's CRS (EPSG:…; null: none recorded).")]
    transform: Annotated[
        list[float],
        Doc(
            "The affine map from a pixel's corner (col, row) to map coordinates, in GDAL's "
            "order [a, b, c, d, e, f]: x = a·col + b·row + c, y = d·col + e·row + f. The "
            "document's coordinates stay the raster's pixels; the GeoJSON answer's are "
            "the map's."
        ),
    ]


class PruneDocument(TypedDict):
    """The output document: an image's, a polygon's or a volume's (``dimensions`` 3)."""

    version: NotRequired[Annotated[VersionsDoc, Doc("Not in a volume's document.")]]
    dimensions: NotRequired[Annotated[Literal[3], Doc("A volume's document only.")]]
    width: int
    height: int
    depth: NotRequired[
        Annotated[int, Doc("A volume's document only: its size along the first axis.")]
    ]
    spacing: NotRequired[
        Annotated[
            list[float],
            Len(3, 3),
            Doc("A volume's document only: a voxel's physical size (dz, dy, dx)."),
        ]
    ]
    method: Method
    beta: float
    coarse: Coarse
    choice: Annotated[Choice, Doc("How the answer was chosen from the pruning sequence.")]
    trim: Annotated[bool, Doc("Whether the answer's end branches were cut back at their tips.")]
    min_margin: Annotated[float | None, Doc(MIN_MARGIN_APPLIED)]
    dce_threshold: NotRequired[Annotated[float | None, Doc(DCE_THRESHOLD_APPLIED)]]
    scope: NotRequired[Annotated[Scope, Doc(SCOPE_APPLIED)]]
    window: NotRequired[Annotated[int, Doc(WINDOW_APPLIED)]]
    foreground: NotRequired[Annotated[ForegroundTakenDoc, Doc("Not in a volume's document.")]]
    components: list[ComponentDoc]
    raster: NotRequired[Annotated[RasterInfoDoc, Doc("Polygon input only.")]]
    georeference: NotRequired[Annotated[GeoreferenceDoc, Doc("GeoTIFF input only.")]]
    warnings: NotRequired[
        Annotated[
            list[RasterWarningItemDoc],
            Doc(
                "Polygon input only: parts the raster does not hold as they are "
                "(vanished, split, merged with another, holes lost or added); empty when it "
                "holds them all."
            ),
        ]
    ]
    overlay_png: NotRequired[Annotated[str, Doc("Base64 PNG; only with overlay=true.")]]
    hint: NotRequired[
        Annotated[
            str,
            Doc(
                "What the reader noticed and an option would change: an image read by the "
                "foreground rule that looks like a label image (then labels=true)."
            ),
        ]
    ]
