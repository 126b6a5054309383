"""The installed package is the product: the wheel, installed into a fresh virtual
environment outside the repository, runs its command line and its server on its own."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import httpx
import pytest

import skelprune
from testkit import REPO
from testkit.realserver import running_server

pytestmark = pytest.mark.slow

PIP = (sys.executable, "-m", "pip", "--quiet", "--disable-pip-version-check")
PURELIB = "import sysconfig; print(sysconfig.get_path('purelib'))"


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("wheel")
    subprocess.run(
        [*PIP, "wheel", "--no-deps", "--no-build-isolation", "--wheel-dir", str(out), str(REPO)],
        check=True,
        cwd=out,
    )
    (path,) = out.glob("skelprune-*.whl")
    return path


@pytest.fixture(scope="module")
def venv(wheel: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A fresh venv holding the wheel. Its dependencies come from the test venv's
    site-packages, added as a plain path: the test venv's editable install of the
    project (a .pth hook there) is not run, so only the wheel's copy can be imported."""
    root = tmp_path_factory.mktemp("venv") / "env"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(root)], check=True)
    site = subprocess.run(
        [
            str(root / "bin" / "python"),
            "-c",
            "import sysconfig; print(sysconfig.get_path('purelib'))",
        ],
        check=True,
        capture_output=True,
        text=True,
    ).stdout.strip()
    Path(site, "test-venv-packages.pth").write_text(sysconfig.get_path("purelib") + "\n")
    subprocess.run(
        [*PIP, "--python", str(root / "bin" / "python"), "install", "--no-deps", str(wheel)],
        check=True,
    )
    return root


def _env(tmp: Path) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env["NUMBA_CACHE_DIR"] = str(tmp / "numba-cache")  # the CLI compiles, the server loads
    return env


def test_the_wheel_holds_the_library_and_the_service_only(wheel: Path) -> None:
    names = zipfile.ZipFile(wheel).namelist()
    tops = {n.split("/")[0] for n in names if not n.split("/")[0].endswith(".dist-info")}
    assert tops == {"skelprune", "service"}
    assert "service/static/index.html" in names and "skelprune/py.typed" in names
    metadata = next(n for n in names if n.endswith(".dist-info/METADATA"))
    text = zipfile.ZipFile(wheel).read(metadata).decode()
    assert "License-Expression: MIT" in text
    requires = [line for line in text.splitlines() if line.startswith("Requires-Dist:")]
    assert not [r for r in requires if "scikit-image" in r and "extra ==" not in r]


def test_the_installed_wheel_prunes_and_serves(venv: Path, tmp_path: Path) -> None:
    work = tmp_path / "elsewhere"  # outside the repository: nothing of it can be imported
    work.mkdir()
    shutil.copy(REPO / "examples" / "shape.png", work / "shape.png")
    env = _env(tmp_path)
    where = subprocess.run(
        [
            str(venv / "bin" / "python"),
            "-c",
            "import skelprune, service; print(skelprune.__file__)",
        ],
        cwd=work,
        env=env,
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    assert Path(where).is_relative_to(venv)

    version = subprocess.run(
        [str(venv / "bin" / "skelprune"), "--version"],
        cwd=work,
        env=env,
        check=True,
        capture_output=True,
        text=True,
    ).stdout.strip()
    assert version == skelprune.__version__

    pruned = subprocess.run(
        [str(venv / "bin" / "skelprune"), "prune", "shape.png"],
        cwd=work,
        env=env,
        check=True,
        capture_output=True,
        text=True,
        timeout=600,
    )
    doc = json.loads(pruned.stdout)
    assert doc["components"] and doc["components"][0]["skeleton"]["endpoints"]

    with running_server(
        tmp_path / "server.log",
        python=str(venv / "bin" / "python"),
        cwd=work,
        env_extra=env,
    ) as (_, base):
        resp = httpx.post(
            f"{base}/v1/prune",
            content=(work / "shape.png").read_bytes(),
            headers={"Content-Type": "image/png"},
            timeout=60,
        )
        assert resp.status_code == 200, resp.text
        assert resp.json()["components"][0]["skeleton"] == doc["components"][0]["skeleton"]
