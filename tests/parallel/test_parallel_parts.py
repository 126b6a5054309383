"""The parts of ``skelprune.parallel`` that need no cluster: naming inputs, the output
folder's writes, the problem kinds and the budget (the service's), the lazy import and
the command's usage errors."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import skelprune
from skelprune.errors import (
    EmptyMaskError,
    InvalidOptionError,
    JobTooLargeError,
    SkelpruneError,
    problem_kind,
)
from skelprune.limits import DATASET_LIMITS, Limits
from skelprune.parallel import Labels, document_bytes
from skelprune.parallel.items import expand
from skelprune.parallel.store import PROBLEMS_FILE, Store
from skelprune.parallel.work import INTERNAL_ERROR, WORKER_CRASHED, Job, run_batch

CLI = [sys.executable, "-m", "skelprune.cli"]


def names(inputs, **kw) -> list[str]:
    return [item.key for item in expand(inputs, **kw)]


def test_files_folders_and_globs_are_named_after_the_files(tmp_path: Path) -> None:
    for sub in ("a", "b"):
        (tmp_path / sub).mkdir()
        (tmp_path / sub / "x.png").write_bytes(b"")
    (tmp_path / "a" / "y.PNG").write_bytes(b"")
    (tmp_path / "a" / "notes.txt").write_bytes(b"")
    assert names(tmp_path / "a") == ["x", "y"]
    assert names(str(tmp_path / "a" / "*.png")) == ["x"]
    # the same name twice: the path from the common folder tells them apart
    assert names(str(tmp_path / "**" / "x.png")) == ["a__x.png", "b__x.png"]
    assert names({"first": tmp_path / "a" / "x.png"}) == ["first"]


def test_a_zarr_store_is_one_input_alone_in_a_folder_or_a_glob(tmp_path: Path) -> None:
    for store in ("cells.zarr", "plain"):  # a store by its name, or by its metadata
        (tmp_path / store).mkdir()
        (tmp_path / store / ".zarray").write_text("{}")
    (tmp_path / "notes").mkdir()  # any other folder is no input
    (tmp_path / "x.png").write_bytes(b"")
    assert names(tmp_path / "cells.zarr") == ["cells"]
    assert names(tmp_path) == ["cells", "plain", "x"]
    assert names(str(tmp_path / "*")) == ["cells", "plain", "x"]


def test_arrays_are_numbered_and_mappings_named() -> None:
    m = np.ones((4, 4), bool)
    assert names([m, m, m]) == ["0000", "0001", "0002"]
    assert names({"one": m, "two/bad name": m}) == ["one", "two_bad_name"]
    assert names(Labels(np.array([[0, 2], [5, 5]]), name="img")) == ["img-2", "img-5"]


def test_clashing_reserved_and_missing_names_are_refused(tmp_path: Path) -> None:
    (tmp_path / "x.png").write_bytes(b"")
    (tmp_path / "x.geojson").write_bytes(b"")
    (tmp_path / "problems.png").write_bytes(b"")
    assert names([tmp_path / "x.png", tmp_path / "x.geojson"]) == ["x.png", "x.geojson"]
    m = np.ones((2, 2), bool)
    with pytest.raises(InvalidOptionError, match="'a_b'"):
        expand({"a b": m, "a_b": m})
    with pytest.raises(InvalidOptionError, match="run's own file"):
        expand(tmp_path / "problems.png")
    with pytest.raises(InvalidOptionError, match="no input"):
        expand(str(tmp_path / "*.tif"))
    with pytest.raises(skelprune.InvalidImageError, match="2-D integer"):
        Labels(np.zeros((3, 3), float)).items()


@pytest.mark.parametrize("bad", [{"jobs": 0}, {"batch_size": 0}, {"batch_size": 2.5}])
def test_counts_are_whole_numbers_checked_before_any_work(bad) -> None:
    from skelprune.parallel import prune_many

    with pytest.raises(InvalidOptionError, match="whole number >= 1"):
        prune_many([np.ones((4, 4), bool)], **bad)


def test_a_batch_runs_every_item_and_names_each_failure() -> None:
    m = np.zeros((20, 30), bool)
    m[4:16, 4:26] = True
    items = expand({"good": m, "empty": m & False, "missing": Path("/nonexistent/x.png")})
    done = run_batch(list(enumerate(items)), Job())
    assert [d.position for d in done] == [0, 1, 2]
    assert done[0].answer.payload == document_bytes(skelprune.prune(m).to_dict())
    assert done[1].problem == ("empty-mask", "the mask has no foreground pixel")
    assert done[2].answer is None and done[2].problem[0] in ("invalid-image", "invalid-input")
    refused = run_batch([(0, items[0])], Job(limits=Limits(memory_mb=1)))
    assert refused[0].problem[0] == "job-too-large"


def test_documents_are_written_whole_and_half_lines_dropped(tmp_path: Path) -> None:
    store = Store(tmp_path)
    (tmp_path / ".x.abc.tmp").write_bytes(b'{"half')  # left by a stopped run
    store.write_document("x", b"{}\n")
    assert store.has_document("x") and (tmp_path / "x.json").read_bytes() == b"{}\n"
    (tmp_path / "t.jsonl").write_bytes(b'{"row": 0}\n{"row": 1')  # stopped mid-line
    assert store.has_row("t", 0) and not store.has_row("t", 1)
    store.write_row("t", 1, b'{"row": 1}\n')
    store.start_problems({"y"})
    store.write_problem({"input": "y", "kind": "empty-mask", "detail": "d"})
    store.close()
    assert (tmp_path / "t.jsonl").read_bytes() == b'{"row": 0}\n{"row": 1}\n'
    store = Store(tmp_path)
    assert not list(tmp_path.glob(".*.tmp"))
    store.start_problems({"z"})  # y is not tried again: its line stays
    store.close()
    assert json.loads((tmp_path / PROBLEMS_FILE).read_text())["input"] == "y"
    store = Store(tmp_path)
    store.start_problems({"y"})  # y tried again: its old line goes
    store.close()
    assert (tmp_path / PROBLEMS_FILE).read_bytes() == b""
    assert oct((tmp_path / "x.json").stat().st_mode & 0o777) != oct(0o600)


def test_problem_kinds_are_the_services() -> None:
    from service.errors import PROBLEMS

    slugs = {row.slug for row in PROBLEMS.values()}
    for cls, row in PROBLEMS.items():
        if issubclass(cls, SkelpruneError):
            assert row.slug == cls.kind, cls
    assert {WORKER_CRASHED, INTERNAL_ERROR} <= slugs
    assert problem_kind(EmptyMaskError("x")) == "empty-mask"
    assert problem_kind(JobTooLargeError("x")) == "job-too-large"
    from skelprune.budget import JobTooLargeError as ServiceJobTooLarge

    assert ServiceJobTooLarge is JobTooLargeError


def test_the_default_budget_is_the_services() -> None:
    from service.settings import Settings

    settings = Settings()
    budget = DATASET_LIMITS
    assert budget.memory_mb == settings.job_memory_mb
    assert budget.seconds == settings.job_timeout
    assert budget.max_pixels == settings.max_pixels
    assert budget.max_vertices == settings.max_vertices


def test_import_skelprune_and_help_load_no_dask() -> None:
    code = (
        "import sys, skelprune, skelprune.parallel\n"
        "from skelprune.cli import app\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in ('dask', 'distributed')))"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert run.stdout.strip() == "[]", run.stderr
    help_ = subprocess.run(
        [*CLI, "prune-many", "--help"], capture_output=True, text=True, timeout=60
    )
    assert help_.returncode == 0 and "--scheduler" in help_.stdout and "--jobs" in help_.stdout


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--jobs", "2", "--scheduler", "tcp://127.0.0.1:1"], "not both"),
        (["--jobs", "0"], "--jobs must be >= 1"),
        (["--beta", "-1"], "beta must be"),
    ],
)
def test_usage_errors_are_one_line_and_status_2(tmp_path: Path, args, message) -> None:
    run = subprocess.run(
        [*CLI, "prune-many", str(tmp_path), "--out", str(tmp_path / "out"), *args],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert run.returncode == 2 and message in run.stderr
    assert len(run.stderr.strip().splitlines()) == 1


def test_no_input_and_an_unreachable_scheduler_are_named(tmp_path: Path) -> None:
    run = subprocess.run(
        [*CLI, "prune-many", str(tmp_path / "*.png"), "--out", str(tmp_path / "out")],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert run.returncode == 2 and "no input given" in run.stderr
    (tmp_path / "a.png").write_bytes(b"")
    unreachable = ["--scheduler", "tcp://127.0.0.1:9"]
    run = subprocess.run(
        [*CLI, "prune-many", str(tmp_path), "--out", str(tmp_path / "out"), *unreachable],
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, "DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT": "3s"},
    )
    assert run.returncode == 2 and "error: the Dask cluster" in run.stderr, run.stderr
