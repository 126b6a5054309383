"""Volumes in ``prune_many`` and ``skelprune prune-many``: a ``.npy`` file, a TIFF stack or
a 3-D array gives the document ``skelprune.prune`` gives it, with the run's spacing; its
voxels count against the pixel limit from the header, its estimate against the budget;
what is refused is a problem line, and a second run skips what is written."""

from __future__ import annotations

import io
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import tifffile

import skelprune
from skelprune.limits import Limits
from skelprune.options import ReadOptions, VolumeOptions
from skelprune.parallel import PROBLEMS_FILE, document_bytes, prune_many
from skelprune.parallel.items import expand
from skelprune.parallel.work import Job, run_batch
from testkit import REPO
from testkit.volumes import tube, y_tubes

CLI = [sys.executable, "-m", "skelprune.cli"]
SPACING = (3.0, 1.0, 1.0)


def labelled_tubes() -> np.ndarray:
    """Two tubes side by side, labels 1 and 2: each its own shape."""
    one = tube(length=14.0, radius=2.5).volume()
    vol = np.zeros((one.shape[0], 2 * one.shape[1], one.shape[2]), np.uint8)
    vol[:, : one.shape[1]][one] = 1
    vol[:, one.shape[1] :][one] = 2
    return vol


def write_folder(folder: Path) -> dict[str, Path]:
    """A PNG mask, two ``.npy`` volumes, a TIFF stack and a corrupt ``.npy``."""
    folder.mkdir()
    files = {
        "shape": folder / "shape.png",
        "fork": folder / "fork.npy",
        "labels": folder / "labels.npy",
        "stack": folder / "stack.tif",
        "bad": folder / "bad.npy",
    }
    files["shape"].write_bytes((REPO / "examples" / "shape.png").read_bytes())
    np.save(files["fork"], y_tubes(radius=2.5, arm=14.0).volume())
    np.save(files["labels"], labelled_tubes())
    stack = y_tubes(radius=2.0, arm=11.0).volume().astype(np.uint8)
    tifffile.imwrite(files["stack"], stack, photometric="minisblack")
    files["bad"].write_bytes(b"\x93NUMPY\x01\x00not a header")
    return files


def header_only(shape: tuple[int, ...]) -> bytes:
    """A ``.npy`` header promising ``shape`` booleans, and nothing after it."""
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        buf, {"descr": "|b1", "fortran_order": False, "shape": shape}
    )
    return buf.getvalue()


def one(source, job: Job) -> tuple[bytes | None, tuple[str, str] | None]:
    done = run_batch([(0, expand({"x": source})[0])], job)[0]
    return (None if done.answer is None else done.answer.payload), done.problem


@pytest.mark.slow
@pytest.mark.timeout(300)
def test_a_folder_of_images_and_volumes_gives_what_prune_gives_each(tmp_path: Path) -> None:
    files = write_folder(tmp_path / "in")
    out = tmp_path / "lib"
    outcomes = prune_many(tmp_path / "in", out=out, spacing=SPACING, jobs=1, ordered=True)
    status = {o.input: o.status for o in outcomes}
    assert status == {
        "bad": "failed",
        "fork": "done",
        "labels": "done",
        "shape": "done",
        "stack": "done",
    }
    for name in ("fork", "labels", "stack"):
        doc = json.loads((out / f"{name}.json").read_bytes())
        assert doc == skelprune.prune(files[name], spacing=SPACING).to_dict(), name
        assert doc["dimensions"] == 3 and doc["spacing"] == list(SPACING)
    for name in ("fork", "stack"):  # the spacing applied: thicker slices, longer arms
        (spaced,) = json.loads((out / f"{name}.json").read_bytes())["components"]
        (unit,) = skelprune.prune(files[name]).to_dict()["components"]
        assert spaced["skeleton"]["length"] > 1.2 * unit["skeleton"]["length"], name
    assert len(json.loads((out / "labels.json").read_bytes())["components"]) == 2
    image = json.loads((out / "shape.json").read_bytes())
    assert image == skelprune.prune(files["shape"]).to_dict()  # the spacing: volumes only
    problems = [json.loads(x) for x in (out / PROBLEMS_FILE).read_text().splitlines()]
    assert [(p["input"], p["kind"]) for p in problems] == [("bad", "invalid-image")]
    assert ".npy" in problems[0]["detail"]

    # a second run skips the volumes written and tries the corrupt one again
    written = {p.name: os.stat(p) for p in out.glob("*.json")}
    again = prune_many(tmp_path / "in", out=out, spacing=SPACING, jobs=1, ordered=True)
    assert [o.status for o in again] == ["failed", "skipped", "skipped", "skipped", "skipped"]
    for name, before in written.items():
        after = os.stat(out / name)
        assert (after.st_ino, after.st_mtime_ns) == (before.st_ino, before.st_mtime_ns), name
    assert len((out / PROBLEMS_FILE).read_text().splitlines()) == 1

    # the command line writes the same bytes
    argv = [*CLI, "prune-many", str(tmp_path / "in"), "--out", str(tmp_path / "cli")]
    cli = subprocess.run(
        [*argv, "--jobs", "1", "--spacing", "3,1,1"], capture_output=True, text=True, timeout=200
    )
    assert cli.returncode == 1, cli.stderr  # the corrupt volume failed
    assert "done 4, failed 1, skipped 0 of 5" in cli.stderr
    assert "failed: bad: invalid-image" in cli.stderr
    for name in files:
        if name != "bad":
            assert (tmp_path / "cli" / f"{name}.json").read_bytes() == (
                out / f"{name}.json"
            ).read_bytes(), name
    bad = subprocess.run([*argv, "--spacing", "3,0,1"], capture_output=True, text=True, timeout=60)
    assert bad.returncode == 2 and bad.stderr.startswith("error: spacing must be")


