"""Names a package exports but imports only when first used (PEP 562), so that
``import skelprune`` and ``--help`` load neither numba nor scipy."""

from __future__ import annotations

import importlib
import importlib.util
import sys
from collections.abc import Callable
from typing import Any


def lazy_exports(
    package: str, table: dict[str, str], submodules: bool = False
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """The module ``__getattr__`` and ``__dir__`` of ``package``.

    ``table`` maps each exported name to the submodule that defines it; the value is
    bound on the package once imported. With ``submodules``, any other name that is a
    submodule (``skelprune.api`` after ``import skelprune``) is imported on first use, as
    when the package imported them all.
    """

    def __getattr__(name: str) -> Any:
        if name not in table:
            if (
                submodules
                and not name.startswith("__")
                and importlib.util.find_spec(f"{package}.{name}")
            ):
                return importlib.import_module(f".{name}", package)
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f".{table[name]}", package), name)
        vars(sys.modules[package])[name] = value
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(table))

    return __getattr__, __dir__
