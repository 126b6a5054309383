"""The command line, run as a user runs it: a real subprocess."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

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


def cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*CLI, *args], capture_output=True, text=True, timeout=120)


def one_line_usage_error(run: subprocess.CompletedProcess[str], fragment: str) -> None:
    assert run.returncode == 2, run.stderr
    assert run.stdout == ""
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and fragment in lines[0], run.stderr


def test_usage_errors_are_one_line_before_any_file_is_read(tmp_path):
    png = str(dataset("kimia216")[0])
    one_line_usage_error(
        cli("prune", png, "--overlay", str(tmp_path / "no" / "x.png")), "does not exist"
    )
    one_line_usage_error(cli("prune", png, png, "--workers", "-3"), "--workers must be >= 0")
    folder = str(dataset("kimia216")[0].parent)
    one_line_usage_error(cli("prune", folder, "--beta", "-1"), "beta must be")
    one_line_usage_error(cli("prune", png, "--beta", "-1"), "beta must be")
    one_line_usage_error(cli("prune", png, "--longest-side", "4"), "longest_side")
    one_line_usage_error(cli("prune", str(tmp_path)), "no PNG, TIFF, GeoJSON or .npy file")


def test_version_and_clean_help():
    from skelprune import __version__

    run = cli("--version")
    assert run.returncode == 0 and run.stdout.strip() == __version__
    text = subprocess.run(
        [*CLI, "prune", "--help"],
        capture_output=True,
        text=True,
        timeout=120,
        env={"COLUMNS": "120", "PATH": ""},
    ).stdout
    assert "FILE..." in text and "bayesian|dce" in text and "dce|none" in text
    for odd in ("{files}", "list[Path]", "<bool>"):
        assert odd not in text, text


def test_a_folder_gives_png_of_any_case_and_geojson(tmp_path):
    png = dataset("kimia216")[0]
    (tmp_path / "shape.PNG").write_bytes(png.read_bytes())
    rect = {"type": "Polygon", "coordinates": [[[0, 0], [40, 0], [40, 20], [0, 20], [0, 0]]]}
    (tmp_path / "rect.GeoJSON").write_text(json.dumps(rect))
    (tmp_path / "notes.txt").write_text("not a shape")
    run = cli("prune", str(tmp_path), "--no-curve", "--workers", "1")
    assert run.returncode == 0, run.stderr
    lines = [json.loads(line) for line in run.stdout.splitlines()]
    assert [Path(line["file"]).name for line in lines] == ["rect.GeoJSON", "shape.PNG"]
    assert all("result" in line for line in lines)


def test_a_geojson_file_is_pruned_in_its_own_coordinates(tmp_path):
    rect = {"type": "Polygon", "coordinates": [[[0, 0], [40, 0], [40, 20], [0, 20], [0, 0]]]}
    path = tmp_path / "rect.geojson"
    path.write_text(json.dumps(rect))
    run = cli("prune", str(path), "--pixel-size", "0.5")
    assert run.returncode == 0, run.stderr
    doc = json.loads(run.stdout)
    assert doc["foreground"]["shape"] == "polygon"
    assert (doc["width"], doc["height"]) == (84, 44)  # 80 × 40 pixels and a 2-pixel margin
    xs = [p[0] for b in doc["components"][0]["skeleton"]["branches"] for p in b["points"]]
    assert min(xs) >= 0 and max(xs) <= 40  # polygon units, not pixels
    bad = tmp_path / "bad.geojson"
    bad.write_text("{not json")
    run = cli("prune", str(bad))
    assert run.returncode == 1 and "not a GeoJSON file" in run.stderr
    assert len(run.stderr.strip().splitlines()) == 1


def test_prune_a_volume_from_npy(tmp_path):
    import numpy as np

    vol = np.zeros((12, 14, 40), bool)
    vol[3:9, 4:10, 3:37] = True
    path = tmp_path / "bar.npy"
    np.save(path, vol)
    out, csv = tmp_path / "mip.png", tmp_path / "branches.csv"
    run = subprocess.run(
        [*CLI, "prune", str(path), "--spacing", "2,1,1", "--overlay", str(out), "--csv", str(csv)],
        capture_output=True,
        text=True,
        timeout=300,
        check=True,
    )
    doc = json.loads(run.stdout)
    assert doc["dimensions"] == 3 and doc["spacing"] == [2.0, 1.0, 1.0]
    assert len(doc["components"][0]["skeleton"]["branches"][0]["points"][0]) == 4
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert csv.read_text().splitlines()[0].startswith("component,label,branch,kind,length")
    refused = subprocess.run(
        [*CLI, "prune", str(path), "--geojson"], capture_output=True, text=True, timeout=300
    )
    assert refused.returncode == 1 and "has no GeoJSON answer" in refused.stderr
    bad = subprocess.run(
        [*CLI, "prune", str(path), "--spacing", "1,0,1"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert bad.returncode == 2 and bad.stderr.startswith("error: spacing must be")
