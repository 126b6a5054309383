"""Every example of the README and of docs/guide.md runs verbatim where ``make run``
leaves a user: their Python blocks and command lines, from the repository's root, with
only the packages of the extras ``make run`` installs (service, graph) importable: the
others' are hidden.

The client's fragments (``# examples/client.py``) are checked against the file by
tests/service/test_examples.py; ``prune-many`` needs the ``parallel`` extra (and one of
its lines a cluster), so its block is not run here."""

from __future__ import annotations

import importlib.metadata
import os
import re
import subprocess
import sys
import textwrap
import tomllib
from pathlib import Path

import pytest

from testkit import REPO

pytestmark = pytest.mark.timeout(300)

README = (REPO / "README.md").read_text(encoding="utf-8")
#: The README and the guide it links to: both show examples that must run.
PAGES = README + "\n" + (REPO / "docs" / "guide.md").read_text(encoding="utf-8")
#: The extras ``make run`` installs (the Makefile's SERVE).
RUN_EXTRAS = ("service", "graph")


def _name(requirement: str) -> str:
    return re.split(r"[\[<>=!~; ]", requirement, maxsplit=1)[0].lower().replace("_", "-")


def _hidden_modules() -> list[str]:
    """The top-level modules of the packages only the other extras install."""
    project = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    extras = project["optional-dependencies"]
    kept = {_name(r) for r in project["dependencies"]}
    kept |= {_name(r) for extra in RUN_EXTRAS for r in extras[extra]}
    others = {_name(r) for extra, reqs in extras.items() for r in reqs} - kept
    modules = importlib.metadata.packages_distributions()
    return sorted(
        module
        for module, dists in modules.items()
        if all(d.lower().replace("_", "-") in others for d in dists)
    )


BLOCKER = """\
import sys
from importlib.abc import MetaPathFinder

HIDDEN = set({hidden!r})


class _NotInstalled(MetaPathFinder):
    # what `make run` does not install cannot be imported
    def find_spec(self, name, path=None, target=None):
        if name.partition(".")[0] in HIDDEN:
            raise ModuleNotFoundError(f"No module named {{name!r}}", name=name)
        return None


sys.meta_path.insert(0, _NotInstalled())
"""


@pytest.fixture(scope="module")
def run_env(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    """An environment whose Python cannot import what ``make run`` does not install."""
    where = tmp_path_factory.mktemp("make-run")
    hidden = _hidden_modules()
    assert {"pandas", "geopandas", "pyproj", "napari"} <= set(hidden)
    assert "networkx" not in hidden and "fastapi" not in hidden
    (where / "sitecustomize.py").write_text(BLOCKER.format(hidden=hidden), encoding="utf-8")
    return {**os.environ, "PYTHONPATH": str(where)}


def _python_blocks() -> list[str]:
    blocks = re.findall(r"^( *)```python\n(.*?)^\1```", PAGES, re.S | re.M)
    out = [textwrap.dedent(code) for _, code in blocks]
    return [code for code in out if not code.startswith("# examples/client.py")]


def _command_lines() -> list[str]:
    sections = re.findall(r"^#+ Command line\n(.*?)(?=^#)", PAGES, re.S | re.M)
    blocks = [b for section in sections for b in re.findall(r"```sh\n(.*?)```", section, re.S)]
    return [line for block in blocks for line in block.splitlines() if line.strip()]


def test_the_blocker_hides_what_make_run_does_not_install(run_env) -> None:
    check = "import networkx\ntry:\n    import pandas\nexcept ImportError:\n    print('hidden')"
    run = subprocess.run(
        [sys.executable, "-c", check], env=run_env, capture_output=True, text=True, timeout=60
    )
    assert run.returncode == 0 and run.stdout.strip() == "hidden", run.stderr


@pytest.mark.parametrize("code", _python_blocks(), ids=lambda c: c.splitlines()[-1][:40])
def test_a_python_example_runs(code: str, run_env) -> None:
    run = subprocess.run(
        [sys.executable, "-c", code],
        cwd=REPO,
        env=run_env,
        capture_output=True,
        text=True,
        timeout=240,
    )
    assert run.returncode == 0, f"{code}\n{run.stderr}"


def test_the_python_examples_are_found() -> None:
    blocks = _python_blocks()
    assert len(blocks) >= 3
    assert any("examples/vessel.npy" in b for b in blocks)
    assert any("summary()" in b for b in blocks)


@pytest.mark.parametrize("line", _command_lines(), ids=lambda s: s.split("#")[0][15:55])
def test_a_command_line_runs(line: str, run_env) -> None:
    command = line.split("  #", 1)[0]
    assert command.startswith(".venv/bin/skelprune ")
    # the README's .venv/bin/skelprune is this environment's
    command = str(Path(sys.executable).parent / "skelprune") + command[len(".venv/bin/skelprune") :]
    run = subprocess.run(
        ["bash", "-c", command], cwd=REPO, env=run_env, capture_output=True, text=True, timeout=240
    )
    assert run.returncode == 0, f"{line}\n{run.stderr[-2000:]}"
