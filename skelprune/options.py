"""Every user option, defined once: for the library, the command line and the service.

Each option is a field of one of three frozen dataclasses, with its default, its help
text and, for a choice, its spellings (``field(metadata=...)``). Constructing one checks
it: that check is the only one, whoever asks (the CLI and the service build these
objects from what they were sent, as titiler builds its dependencies once).

- :class:`ReadOptions`: which pixels of an image are the shape (image input only);
- :class:`RasterOptions`: how a polygon becomes pixels (polygon input only);
- :class:`PruneOptions`: how :func:`skelprune.prune` prunes;
- :class:`OutputOptions`: what the document holds.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, fields, replace
from typing import Any

from .errors import InvalidOptionError, shown

__all__ = [
    "ARRAY_FOREGROUND",
    "CHOICES",
    "COARSE",
    "DEFAULT_DCE_THRESHOLD",
    "DEFAULT_LONGEST_SIDE",
    "DEFAULT_MIN_MARGIN",
    "DEFAULT_PIXELS_PER_WIDTH",
    "DEFAULT_PIXEL_BUDGET",
    "FOREGROUND_RULES",
    "GROUPS",
    "LOCAL_HALO_FRACTION",
    "LOCAL_WINDOW_RANGE",
    "LOCAL_WINDOW_WIDTHS",
    "LONGEST_SIDE_RANGE",
    "MAX_BETA",
    "MAX_CLEAN_AREA",
    "METHODS",
    "SCOPES",
    "TABLES",
    "OutputOptions",
    "PruneOptions",
    "RasterOptions",
    "ReadOptions",
    "VolumeOptions",
    "check_option",
    "option_fields",
    "options_value",
    "resolve_options",
    "split_options",
]

METHODS = ("bayesian", "dce")
#: The largest β accepted: far past any useful weight, and far from a float overflow.
MAX_BETA = 1_000_000_000
#: The foreground rules (:mod:`skelprune.io.foreground`).
FOREGROUND_RULES = ("auto", "nonzero", "zero")
#: Spellings of ``coarse``: the name ``"none"`` is the full medial axis (``None``).
COARSE = ("dce", "none")
#: The margin below which the answer's end branches go unless told otherwise: chosen by
#: the stability benchmark over noise models and sizes (docs/stability-findings.md).
DEFAULT_MIN_MARGIN = 0.01
#: The DCE stop of ``method="dce"`` on relevance (scale-free: lengths over the perimeter,
#: angle in radians): docs/dce.md gives the evidence.
DEFAULT_DCE_THRESHOLD = 0.01
#: The foreground rule of an array given without one: an array is a mask, its non-zero
#: pixels the shape (an image file's default is ``auto``, :class:`ReadOptions`).
ARRAY_FOREGROUND = "nonzero"
#: The tables of :meth:`PruneResult.summary` (docs/tables.md).
TABLES = ("branch", "component")
#: How the answer is chosen from the sequence (:mod:`skelprune.pruning.choice`).
CHOICES = ("argmin", "noise-floor")
#: Where the trade-off is taken (:mod:`skelprune.local`): over each whole component (the
#: paper's) or over windows of the image, each branch judged in its neighbourhood.
SCOPES = ("global", "local")
#: ``scope="local"``: the window, when none is given, is this many mean widths of the
#: shape (2·area / boundary pixels), rounded up to a multiple of 64 ...
LOCAL_WINDOW_WIDTHS = 64
#: ... within this range (px), which is also the range ``window`` may be set to.
LOCAL_WINDOW_RANGE = (128, 8192)
#: The halo grown around each window's core, as a fraction of the window.
LOCAL_HALO_FRACTION = 0.25
#: The largest area (pixels) ``fill_holes`` and ``min_area`` take: a 2¹⁶ × 2¹⁶ image.
MAX_CLEAN_AREA = 1 << 32
#: Pixels across the longer side of a polygon's bounding box at the least (a polygon's
#: narrow parts may ask for more) ...
DEFAULT_LONGEST_SIDE = 512
#: ... and the range it may be set to: fewer pixels cannot hold a skeleton worth the
#: name; for more, give a pixel_size.
LONGEST_SIDE_RANGE = (8, 16384)
#: Pixels across a polygon's narrowest part when the pixel size comes from the polygon
#: (where the answer stops changing on generated rivers: docs/gis.md) ...
DEFAULT_PIXELS_PER_WIDTH = 3.0
#: ... within this many raster pixels (a 2048 × 2048 image).
DEFAULT_PIXEL_BUDGET = 2048 * 2048


def _option(
    default: Any,
    help: str,
    check: Callable[[str, Any], Any],
    choices: tuple[str, ...] | None = None,
) -> Any:
    return field(default=default, metadata={"help": help, "choices": choices, "check": check})


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
    from .io.crs import PLANAR, is_geographic

    if value == PLANAR:
        return value
    is_geographic(value)  # an authority code pyproj knows, or the error says which not
    return value


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


@dataclass(frozen=True)
class ReadOptions:
    """Which pixels of an image are the shape (image input only)."""

    foreground: str = _option(
        "auto",
        "Which pixels are the shape: auto (the grey side not holding most of the "
        "image border, split at mid-grey; the opaque part of a transparent image), nonzero "
        "or zero.",
        _choice(FOREGROUND_RULES),
        FOREGROUND_RULES,
    )
    # label images and cleaning (docs/graph.md#label-images, #cleaning)
    labels: bool = _option(
        False,
        "Label image: every distinct non-zero value of an integer image is its own shape, "
        "pruned on its own even where two labels touch; each component carries its label.",
        _flag,
    )
    fill_holes: int = _option(
        0,
        "Fill the shape's holes of fewer pixels than this, a whole number from 0 to "
        f"{MAX_CLEAN_AREA} (default 0: every hole kept).",
        _integer(0, MAX_CLEAN_AREA),
    )
    min_area: int = _option(
        0,
        "Drop the components of fewer pixels than this, a whole number from 0 to "
        f"{MAX_CLEAN_AREA} (default 0: every component kept).",
        _integer(0, MAX_CLEAN_AREA),
    )

    def __post_init__(self) -> None:
        _check_fields(self)


@dataclass(frozen=True)
class PruneOptions:
    """How :func:`skelprune.prune` prunes.

    Examples
    --------
    >>> PruneOptions(coarse="none")  # doctest: +NORMALIZE_WHITESPACE
    PruneOptions(beta=9.0, method='bayesian', coarse=None, dce_threshold=None,
                 min_margin=None, choice='argmin', trim=True, scope='global', window=None)
    >>> PruneOptions(beta=-1)
    Traceback (most recent call last):
    ...
    skelprune.errors.InvalidOptionError: beta must be a finite number > 0 and <= 1e+09, got -1
    """

    beta: float = _option(
        9.0,
        "Weight β of the reconstruction term, > 0 (at most 1e9): α = β·log(L(M)/ℓ̄). The paper's 9.",
        _number(0, strict=True, high=MAX_BETA),
    )
    method: str = _option(
        "bayesian",
        "bayesian: the paper's pruning; dce: contour-partition pruning (its ref. [10]).",
        _choice(METHODS),
        METHODS,
    )
    coarse: str | None = _option(
        "dce",
        "dce: a coarse DCE stage before the Bayesian pruning (the default); none: "
        "start from the full medial axis. Ignored by method=dce.",
        _choice(COARSE),
        COARSE,
    )
    dce_threshold: float | None = _option(
        None,
        "For method=dce: the DCE stop threshold on relevance, >= 0 (scale-free; default "
        f"{DEFAULT_DCE_THRESHOLD:g}).",
        _number(0, strict=False),
    )
    min_margin: float | None = _option(
        None,
        "For method=bayesian: also drop the answer's end branches whose margin is "
        f"below this, >= 0, cheapest first, as the sequence goes on (default "
        f"{DEFAULT_MIN_MARGIN:g}, chosen for endpoint stability under noise, turns and "
        "scaling at every size; 0: the argmin of λ over the sequence, which never removes "
        "a limb: docs/algorithm.md).",
        _number(0, strict=False),
    )
    choice: str = _option(
        "argmin",
        "For method=bayesian: argmin (the paper's answer: the skeleton of least λ) or "
        "noise-floor (least λ with the reconstruction error counted only deeper than the "
        "boundary's one-pixel rim, which a one-pixel boundary move changes).",
        _choice(CHOICES),
        CHOICES,
    )
    trim: bool = _option(
        True,
        "For method=bayesian: cut each end branch of the answer back from its tip to the "
        "point where the trade-off is best (true, the default), or keep the answer's "
        "branches whole (false).",
        _flag,
    )
    scope: str = _option(
        "global",
        "global: the paper's trade-off over each whole component (the default); local: "
        "over windows of the image, each branch judged in its neighbourhood and the "
        "windows' answers stitched, so that what is kept does not depend on how far the "
        "image extends (for large networks: roads, vessels, cracks; docs/algorithm.md).",
        _choice(SCOPES),
        SCOPES,
    )
    window: int | None = _option(
        None,
        "For scope=local: the window's side in pixels, a whole number from "
        f"{LOCAL_WINDOW_RANGE[0]} to {LOCAL_WINDOW_RANGE[1]} (default: "
        f"{LOCAL_WINDOW_WIDTHS} mean widths of the shape, within that range); each "
        f"window is pruned with a halo of a quarter of it around.",
        _integer(*LOCAL_WINDOW_RANGE),
    )

    def __post_init__(self) -> None:
        if self.coarse is None:  # the library's spelling of "none"
            object.__setattr__(self, "coarse", "none")
        _check_fields(self)
        if self.coarse == "none":
            object.__setattr__(self, "coarse", None)
        if self.min_margin is not None and self.method != "bayesian":
            raise InvalidOptionError(
                "min_margin applies to method='bayesian' only: the "
                "margin measures the Bayesian trade-off"
            )
        if self.window is not None and self.scope != "local":
            raise InvalidOptionError("window applies to scope='local' only")

    def resolved(self) -> PruneOptions:
        """The options as the pruning applies them, as the document records them: the
        method's defaults filled in (``min_margin`` of the Bayesian pruning,
        ``dce_threshold`` of the DCE one) and what the method does not use cleared (DCE
        pruning has no coarse stage, no choice of step, no tips cut).

        Examples
        --------
        >>> PruneOptions().resolved().min_margin
        0.01
        >>> PruneOptions(method="dce").resolved()  # doctest: +NORMALIZE_WHITESPACE
        PruneOptions(beta=9.0, method='dce', coarse=None, dce_threshold=0.01,
                     min_margin=None, choice='argmin', trim=False, scope='global',
                     window=None)
        """
        if self.method == "dce":
            threshold = DEFAULT_DCE_THRESHOLD if self.dce_threshold is None else self.dce_threshold
            return replace(self, coarse=None, choice="argmin", trim=False, dce_threshold=threshold)
        margin = DEFAULT_MIN_MARGIN if self.min_margin is None else self.min_margin
        return replace(self, dce_threshold=None, min_margin=margin)


@dataclass(frozen=True)
class OutputOptions:
    """What the output document holds."""

    curve: bool = _option(True, "Include the pruning curve (α·AR, LR and λ at every step).", _flag)
    overlay: bool = _option(False, "Add the overlay image as a base64 PNG (overlay_png).", _flag)
    sequence: bool = _option(
        False,
        "Add the pruning sequence (sequence): every branch and junction of the "
        "starting skeleton with its points and the step that removes it, from which a "
        "viewer draws the skeleton of any step.",
        _flag,
    )
    overlay_scale: int | None = _option(
        None,
        "Overlay image: each input pixel as N × N pixels, a whole number from 1 to "
        "16 (default: the smallest that makes the longer side at least 512 px).",
        _integer(1, 16),
    )
    overlay_legend: bool = _option(
        False, "Overlay image: add a strip with the colour key, RER and SS.", _flag
    )
    simplify: float = _option(
        0.5,
        "GeoJSON answer: simplify each line within this many pixels, >= 0, keeping its "
        "nodes, keeping it inside the shape and off the other lines (0: every pixel).",
        _number(0, strict=False),
    )
    cut_ends: bool = _option(
        False,
        "GeoJSON answer: end a reach cut straight across at the middle of the cut, not "
        "in a fork to its two corners (the JSON document keeps the fork).",
        _flag,
    )
    table: str = _option(
        "branch",
        "CSV answer: the table, one row per branch (branch) or per component (component).",
        _choice(TABLES),
        TABLES,
    )

    def __post_init__(self) -> None:
        _check_fields(self)


@dataclass(frozen=True)
class RasterOptions:
    """How a GeoJSON polygon becomes a raster (polygon input only).

    Examples
    --------
    >>> RasterOptions(pixel_size=0.5)  # doctest: +NORMALIZE_WHITESPACE
    RasterOptions(pixel_size=0.5, longest_side=None, pixels_per_width=3.0,
                  pixel_budget=4194304, repair=True, crs=None)
    >>> RasterOptions(pixel_size=0.5, longest_side=100)
    Traceback (most recent call last):
    ...
    skelprune.errors.InvalidOptionError: give pixel_size or longest_side, not both
    """

    pixel_size: float | None = _option(
        None,
        "Raster pixel size in the polygon's units, > 0 (default: fitted to the polygon, "
        "see pixels_per_width). For an image: the side of a pixel in your units, which "
        "the tables (summary, CSV) measure in (default: pixels).",
        _number(0, strict=True),
    )
    longest_side: int | None = _option(
        None,
        "Pixels across the longer side of the bounding box, a whole number from "
        f"{LONGEST_SIDE_RANGE[0]} to {LONGEST_SIDE_RANGE[1]} (instead of pixel_size; "
        "default: fitted to the polygon).",
        _integer(*LONGEST_SIDE_RANGE),
    )
    pixels_per_width: float = _option(
        DEFAULT_PIXELS_PER_WIDTH,
        "When neither pixel_size nor longest_side is given: pixels across the polygon's "
        f"narrowest part, >= 1 (default {DEFAULT_PIXELS_PER_WIDTH:g}); the raster is never "
        f"coarser than {DEFAULT_LONGEST_SIDE} px along the longer side and holds at most "
        "pixel_budget pixels.",
        _number(1, strict=False),
    )
    pixel_budget: int = _option(
        DEFAULT_PIXEL_BUDGET,
        "Most pixels of a raster fitted to the polygon, a whole number from 4096 to "
        f"{1 << 28} (default {DEFAULT_PIXEL_BUDGET}).",
        _integer(4096, 1 << 28),
    )
    repair: bool = _option(
        True,
        "Repair self-intersections with shapely's make_valid (true) or refuse them.",
        _flag,
    )
    crs: str | None = _option(
        None,
        "The coordinates' CRS, an authority code pyproj knows or its URN (EPSG:4326, "
        "OGC:CRS84 for RFC 7946 GeoJSON, EPSG:32633, urn:ogc:def:crs:EPSG::32633), or "
        "planar: coordinates used as they are. Default: the GeoJSON's crs member; "
        "without one, longitude/latitude (OGC:CRS84, with a warning) if every coordinate "
        "lies within its bounds and the polygon is 1e-6 to 1 degree across, else planar. "
        "Longitude/latitude is pruned in a local equidistant projection: "
        "pixel_size, lengths and radii in metres, lines back in longitude/latitude. Needs "
        "the geo extra (pyproj).",
        _crs_name,
    )

    def __post_init__(self) -> None:
        _check_fields(self)
        if self.pixel_size is not None and self.longest_side is not None:
            raise InvalidOptionError("give pixel_size or longest_side, not both")


def _spacing(name: str, value: Any) -> tuple[float, float, float]:
    try:
        if isinstance(value, str):  # "dz,dy,dx", as a query or the CLI writes it
            values: tuple[Any, ...] = tuple(float(v) for v in value.split(","))
        else:
            values = tuple(value)
    except (TypeError, ValueError):
        values = ()
    if len(values) != 3 or not all(
        not isinstance(v, bool) and isinstance(v, int | float) and math.isfinite(v) and v > 0
        for v in values
    ):
        raise InvalidOptionError(
            f"{name} must be three finite numbers > 0 (dz, dy, dx), got {shown(value)}"
        )
    return (float(values[0]), float(values[1]), float(values[2]))


_with_schema(
    _spacing,
    type="array",
    items={"type": "number", "exclusiveMinimum": 0},
    minItems=3,
    maxItems=3,
)


@dataclass(frozen=True)
class VolumeOptions:
    """How a 3-D volume's voxels measure (volume input only: a 3-D array, a ``.npy`` or a
    TIFF stack).

    Examples
    --------
    >>> VolumeOptions(spacing=(3, 1, 1)).spacing, VolumeOptions(spacing="2,1,1").spacing
    ((3.0, 1.0, 1.0), (2.0, 1.0, 1.0))
    >>> VolumeOptions(spacing=(1, 0, 1))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    skelprune.errors.InvalidOptionError: spacing must be three finite numbers > 0 ...
    """

    spacing: tuple[float, float, float] = _option(
        (1.0, 1.0, 1.0),
        "Volume input: the physical size of a voxel along z, y and x (the array's first, "
        "second and last axis), three numbers > 0 (default 1, 1, 1). Distances, radii, "
        "lengths and widths are in its units; volumes are counted in voxels.",
        _spacing,
    )

    def __post_init__(self) -> None:
        object.__setattr__(self, "spacing", _spacing("spacing", self.spacing))


GROUPS: tuple[type, ...] = (PruneOptions, OutputOptions, ReadOptions, RasterOptions)


def check_option(name: str, value: Any) -> Any:
    """Check one option on its own (what a form or a query parser can do per field);
    returns the value as given.

    >>> check_option("coarse", "none")
    'none'
    >>> check_option("longest_side", 4)
    Traceback (most recent call last):
    ...
    skelprune.errors.InvalidOptionError: longest_side must be an integer from 8 to 16384, got 4
    """
    for group in GROUPS:
        for f in fields(group):
            if f.name == name:
                f.metadata["check"](name, value)
                return value
    raise InvalidOptionError(f"unknown option {name!r}")


def split_options(given: Mapping[str, Any]) -> dict[type, dict[str, Any]]:
    """Keyword options sorted by the class that defines each (what :func:`skelprune.prune`
    builds its options values from); a name no class defines is a ``TypeError``, as for
    any unknown keyword argument.

    >>> split_options({"beta": 3.0, "foreground": "zero"})[PruneOptions]
    {'beta': 3.0}
    >>> split_options({"betta": 3.0})
    Traceback (most recent call last):
    ...
    TypeError: unknown option 'betta'
    """
    owner = {f.name: group for group in GROUPS for f in fields(group)}
    out: dict[type, dict[str, Any]] = {group: {} for group in GROUPS}
    for name, value in given.items():
        if name not in owner:
            raise TypeError(f"unknown option {name!r}")
        out[owner[name]][name] = value
    return out


def options_value(cls: type, given: Any, keywords: Mapping[str, Any]) -> Any:
    """One options value of class ``cls``: ``given``, or one built from keyword options
    (its fields), never both; whoever takes options this way checks them once, here.

    >>> options_value(RasterOptions, None, {"pixel_size": 2.0}).pixel_size
    2.0
    >>> options_value(PruneOptions, PruneOptions(), {"beta": 3.0})
    Traceback (most recent call last):
    ...
    TypeError: give PruneOptions or its fields as keywords, not both (got beta)
    """
    if given is None:
        return cls(**keywords)
    if keywords:
        raise TypeError(
            f"give {cls.__name__} or its fields as keywords, not both (got {', '.join(keywords)})"
        )
    if not isinstance(given, cls):
        raise TypeError(f"expected {cls.__name__}, got {type(given).__name__}")
    return given


def resolve_options(
    options: PruneOptions | None,
    read: ReadOptions | None,
    raster: RasterOptions | None,
    output: OutputOptions | None,
    keywords: Mapping[str, Any],
) -> tuple[PruneOptions, ReadOptions | None, RasterOptions | None, OutputOptions]:
    """A call's four options values from its objects and its keyword options (what
    :func:`skelprune.prune` and the data-set runs take): read and raster stay None when
    neither is given, so that the input's kind picks their defaults.

    >>> opts, read, raster, out = resolve_options(None, None, None, None, {"beta": 3.0})
    >>> opts.beta, read, raster, out == OutputOptions()
    (3.0, None, None, True)
    """
    groups = split_options(keywords)
    return (
        options_value(PruneOptions, options, groups[PruneOptions]),
        None
        if read is None and not groups[ReadOptions]
        else options_value(ReadOptions, read, groups[ReadOptions]),
        None
        if raster is None and not groups[RasterOptions]
        else options_value(RasterOptions, raster, groups[RasterOptions]),
        options_value(OutputOptions, output, groups[OutputOptions]),
    )


def option_fields(*groups: type) -> list[tuple[str, Any, str, tuple[str, ...] | None]]:
    """``(name, default, help, choices)`` of every option of the given classes, in order:
    what the CLI and the service describe their options from.

    >>> [name for name, *_ in option_fields(OutputOptions)]  # doctest: +NORMALIZE_WHITESPACE
    ['curve', 'overlay', 'sequence', 'overlay_scale', 'overlay_legend', 'simplify',
     'cut_ends', 'table']
    """
    return [
        (f.name, f.default, f.metadata["help"], f.metadata["choices"])
        for group in groups
        for f in fields(group)
    ]
