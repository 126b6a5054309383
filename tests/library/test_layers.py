"""The code's layers: the pruning core knows no grid (docs/architecture.md)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import skelprune

PACKAGE = Path(skelprune.__file__).parent
#: The grids and the pixel skeleton: what ``skelprune.pruning`` must not reach.
GRIDS = ("skelprune.grid", "skelprune.grid3d", "skelprune.skeleton")


def module_file(name: str) -> Path | None:
    """The source file of module ``name`` of the package (``None``: not one of its own)."""
    parts = name.split(".")
    if parts[0] != "skelprune":
        return None
    base = PACKAGE.joinpath(*parts[1:])
    for path in (base / "__init__.py", base.with_suffix(".py")):
        if path.is_file():
            return path
    return None


def imported(name: str) -> set[str]:
    """Every module of the package that module ``name`` imports, anywhere in its file
    (under ``TYPE_CHECKING`` and inside functions included)."""
    path = module_file(name)
    assert path is not None, name
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                anchor = package.split(".")
                anchor = anchor[: len(anchor) - node.level + 1]
                base = ".".join(anchor + ([node.module] if node.module else []))
            else:
                base = node.module or ""
            out.add(base)
            # ``from package import module`` imports the module
            out.update(f"{base}.{a.name}" for a in node.names if module_file(f"{base}.{a.name}"))
    return {m for m in out if module_file(m) is not None}


def reaches_grid(name: str) -> list[str] | None:
    """A chain of imports from module ``name`` to a grid module, or ``None``."""
    seen = {name}
    todo = [[name]]
    while todo:
        chain = todo.pop()
        for m in sorted(imported(chain[-1])):
            if any(m == g or m.startswith(g + ".") for g in GRIDS):
                return [*chain, m]
            if m not in seen:
                seen.add(m)
                todo.append([*chain, m])
    return None


PRUNING = sorted(p.stem for p in (PACKAGE / "pruning").glob("*.py"))


def test_the_walk_sees_imports() -> None:
    # the walk itself: a grid module's own imports are found, relative ones resolved
    assert "skelprune.pruning.branch_graph" in imported("skelprune.grid.graph")
    assert reaches_grid("skelprune.grid.dce") is not None


@pytest.mark.parametrize("stem", PRUNING)
def test_pruning_imports_no_grid(stem: str) -> None:
    name = "skelprune.pruning" if stem == "__init__" else f"skelprune.pruning.{stem}"
    assert reaches_grid(name) is None, " -> ".join(reaches_grid(name) or [])
