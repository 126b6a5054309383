"""The command line, run as a user runs it: a real subprocess."""

from __future__ import annotations

import json
import subprocess
import sys

from testkit.shapes import dataset

CLI = [sys.executable, "-m", "skelprune.cli"]


def test_prune_one_file_prints_document_and_writes_overlay(tmp_path):
    png = dataset("kimia216")[0]
    out = tmp_path / "overlay.png"
    run = subprocess.run(
        [*CLI, "prune", str(png), "--beta", "9", "--overlay", str(out)],
        capture_output=True,
        text=True,
        timeout=300,
        check=True,
    )
    doc = json.loads(run.stdout)
    assert doc["beta"] == 9.0 and doc["method"] == "bayesian"
    assert doc["components"][0]["skeleton"]["endpoints"]
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_prune_several_files_in_pool(tmp_path):
    files = [str(p) for p in dataset("kimia99")[:3]]
    bad = tmp_path / "bad.png"
    bad.write_bytes(b"not a png")
    run = subprocess.run(
        [*CLI, "prune", *files, str(bad), "--no-curve", "--workers", "2"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    lines = [json.loads(x) for x in run.stdout.splitlines()]
    assert [x["file"] for x in lines] == [*files, str(bad)]
    assert all("result" in x and "curve" not in x["result"]["components"][0] for x in lines[:3])
    assert "InvalidImageError" in lines[3]["error"]
    assert run.returncode == 1  # one input failed


def test_missing_file_is_a_clear_error(tmp_path):
    run = subprocess.run(
        [*CLI, "prune", str(tmp_path / "nope.png")], capture_output=True, text=True, timeout=120
    )
    assert run.returncode == 1
    assert "nope.png" in run.stderr and "Traceback" not in run.stderr
