"""Every user option, defined once: for the library, the command line and the service.

Each option is a field of one of five frozen dataclasses, with its default, its help
text and, for a choice, its spellings (``field(metadata=...)``). Constructing one checks
it: that check is the only one, whoever asks (the CLI and the service build these
objects from what they were sent, as titiler builds its dependencies once).

- :class:`ReadOptions`: which pixels of an image are the shape (image input only);
- :class:`RasterOptions`: how a polygon becomes pixels (polygon input only);
- :class:`VolumeOptions`: the voxel spacing of a volume (volume input only);
- :class:`PruneOptions`: how :func:`skelprune.prune` prunes;
- :class:`OutputOptions`: what the document holds.

The input's classes (read, raster, volume) and their limits are defined in
:mod:`skelprune.options_input`, the checks in :mod:`skelprune.options_checks`; every
option is imported from here.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, fields, replace
from typing import Any

from .errors import InvalidOptionError
from .options_checks import _check_fields, _choice, _flag, _integer, _number, _option
from .options_input import (
    ARRAY_FOREGROUND,
    DEFAULT_LONGEST_SIDE,
    DEFAULT_PIXEL_BUDGET,
    DEFAULT_PIXELS_PER_WIDTH,
    FOREGROUND_RULES,
    LONGEST_SIDE_RANGE,
    MAX_CLEAN_AREA,
    RasterOptions,
    ReadOptions,
    VolumeOptions,
)

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
    "LINES",
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
    "volume_value",
]

METHODS = ("bayesian", "dce")
#: The largest β accepted: far past any useful weight, and far from a float overflow.
MAX_BETA = 1_000_000_000
#: Spellings of ``coarse``: the name ``"none"`` is the full medial axis (``None``).
COARSE = ("dce", "none")
#: The margin below which the answer's end branches go unless told otherwise, measured on
#: the choice's own λ: with the noise-floor choice it takes the short ends that boundary
#: noise leaves on networks and keeps their vessels (docs/default.md).
DEFAULT_MIN_MARGIN = 0.01
#: The DCE stop of ``method="dce"`` on relevance (scale-free: lengths over the perimeter,
#: angle in radians): docs/dce.md gives the evidence.
DEFAULT_DCE_THRESHOLD = 0.01
#: The tables of :meth:`PruneResult.summary` (docs/tables.md).
TABLES = ("branch", "component")
#: The GeoJSON answer's lines: the skeleton's branches, or the map lines of
#: :func:`skelprune.geo.centerlines` (every line, or one per network: its longest path).
LINES = ("branches", "map", "main-path")
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


@dataclass(frozen=True)
class PruneOptions:
    """How :func:`skelprune.prune` prunes.

    Examples
    --------
    >>> PruneOptions(coarse="dce")  # doctest: +NORMALIZE_WHITESPACE
    PruneOptions(beta=9.0, method='bayesian', coarse='dce', dce_threshold=None,
                 min_margin=None, choice='noise-floor', trim=True, scope='global',
                 window=None)
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
        "none",
        "none: start from the full medial axis (the default); dce: a coarse DCE stage "
        "before the Bayesian pruning (faster on large shapes, but it may remove ends the "
        "pruning would keep, such as vessels of a large tree). Ignored by method=dce.",
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
        f"{DEFAULT_MIN_MARGIN:g}, measured on the choice's λ; 0: the choice's least λ; "
        "docs/algorithm.md).",
        _number(0, strict=False),
    )
    choice: str = _option(
        "noise-floor",
        "For method=bayesian: noise-floor (the default: least λ with the reconstruction "
        "error counted only beyond the boundary's own noise depth, measured on the shape, "
        "so that spurs of boundary noise go and thin real branches stay) or argmin (the "
        "paper's answer: the skeleton of least λ).",
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


#: Where the output options apply (read by :mod:`skelprune.options_where`): the JSON
#: document of an image or a polygon (a volume's document is its graph) ...
_DOCUMENT: dict[str, tuple[str, ...] | None] = {"image": ("json",), "polygon": ("json",)}
#: ... the overlay image (image/png, or inside the document with overlay=true) ...
_OVERLAY = ("png", "overlay")
#: ... and the GeoJSON answer, which a volume has not.
_PLANAR_GEOJSON: dict[str, tuple[str, ...] | None] = {
    "image": ("geojson",),
    "polygon": ("geojson",),
}


@dataclass(frozen=True)
class OutputOptions:
    """What the output document holds."""

    curve: bool = _option(
        True,
        "Include the pruning curve (α·AR, LR and λ at every step).",
        _flag,
        where=_DOCUMENT,
    )
    overlay: bool = _option(
        False, "Add the overlay image as a base64 PNG (overlay_png).", _flag, where=_DOCUMENT
    )
    sequence: bool = _option(
        False,
        "Add the pruning sequence (sequence): every branch and junction of the "
        "starting skeleton with its points and the step that removes it, from which a "
        "viewer draws the skeleton of any step.",
        _flag,
        where=_DOCUMENT,
    )
    overlay_scale: int | None = _option(
        None,
        "Overlay image: each input pixel as N × N pixels, a whole number from 1 to "
        "16 (default: the smallest that makes the longer side at least 512 px).",
        _integer(1, 16),
        where={"image": _OVERLAY, "polygon": _OVERLAY, "volume": ("png",)},
    )
    overlay_legend: bool = _option(
        False,
        "Overlay image: add a strip with the colour key, RER and SS.",
        _flag,
        where={"image": _OVERLAY, "polygon": _OVERLAY},
    )
    simplify: float = _option(
        0.5,
        "GeoJSON answer: simplify each line within this many pixels, >= 0, keeping its "
        "nodes, keeping it inside the shape and off the other lines (0: every pixel).",
        _number(0, strict=False),
        where=_PLANAR_GEOJSON,
    )
    cut_ends: bool = _option(
        False,
        "GeoJSON answer: end a reach cut straight across at the middle of the cut, not "
        "in a fork to its two corners (the JSON document keeps the fork).",
        _flag,
        where=_PLANAR_GEOJSON,
    )
    lines: str = _option(
        "branches",
        "GeoJSON answer of a polygon: the skeleton's branches and nodes (branches), the "
        "map lines of skelprune.geo.centerlines, as `skelprune centerlines` writes them "
        "(map), or one line per network, its longest path (main-path; docs/gis.md).",
        _choice(LINES),
        LINES,
        where=_PLANAR_GEOJSON,  # and the map lines for a polygon only (their value's rule)
    )
    table: str = _option(
        "branch",
        "CSV answer: the table, one row per branch (branch) or per component (component).",
        _choice(TABLES),
        TABLES,
        where={"image": ("csv",), "polygon": ("csv",)},
    )

    def __post_init__(self) -> None:
        _check_fields(self)


#: Every options class: how to prune, what the answers hold, and the input's (an
#: image's pixels, a polygon's raster, a volume's voxels).
GROUPS: tuple[type, ...] = (PruneOptions, OutputOptions, ReadOptions, RasterOptions, VolumeOptions)


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


def volume_value(volume: VolumeOptions | None, keywords: dict[str, Any]) -> VolumeOptions | None:
    """A call's volume options: ``volume``, or one built from its fields among
    ``keywords`` (taken out of them), never both; None when the call gives neither.

    >>> kw = {"spacing": (3, 1, 1), "beta": 2.0}
    >>> volume_value(None, kw).spacing, kw, volume_value(None, {})
    ((3.0, 1.0, 1.0), {'beta': 2.0}, None)
    """
    given = {f.name: keywords.pop(f.name) for f in fields(VolumeOptions) if f.name in keywords}
    if volume is None and not given:
        return None
    return options_value(VolumeOptions, volume, given)


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
     'cut_ends', 'lines', 'table']
    """
    return [
        (f.name, f.default, f.metadata["help"], f.metadata["choices"])
        for group in groups
        for f in fields(group)
    ]
