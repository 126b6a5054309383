"""``skelprune match`` and ``skelprune retrieve``, run as a user runs them: a subprocess."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys

import numpy as np
from PIL import Image

import skelprune
from skelprune.io.png import read_mask
from testkit import DATA

CLI = [sys.executable, "-m", "skelprune.cli"]
SHAPES = ["hammer-1", "hammer-2", "hammer-3", "bird-2", "bird-7", "bone-1"]


def test_match_prints_distance_and_correspondence():
    a, b = (str(DATA / "kimia216" / f"{n}.png") for n in ("hammer-1", "bird-2"))
    run = subprocess.run(
        [*CLI, "match", a, b], capture_output=True, text=True, timeout=300, check=True
    )
    doc = json.loads(run.stdout)
    lib = skelprune.match(*(read_mask(p) for p in (a, b)))
    assert doc["distance"] == lib.distance > 0
    assert len(doc["correspondence"]) == min(doc["endpoints"])
    same = json.loads(
        subprocess.run(
            [*CLI, "match", a, a], capture_output=True, text=True, timeout=300, check=True
        ).stdout
    )
    assert same["distance"] == 0.0
    assert all(p["a"] == p["b"] for p in same["correspondence"])


def test_match_errors_are_one_line(tmp_path):
    a = str(DATA / "kimia216" / "hammer-1.png")
    ring = np.zeros((60, 60), np.uint8)
    yy, xx = np.mgrid[:60, :60]
    rr = np.hypot(yy - 30, xx - 30)
    ring[(rr < 25) & (rr > 12)] = 255
    Image.fromarray(ring).save(tmp_path / "ring.png")
    for args, code, text in (
        ([a, str(tmp_path / "ring.png")], 1, "endpoint"),
        ([a, str(tmp_path / "nope.png")], 1, "nope.png"),
        ([a, a, "--beta", "-1"], 2, "beta"),
        ([a], 2, ""),
    ):
        run = subprocess.run([*CLI, "match", *args], capture_output=True, text=True, timeout=300)
        assert run.returncode == code, run.stderr
        lines = run.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("error:") and text in lines[0]
        assert "Traceback" not in run.stderr


def test_retrieve_folder_top_k_json_lines(tmp_path):
    for n in SHAPES:
        shutil.copy(DATA / "kimia216" / f"{n}.png", tmp_path / f"{n}.png")
    (tmp_path / "bad.png").write_bytes(b"not a png")
    run = subprocess.run(
        [*CLI, "retrieve", str(tmp_path), "--top", "2", "--workers", "2"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 1  # one input could not be read
    lines = [json.loads(x) for x in run.stdout.splitlines()]
    files = sorted(str(p) for p in tmp_path.glob("*.png"))
    assert [x["file"] for x in lines] == files
    by_name = {x["file"].rsplit("/", 1)[-1][:-4]: x for x in lines}
    assert "InvalidImageError" in by_name["bad"]["error"]
    descs = {n: skelprune.describe(read_mask(tmp_path / f"{n}.png")) for n in SHAPES}
    for n in SHAPES:
        top = by_name[n]["top"]
        assert len(top) == 2 and all(t["file"] != by_name[n]["file"] for t in top)
        expected = sorted(
            (skelprune.match(descs[n], descs[m]).distance, m) for m in SHAPES if m != n
        )[:2]
        assert [t["distance"] for t in top] == [d for d, _ in expected]
    assert by_name["hammer-1"]["top"][0]["file"].rsplit("/", 1)[-1].startswith("hammer-")
