"""The command line's options, declared once from :mod:`skelprune.options`: their help
texts, the choices as Enums, the ``Annotated`` option types the commands share, a
``--help`` without type labels that say nothing, and the commands' parameters read back
into option values (a usage error, exit status 2, when a class refuses them).
"""

from __future__ import annotations

import enum
from dataclasses import fields
from typing import Annotated, Any

import typer
import typer.core

from .errors import SkelpruneError
from .options import (
    CHOICES,
    COARSE,
    FOREGROUND_RULES,
    METHODS,
    SCOPES,
    OutputOptions,
    PruneOptions,
    RasterOptions,
    ReadOptions,
    VolumeOptions,
    option_fields,
)


def _usage(message: str) -> typer.Exit:
    """A usage error: one line on stderr, exit status 2."""
    typer.echo(f"error: {message}", err=True)
    return typer.Exit(2)


def _no_type(ctx: Any) -> str:
    """A parameter's type as --help shows it: not at all."""
    return ""


class _CleanCommand(typer.core.TyperCommand):
    """``--help`` without typer's type labels where they say nothing: none for flags and
    for the file arguments (``<list[Path]>``), ``FILE...`` in the usage line."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        # typer has no setting for these: each parameter's own methods are replaced
        for param in self.params:
            if isinstance(param, typer.core.TyperArgument):
                setattr(param, "display_type", _no_type)  # noqa: B010
                name = f"{param.metavar or (param.name or '').upper()}..."
                setattr(param, "_usage_display_name", lambda name=name: name)  # noqa: B010
            elif getattr(param, "is_flag", False):
                setattr(param, "display_type", _no_type)  # noqa: B010

    def get_help_option(self, ctx: Any) -> Any:
        option = super().get_help_option(ctx)
        if option is not None:
            setattr(option, "display_type", _no_type)  # noqa: B010
        return option


HELP = {
    name: text
    for name, _, text, _ in option_fields(
        PruneOptions, OutputOptions, ReadOptions, RasterOptions, VolumeOptions
    )
}


def _geojson_only(name: str) -> str:
    return "GeoJSON input: " + HELP[name][0].lower() + HELP[name][1:]


# the choices as typer shows them (it lists an Enum's values in --help); made from the
# tuples of skelprune.options, where each is defined once, which mypy cannot read
Method = enum.Enum("Method", {name: name for name in METHODS}, type=str)  # type: ignore[misc]
Coarse = enum.Enum("Coarse", {name: name for name in COARSE}, type=str)  # type: ignore[misc]
Rule = enum.Enum("Rule", {n: n for n in FOREGROUND_RULES}, type=str)  # type: ignore[misc]
# the options every pruning command takes, declared once
BetaOption = Annotated[float, typer.Option(help=HELP["beta"])]
MethodOption = Annotated[Method, typer.Option(help=HELP["method"])]
CoarseOption = Annotated[Coarse, typer.Option(help=HELP["coarse"])]
ThresholdOption = Annotated[float | None, typer.Option(help=HELP["dce_threshold"])]
MarginOption = Annotated[float | None, typer.Option(help=HELP["min_margin"])]
TrimOption = Annotated[bool, typer.Option(help=HELP["trim"])]
Choice = enum.Enum("Choice", {name: name for name in CHOICES}, type=str)  # type: ignore[misc]
ChoiceOption = Annotated[Choice, typer.Option(help=HELP["choice"])]
ForegroundOption = Annotated[Rule, typer.Option(help=HELP["foreground"])]
LabelsOption = Annotated[bool, typer.Option(help=HELP["labels"])]
FillHolesOption = Annotated[int, typer.Option(help=HELP["fill_holes"])]
MinAreaOption = Annotated[int, typer.Option(help=HELP["min_area"])]
CurveOption = Annotated[bool, typer.Option(help=HELP["curve"])]
SequenceOption = Annotated[bool, typer.Option(help=HELP["sequence"])]
PixelSizeOption = Annotated[float | None, typer.Option(help=HELP["pixel_size"])]
LongestSideOption = Annotated[int | None, typer.Option(help=_geojson_only("longest_side"))]
PixelsPerWidthOption = Annotated[float, typer.Option(help=_geojson_only("pixels_per_width"))]
PixelBudgetOption = Annotated[int, typer.Option(help=_geojson_only("pixel_budget"))]
RepairOption = Annotated[bool, typer.Option(help=_geojson_only("repair"))]
CrsOption = Annotated[str | None, typer.Option(help=_geojson_only("crs"))]
SimplifyOption = Annotated[float, typer.Option(help=HELP["simplify"])]
CutEndsOption = Annotated[bool, typer.Option(help=HELP["cut_ends"])]
OverlayScaleOption = Annotated[int | None, typer.Option(help=HELP["overlay_scale"])]
Scope = enum.Enum("Scope", {name: name for name in SCOPES}, type=str)  # type: ignore[misc]
ScopeOption = Annotated[Scope, typer.Option(help=HELP["scope"])]
WindowOption = Annotated[int | None, typer.Option(help=HELP["window"])]
SpacingOption = Annotated[str | None, typer.Option(help=HELP["spacing"] + " Written DZ,DY,DX.")]


def _volume_or_exit(spacing: str | None) -> VolumeOptions:
    """``--spacing DZ,DY,DX`` as volume options (checked by their class)."""
    if spacing is None:
        return VolumeOptions()
    try:
        values = tuple(float(v) for v in spacing.split(","))
    except ValueError:
        raise _usage(f"--spacing is three numbers DZ,DY,DX, got {spacing!r}") from None
    try:
        return VolumeOptions(spacing=values)  # type: ignore[arg-type]
    except SkelpruneError as exc:
        raise _usage(str(exc)) from None


def _options_or_exit(params: dict[str, Any], *groups: type) -> tuple[Any, ...]:
    """One value of each options class, from the command's parameters of its fields'
    names (a choice's Enum read as its value): the classes check them, once."""
    values = {k: v.value if isinstance(v, enum.Enum) else v for k, v in params.items()}
    try:
        return tuple(
            group(**{f.name: values[f.name] for f in fields(group) if f.name in values})
            for group in groups
        )
    except SkelpruneError as exc:
        raise _usage(str(exc)) from None
