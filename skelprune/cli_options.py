"""The command line's options, declared once from :mod:`skelprune.options`: their help
texts, the choices as Enums, the ``Annotated`` option types the commands share, a
``--help`` without type labels that say nothing, and the commands' parameters read back
into option values (a usage error, exit status 2, when a class refuses them).
"""

from __future__ import annotations

import enum
import functools
import inspect
import typing
from collections.abc import Callable
from dataclasses import fields
from typing import Annotated, Any, TypeVar

import typer
import typer.core

from .errors import SkelpruneError
from .options import (
    OutputOptions,
    PruneOptions,
    RasterOptions,
    ReadOptions,
    VolumeOptions,
    option_fields,
)

T = TypeVar("T")


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
#: The option classes every pruning command takes, in --help's order.
PRUNE_GROUPS: tuple[type, ...] = (
    PruneOptions,
    ReadOptions,
    RasterOptions,
    VolumeOptions,
    OutputOptions,
)
#: Options a command writes as files, not as flags of their own: the overlay image
#: (``--overlay FILE``), written beside the document rather than inside it.
AS_FILES = ("overlay",)


def _choices(name: str, choices: tuple[str, ...]) -> type[enum.Enum]:
    # typer lists an Enum's values in --help; made from the definition's spellings
    return enum.Enum(name.title().replace("_", ""), {c: c for c in choices}, type=str)  # type: ignore[return-value]


def _parameter(group: type, f: Any, hints: dict[str, Any]) -> inspect.Parameter:
    """A command's parameter for one option field: its flag, help and default."""
    help_text = f.metadata["help"]
    default = f.default
    kind: Any = hints[f.name]
    if f.metadata["choices"]:
        kind = _choices(f.name, f.metadata["choices"])
        default = kind(default if default is not None else "none")
    elif f.name == "spacing":
        kind, default = str | None, None
        help_text += " Written DZ,DY,DX."
    elif f.default is None:
        kind = kind if type(None) in typing.get_args(kind) else kind | None
    annotation = Annotated[kind, typer.Option(help=help_text, show_default=default is not None)]
    return inspect.Parameter(
        f.name, inspect.Parameter.KEYWORD_ONLY, default=default, annotation=annotation
    )


def option_parameters(*groups: type, skip: tuple[str, ...] = ()) -> list[inspect.Parameter]:
    """The command-line parameters of every option of ``groups`` (but ``skip``), made
    from their definitions: a new option is a new flag of every command that takes its
    class."""
    out = []
    for group in groups:
        hints = typing.get_type_hints(group)
        out += [_parameter(group, f, hints) for f in fields(group) if f.name not in skip]
    return out


def with_options(
    *groups: type, skip: tuple[str, ...] = ()
) -> Callable[[Callable[..., T]], Callable[..., T]]:
    """Give a command every option of ``groups`` as flags; the command receives them as
    one dict, ``options`` (read back into values by :func:`_options_or_exit`).

    The command's own parameters come first in --help, the options after them.
    """

    def decorate(command: Callable[..., T]) -> Callable[..., T]:
        signature = inspect.signature(command, eval_str=True)
        own = [p for p in signature.parameters.values() if p.name != "options"]
        generated = option_parameters(*groups, skip=skip)
        names = {p.name for p in generated}

        @functools.wraps(command)
        def run(*args: Any, **kwargs: Any) -> T:
            options = {k: kwargs.pop(k) for k in list(kwargs) if k in names}
            return command(*args, options=options, **kwargs)

        params = [
            p.replace(kind=inspect.Parameter.KEYWORD_ONLY) if p.default is not p.empty else p
            for p in own
        ]
        run.__signature__ = inspect.Signature([*params, *generated])  # type: ignore[attr-defined]
        run.__annotations__ = {p.name: p.annotation for p in (*params, *generated)}
        return run

    return decorate


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
    if "spacing" in values:  # written DZ,DY,DX
        values["spacing"] = _volume_or_exit(values["spacing"]).spacing
    try:
        return tuple(
            group(**{f.name: values[f.name] for f in fields(group) if f.name in values})
            for group in groups
        )
    except SkelpruneError as exc:
        raise _usage(str(exc)) from None