def test_a_volume_is_pruned_in_a_task_with_the_runs_spacing() -> None:
    fork = y_tubes(radius=2.5, arm=14.0).volume()
    payload, problem = one(fork, Job(volume=VolumeOptions(spacing=SPACING)))
    assert problem is None
    assert payload == document_bytes(skelprune.prune(fork, spacing=SPACING).to_dict())
    unit, _ = one(fork, Job())  # a 3-D array of last axis > 4: a volume without spacing
    assert unit == document_bytes(skelprune.prune(fork).to_dict()) != payload
    # given volume options, any 3-D array is a volume (as for skelprune.prune)
    thin = np.zeros((20, 20, 4), bool)
    thin[2:18, 8:12, 1:3] = True
    as_volume, _ = one(thin, Job(volume=VolumeOptions()))
    assert json.loads(as_volume or b"{}")["dimensions"] == 3


def test_a_volume_over_the_pixel_limit_is_refused_from_its_header(tmp_path: Path) -> None:
    promise = tmp_path / "promise.npy"
    promise.write_bytes(header_only((30, 30, 30)))  # 27,000 voxels promised, none there
    _, problem = one(promise, Job(limits=Limits(max_pixels=1000)))
    assert problem is not None and problem[0] == "image-too-large"
    assert "27000 voxels" in problem[1] and "1000" in problem[1]
    # within the limit the same file is read, and found wanting: the refusal above came
    # from the header alone
    _, problem = one(promise, Job(limits=Limits(max_pixels=None)))
    assert problem is not None and problem[0] == "invalid-image"
    stack = tmp_path / "stack.tif"
    tifffile.imwrite(stack, np.ones((10, 20, 20), np.uint8), photometric="minisblack")
    _, problem = one(stack, Job(limits=Limits(max_pixels=3999)))
    assert problem is not None and problem[0] == "image-too-large" and "4000 voxels" in problem[1]
    _, problem = one(np.ones((10, 20, 20), bool), Job(limits=Limits(max_pixels=3999)))
    assert problem is not None and problem[0] == "image-too-large"


def test_a_volume_over_the_memory_or_time_budget_fails_as_job_too_large(tmp_path: Path) -> None:
    path = tmp_path / "fork.npy"
    np.save(path, y_tubes(radius=2.5, arm=14.0).volume())
    _, problem = one(path, Job(limits=Limits(memory_mb=1)))
    assert problem is not None and problem[0] == "job-too-large"
    assert "the voxels inside" in problem[1] and "memory budget of 1 MiB" in problem[1]
    _, problem = one(path, Job(limits=Limits(seconds=1e-6)))
    assert problem is not None and problem[0] == "job-too-large" and "time limit" in problem[1]


def test_image_options_fail_a_volume_alone_and_label_runs_keep_volumes_whole(
    tmp_path: Path,
) -> None:
    files = write_folder(tmp_path / "in")
    items = expand(tmp_path / "in")
    assert [it.name for it in items] == ["bad", "fork", "labels", "shape", "stack"]
    done = run_batch(list(enumerate(items)), Job(read=ReadOptions(fill_holes=5)))
    kinds = {it.name: d.problem and d.problem[0] for it, d in zip(items, done, strict=True)}
    assert kinds == {
        "bad": "invalid-option",
        "fork": "invalid-option",
        "labels": "invalid-option",
        "shape": None,
        "stack": "invalid-option",
    }
    labelled = expand(files["labels"], labels=True)
    assert [(it.name, it.source) for it in labelled] == [("labels", str(files["labels"]))]
    (done,) = run_batch(list(enumerate(labelled)), Job(read=ReadOptions(labels=True)))
    assert done.answer.payload == document_bytes(skelprune.prune(files["labels"]).to_dict())
    with pytest.raises(TypeError, match="not both"):
        prune_many(files["fork"], volume=VolumeOptions(), spacing=SPACING)
