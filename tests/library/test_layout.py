"""The package's architecture, checked: no import cycles (lazy imports included), and a
library that knows nothing of HTTP."""

from __future__ import annotations

import ast
from pathlib import Path

from testkit import REPO

PACKAGES = ("skelprune", "service", "evaluation")
HTTP = ("fastapi", "starlette", "uvicorn", "pydantic", "pydantic_settings", "service")


def _modules() -> dict[str, Path]:
    out = {}
    for pkg in PACKAGES:
        for path in (REPO / pkg).rglob("*.py"):
            parts = path.relative_to(REPO).with_suffix("").parts
            name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            out[name] = path
    return out


def _imports(name: str, path: Path, modules: dict[str, Path]) -> set[str]:
    """Every project module ``name`` imports, at any depth of the file (lazy or not)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")
                anchor = anchor[: len(anchor) - node.level + 1]
                base = ".".join([*anchor, base] if base else anchor)
            # `from pkg import mod` imports the submodule when there is one
            targets = [
                f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base for a in node.names
            ]
        else:
            continue
        found.update(t for t in targets if t.split(".")[0] in PACKAGES or t in HTTP)
    return found - {name}


def _graph() -> dict[str, set[str]]:
    modules = _modules()
    return {name: _imports(name, path, modules) for name, path in modules.items()}


def _cycle(graph: dict[str, set[str]]) -> list[str] | None:
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(u: str) -> list[str] | None:
        state[u] = 1
        stack.append(u)
        for v in sorted(graph.get(u, ())):
            if v not in graph:
                continue
            if state.get(v) == 1:
                return [*stack[stack.index(v) :], v]
            if v not in state and (found := visit(v)):
                return found
        stack.pop()
        state[u] = 2
        return None

    for u in sorted(graph):
        if u not in state and (found := visit(u)):
            return found
    return None


def test_the_cycle_finder_finds_a_cycle() -> None:
    assert _cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert _cycle({"a": {"b"}, "b": {"c"}, "c": set()}) is None


def test_no_import_cycles() -> None:
    # A package's __init__ re-exports its submodules, and a submodule importing a sibling
    # goes through the package, so edges into a package's own __init__ are not cycles.
    graph = {u: {v for v in vs if not u.startswith(v + ".")} for u, vs in _graph().items()}
    assert _cycle(graph) is None


def test_the_library_knows_nothing_of_http() -> None:
    offenders = {
        u: sorted(v for v in vs if v.split(".")[0] in HTTP)
        for u, vs in _graph().items()
        if u.split(".")[0] == "skelprune"
    }
    assert {u: vs for u, vs in offenders.items() if vs} == {}


def test_the_installed_packages_import_nothing_of_the_repository_around_them() -> None:
    """The wheel holds skelprune and service only: neither may import the evaluation,
    the test kit or the benchmarks, which an installed copy does not have."""
    outside = ("evaluation", "testkit", "benchmarks", "tests")
    offenders = {
        u: sorted(v for v in vs if v.split(".")[0] in outside)
        for u, vs in _graph().items()
        if u.split(".")[0] in ("skelprune", "service")
    }
    assert {u: vs for u, vs in offenders.items() if vs} == {}
