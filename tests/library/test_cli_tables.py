"""The command line with label images, TIFF files, cleaning and the CSV table."""

from __future__ import annotations

import csv
import io
import json
import subprocess
import sys

import numpy as np
import tifffile
from PIL import Image

CLI = [sys.executable, "-m", "skelprune.cli"]


def run(*args: str, check: bool = True) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*CLI, *args], capture_output=True, text=True, timeout=300, check=check)


def label_image() -> np.ndarray:
    lab = np.zeros((60, 120), np.uint16)
    lab[10:50, 5:60] = 11
    lab[10:50, 60:115] = 50000
    lab[20:22, 20:22] = 0  # a pinhole in 11
    return lab


def test_labels_tiff_csv_and_cleaning(tmp_path):
    tif = tmp_path / "cells.tif"
    tifffile.imwrite(tif, label_image(), compression="zlib")
    table = tmp_path / "branches.csv"
    done = run("prune", str(tif), "--labels", "--fill-holes", "8", "--csv", str(table))
    doc = json.loads(done.stdout)
    assert [c["label"] for c in doc["components"]] == [11, 50000]
    assert doc["foreground"] == {
        "rule": "auto",
        "shape": "labels",
        "threshold": None,
        "border": None,
        "fill_holes": 8,
    }
    assert doc["components"][0]["area"] == 40 * 55  # the pinhole filled
    rows = list(csv.DictReader(io.StringIO(table.read_text())))
    assert {r["label"] for r in rows} == {"11", "50000"} and rows[0]["unit"] == "px"


def test_folder_mode_takes_tiff_and_refuses_other_images_by_name(tmp_path):
    Image.fromarray(((label_image() > 0) * 255).astype(np.uint8)).save(tmp_path / "a.png")
    tifffile.imwrite(tmp_path / "b.TIFF", (label_image() > 0).astype(np.uint8) * 255)
    (tmp_path / "c.jpg").write_bytes(b"\xff\xd8\xff\xe0" + bytes(30))
    done = run("prune", str(tmp_path), "--no-curve", "--workers", "1")
    lines = [json.loads(line) for line in done.stdout.splitlines()]
    assert sorted(line["file"].rsplit("/", 1)[1] for line in lines) == ["a.png", "b.TIFF"]
    assert all("result" in line for line in lines)
    bad = run("prune", str(tmp_path / "c.jpg"), check=False)
    assert bad.returncode == 1
    assert "a JPEG image" in bad.stderr and "PNG, TIFF and GIF" in bad.stderr


def test_csv_usage_errors(tmp_path):
    one = tmp_path / "a.tif"
    tifffile.imwrite(one, label_image())
    bad = run("prune", str(one), str(one), "--csv", str(tmp_path / "t.csv"), check=False)
    assert bad.returncode == 2 and "--csv takes one input file" in bad.stderr
    bad = run("prune", str(one), "--csv", str(tmp_path / "no" / "t.csv"), check=False)
    assert bad.returncode == 2 and "does not exist" in bad.stderr
    bad = run("prune", str(one), "--min-area", "-1", check=False)
    assert bad.returncode == 2 and "min_area" in bad.stderr
