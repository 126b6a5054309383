"""The examples a user runs first: examples/client.py against the real server, and the
README's copy of it, which must be the file's code verbatim."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from testkit import REPO

pytestmark = pytest.mark.timeout(300)

CLIENT = REPO / "examples" / "client.py"


def test_the_client_runs_against_the_real_server(real_server, tmp_path) -> None:
    where = tmp_path / "cwd"
    where.mkdir()
    with real_server(workers="1") as (_, base):
        run = subprocess.run(
            [sys.executable, str(CLIENT), base],
            cwd=where,
            capture_output=True,
            text=True,
            timeout=120,
        )
    assert run.returncode == 0, run.stderr
    lines = run.stdout.splitlines()
    assert lines[0].startswith("shape.png: RER ") and "endpoints" in lines[0]
    assert lines[1].startswith("shape.geojson: RER ")
    written = lines[2].split(" written ")[0]
    assert Path(written).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert list(where.iterdir()) == []  # nothing written where it runs
    # an overlay path given: written there
    with real_server(workers="1") as (_, base):
        run = subprocess.run(
            [sys.executable, str(CLIENT), base, str(tmp_path / "mine.png")],
            capture_output=True,
            text=True,
            timeout=120,
        )
    assert run.returncode == 0, run.stderr
    assert (tmp_path / "mine.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_readme_uses_the_client_verbatim() -> None:
    readme = (REPO / "docs" / "guide.md").read_text(encoding="utf-8")
    code = CLIENT.read_text(encoding="utf-8")
    blocks = re.findall(r"```python\n# examples/client\.py\n(.*?)```", readme, re.S)
    assert blocks, "the guide shows the client"
    for block in blocks:
        assert block in code, block
