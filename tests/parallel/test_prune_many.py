"""``prune_many`` and ``skelprune prune-many`` on a real Dask cluster: a ``dask scheduler``
and two ``dask worker`` processes over TCP on 127.0.0.1 (once for the module), and a
local cluster of processes, against a plain library loop, byte for byte."""

from __future__ import annotations

import ast
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import skelprune
from skelprune.limits import Limits
from skelprune.parallel import PROBLEMS_FILE, Labels, prune_many
from testkit import REPO
from testkit.daskcluster import dask_cluster
from testkit.shapes import dataset

pytestmark = [pytest.mark.slow, pytest.mark.timeout(600)]

CLI = [sys.executable, "-m", "skelprune.cli"]


@pytest.fixture(scope="module")
def scheduler(tmp_path_factory: pytest.TempPathFactory):
    """The address of a scheduler with two one-thread workers, all on 127.0.0.1."""
    with dask_cluster(tmp_path_factory.mktemp("dask"), workers=2) as address:
        yield address


def blob(rng: np.random.Generator, size: int = 40) -> np.ndarray:
    """A small shape: an ellipse with a bar through it, at random sizes."""
    yy, xx = np.mgrid[:size, :size]
    a, b = rng.uniform(size / 5, size / 2.5, 2)
    mask = ((yy - size / 2) / a) ** 2 + ((xx - size / 2) / b) ** 2 < 1
    r = int(rng.integers(size // 4, size // 2))
    mask[r : r + 3, 2 : size - 2] = True
    return mask


def write_masks(folder: Path, n: int, seed: int = 0, size: int = 40) -> list[Path]:
    folder.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    paths = []
    for i in range(n):
        path = folder / f"m{i:04d}.png"
        Image.fromarray(np.where(blob(rng, size), 0, 255).astype(np.uint8)).save(path)
        paths.append(path)
    return paths


def library_loop(files: list[Path], out: Path) -> None:
    """What a user writes without prune_many: the documented format, by hand."""
    out.mkdir()
    for path in files:
        doc = skelprune.prune(path).to_dict()
        text = json.dumps(doc, separators=(",", ":"), allow_nan=False) + "\n"
        (out / f"{path.stem}.json").write_bytes(text.encode())


def contents(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.glob("*.json"))}


def test_library_loop_local_cluster_tcp_cluster_and_cli_write_the_same_bytes(
    tmp_path: Path, scheduler: str
) -> None:
    inputs = tmp_path / "in"
    inputs.mkdir()
    for p in [*dataset("kimia216")[:12], REPO / "examples" / "shape.geojson"]:
        (inputs / p.name).write_bytes(p.read_bytes())
    files = sorted(inputs.iterdir())
    library_loop(files, tmp_path / "loop")
    local = prune_many(inputs, out=tmp_path / "local", jobs=2)
    tcp = prune_many(str(inputs / "*"), out=tmp_path / "tcp", client=scheduler, batch_size=3)
    cli = subprocess.run(
        [*CLI, "prune-many", str(inputs), "--out", str(tmp_path / "cli"), "--scheduler", scheduler],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert cli.returncode == 0, cli.stderr
    assert f"done {len(files)}, failed 0, skipped 0 of {len(files)}" in cli.stderr
    expected = contents(tmp_path / "loop")
    assert len(expected) == len(files)
    for name in ("local", "tcp", "cli"):
        assert contents(tmp_path / name) == expected, name
    assert {o.status for o in local + tcp} == {"done"}
    # nothing failed: the problems file is there, and empty
    assert (tmp_path / "cli" / PROBLEMS_FILE).read_bytes() == b""


def test_a_relative_folder_is_read_by_workers_started_elsewhere(
    tmp_path: Path, scheduler: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The cluster's workers run in the folder they were started in, not the caller's."""
    write_masks(tmp_path / "in", 3)
    monkeypatch.chdir(tmp_path)
    assert Path.cwd() != REPO  # where the workers were started
    outcomes = prune_many("in", client=scheduler, out="out", ordered=True)
    assert [o.status for o in outcomes] == ["done"] * 3, [o.problem for o in outcomes]
    assert sorted(p.name for p in (tmp_path / "out").glob("*.json")) == [
        "m0000.json",
        "m0001.json",
        "m0002.json",
    ]


def test_a_poisoned_input_among_1000_leaves_999_results_and_one_problem(
    tmp_path: Path, scheduler: str
) -> None:
    files = write_masks(tmp_path / "in", 1000, size=24)
    poisoned = files[613]
    poisoned.write_bytes(poisoned.read_bytes()[:60])  # a PNG cut short
    outcomes = prune_many(files, out=tmp_path / "out", client=scheduler, ordered=True)
    assert [o.position for o in outcomes] == list(range(1000))
    assert [o.input for o in outcomes if o.status == "failed"] == ["m0613"]
    written = sorted(p.stem for p in (tmp_path / "out").glob("*.json"))
    assert len(written) == 999 and "m0613" not in written
    lines = (tmp_path / "out" / PROBLEMS_FILE).read_text().splitlines()
    assert len(lines) == 1
    problem = json.loads(lines[0])
    assert problem["input"] == "m0613" and problem["kind"] == "invalid-image"
    assert problem["detail"]


def test_a_run_killed_halfway_finishes_without_redoing_what_was_written(
    tmp_path: Path, scheduler: str
) -> None:
    files = write_masks(tmp_path / "in", 600, seed=1, size=96)
    out = tmp_path / "out"
    argv = [*CLI, "prune-many", str(tmp_path / "in"), "--out", str(out), "--scheduler", scheduler]
    first = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 240
    while len(list(out.glob("*.json"))) < 100:
        assert first.poll() is None, "the run finished before it could be stopped"
        assert time.monotonic() < deadline, "no result within the time limit"
        time.sleep(0.01)
    first.send_signal(signal.SIGKILL)
    first.wait(timeout=30)
    written = {p.name: os.stat(p) for p in out.glob("*.json")}
    assert 100 <= len(written) < len(files), "stopped halfway"
    second = subprocess.run(argv, capture_output=True, text=True, timeout=300)
    assert second.returncode == 0, second.stderr
    done = len(files) - len(written)
    assert f"done {done}, failed 0, skipped {len(written)} of {len(files)}" in second.stderr
    assert len(list(out.glob("*.json"))) == len(files)
    assert not list(out.glob(".*.tmp")), "a half-written document was left"
    for name, before in written.items():  # not written again
        after = os.stat(out / name)
        assert (after.st_ino, after.st_mtime_ns) == (before.st_ino, before.st_mtime_ns), name
    # and what the second run wrote is what an uninterrupted run writes
    for path in files[:: len(files) // 12]:
        doc = json.loads((out / f"{path.stem}.json").read_bytes())
        assert doc == skelprune.prune(path).to_dict()


def test_inputs_over_the_budget_fail_alone_as_job_too_large(scheduler: str) -> None:
    rng = np.random.default_rng(3)
    noise = rng.random((512, 512)) < 0.5  # pixel noise: the costliest kind of mask
    small = blob(rng)
    budget = Limits(seconds=1.0)
    outcomes = prune_many(
        {"small": small, "noise": noise}, client=scheduler, limits=budget, ordered=True
    )
    assert [o.status for o in outcomes] == ["done", "failed"]
    assert outcomes[1].problem["kind"] == "job-too-large"
    assert "time limit of 1 s" in outcomes[1].problem["detail"]
    assert outcomes[0].result == skelprune.prune(small).to_dict()
    too_many = prune_many([small], client=scheduler, limits=Limits(max_pixels=100))
    assert too_many[0].problem["kind"] == "image-too-large"


def test_label_images_give_one_document_an_object_in_the_image_coordinates(
    tmp_path: Path, scheduler: str
) -> None:
    img = np.zeros((60, 90), np.uint16)
    img[5:40, 5:30] = 3
    img[5:40, 30:60] = 700  # touching label 3: never joined to it
    img[45:55, 10:80] = 12
    outcomes = prune_many(
        {"cells": Labels(img)}, client=scheduler, out=tmp_path / "out", batch_size=2
    )
    assert sorted(o.input for o in outcomes) == ["cells-12", "cells-3", "cells-700"]
    for label in (3, 700, 12):
        doc = json.loads((tmp_path / "out" / f"cells-{label}.json").read_bytes())
        alone = skelprune.prune(img == label).to_dict()  # the object alone, full image
        assert len(doc["components"]) == len(alone["components"]) == 1
        got, want = doc["components"][0], alone["components"][0]
        assert [(n["x"], n["y"]) for n in got["skeleton"]["nodes"]] == [
            (n["x"], n["y"]) for n in want["skeleton"]["nodes"]
        ]
        assert got["rer"] == want["rer"] and got["area"] == want["area"]


def test_a_geodataframe_is_a_table_of_rows_resumed_row_by_row(
    tmp_path: Path, scheduler: str
) -> None:
    import geopandas
    from shapely.geometry import Polygon, box

    shapes = [box(0, 0, 100 + 10 * i, 20) for i in range(5)]
    shapes.insert(2, Polygon([(0, 0), (1, 1), (0, 1), (1, 0)]).buffer(0).boundary)  # a line
    frame = geopandas.GeoDataFrame({"name": list("abcdef")}, geometry=shapes, index=range(10, 16))
    out = tmp_path / "out"
    outcomes = prune_many({"lakes": frame}, client=scheduler, out=out, ordered=True)
    assert [o.status for o in outcomes] == ["done", "done", "failed", "done", "done", "done"]
    assert outcomes[2].input == "lakes#2"
    lines = [json.loads(x) for x in (out / "lakes.jsonl").read_text().splitlines()]
    assert sorted(x["row"] for x in lines) == [0, 1, 3, 4, 5]
    for line in lines:
        assert line["index"] == 10 + line["row"]
        assert line["result"] == skelprune.prune(frame.geometry.iloc[line["row"]]).to_geojson()
    problem = json.loads((out / PROBLEMS_FILE).read_text())
    assert problem["input"] == "lakes#2" and problem["kind"] == "invalid-polygon"
    again = prune_many({"lakes": frame}, client=scheduler, out=out, ordered=True)
    assert [o.status for o in again] == ["skipped"] * 2 + ["failed"] + ["skipped"] * 3
    assert len((out / "lakes.jsonl").read_text().splitlines()) == 5
    assert len((out / PROBLEMS_FILE).read_text().splitlines()) == 1  # tried again, not twice


def test_an_input_that_kills_its_worker_fails_alone_as_worker_crashed() -> None:
    """No estimate to stop it (the budget lifted), a worker memory limit it goes over: the
    nanny restarts the worker, and the inputs that shared its task are done all the same."""
    import dask
    from distributed import Client, LocalCluster

    small = blob(np.random.default_rng(5))
    hog = np.zeros((9000, 9000), bool)  # an 81-million-pixel square: far over 700 MiB
    hog[100:-100, 100:-100] = True
    unlimited = Limits(memory_mb=None, seconds=None, max_pixels=None)
    with (
        dask.config.set({"distributed.scheduler.allowed-failures": 0}),
        LocalCluster(
            n_workers=1, threads_per_worker=1, memory_limit="700MiB", dashboard_address=":0"
        ) as cluster,
        Client(cluster) as client,
    ):
        outcomes = prune_many(
            {"a": small, "hog": hog, "b": small},
            client=client,
            limits=unlimited,
            batch_size=3,
            ordered=True,
        )
    assert [o.status for o in outcomes] == ["done", "failed", "done"]
    assert outcomes[1].problem["kind"] == "worker-crashed"
    assert outcomes[0].result == outcomes[2].result == skelprune.prune(small).to_dict()


def test_a_local_clusters_workers_start_with_the_kernels_loaded() -> None:
    """Forked from one process that loaded them: no worker loads the library's numba
    kernels again on its first input (about 1.5 s of CPU a worker, for each run). In a
    fresh process, as a run starts: a process whose forkserver already runs (this test
    session's service pools) forks the workers from that one instead."""
    code = (
        "import numpy as np\n"
        "from service.worker.jobs import kernel_counts\n"
        "from skelprune.limits import DATASET_LIMITS\n"
        "from skelprune.parallel import prune_many\n"
        "from skelprune.parallel.run import _client\n"
        "if __name__ == '__main__':\n"
        "    m = np.zeros((20, 40), bool); m[4:16, 4:36] = True\n"
        "    with _client(None, 2, DATASET_LIMITS) as client:\n"
        "        counts = client.run(kernel_counts)  # before any task\n"
        "        outcomes = prune_many({'a': m}, client=client)\n"
        "    print(sorted(counts.values()), outcomes[0].status)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=300, check=True
    )
    counts, status = done.stdout.strip().splitlines()[-1].rsplit(" ", 1)
    pairs = ast.literal_eval(counts)
    assert len(pairs) == 2 and status == "done"
    assert all(loaded > 0 and compiled == 0 for loaded, compiled in pairs), pairs


def test_the_client_imports_none_of_the_pruning_modules(tmp_path: Path) -> None:
    """The client feeds the workers and writes their results: numba, scipy and pandas are
    the workers' to import (about 0.8 s at the start of every run, measured)."""
    write_masks(tmp_path / "in", 3)
    code = (
        "import sys; from skelprune.parallel import prune_many; "
        "outs = prune_many(sys.argv[1], jobs=1, out=sys.argv[2]); "
        "print([o.status for o in outs], [m for m in ('numba', 'scipy', 'pandas') "
        "if m in sys.modules])"
    )
    args = [sys.executable, "-c", code, str(tmp_path / "in"), str(tmp_path / "out")]
    done = subprocess.run(args, capture_output=True, text=True, timeout=300, check=True)
    assert done.stdout.strip().splitlines()[-1] == "['done', 'done', 'done'] []"


def test_a_geoparquet_becomes_a_geoparquet_of_lines_with_the_rows_attributes(
    tmp_path: Path, scheduler: str
) -> None:
    import geopandas
    from shapely.geometry import LineString, box

    from skelprune.parallel.geoparquet import prune_geoparquet

    shapes = [box(0, 0, 60 + i, 12 + i % 7) for i in range(40)]
    shapes[17] = LineString([(0, 0), (5, 5)])  # not a polygon: its row fails alone
    table = geopandas.GeoDataFrame(
        {"name": [f"lake{i}" for i in range(40)], "depth": np.arange(40.0)},
        geometry=shapes,
        crs="EPSG:3857",
        index=range(1000, 1040),
    )
    table.to_parquet(tmp_path / "lakes.parquet")
    out = prune_geoparquet(
        tmp_path / "lakes.parquet", tmp_path / "lines", client=scheduler, npartitions=4
    )
    lines = geopandas.read_parquet(out)
    assert len(list(out.glob("*.parquet"))) == 4
    assert lines.crs == table.crs
    failed = lines[lines["problem"].notna()]
    assert list(failed["source_row"]) == [1017] and failed.geometry.isna().all()
    assert failed["problem"].iloc[0] == "invalid-polygon"
    good = lines[lines["problem"].isna()]
    assert sorted(set(good["source_row"])) == [i for i in range(1000, 1040) if i != 1017]
    for row, group in good.groupby("source_row"):  # the input's attributes, on every line
        assert set(group["name"]) == {f"lake{row - 1000}"}
        assert set(group["depth"]) == {float(row - 1000)}
    for row in (1000, 1021, 1039):
        expected = [
            f["geometry"]["coordinates"]
            for f in skelprune.prune(table.geometry.loc[row]).to_geojson()["features"]
            if f["geometry"]["type"] == "LineString"
        ]
        got = good[good["source_row"] == row].sort_values("branch")
        assert [[list(c) for c in g.coords] for g in got.geometry] == expected


def test_a_geoparquet_becomes_map_lines_with_the_rows_attributes(
    tmp_path: Path, scheduler: str
) -> None:
    import geopandas
    from shapely.geometry import LineString, MultiPolygon, box

    from skelprune.geo import centerlines
    from skelprune.parallel.geoparquet import prune_geoparquet

    shapes = [box(0, 0, 300 + 10 * i, 40 + i % 5) for i in range(12)]
    shapes[3] = MultiPolygon([box(0, 0, 300, 40), box(400, 0, 404, 4)])  # and an islet
    shapes[7] = LineString([(0, 0), (5, 5)])  # not a polygon: its row fails alone
    table = geopandas.GeoDataFrame(
        {"name": [f"lake{i}" for i in range(12)], "depth": np.arange(12.0)},
        geometry=shapes,
        crs="EPSG:32633",
        index=range(500, 512),
    )
    table.to_parquet(tmp_path / "lakes.parquet")
    out = prune_geoparquet(
        tmp_path / "lakes.parquet", tmp_path / "lines", client=scheduler, npartitions=3,
        lines="map",
    )  # fmt: skip
    lines = geopandas.read_parquet(out).sort_values(["feature", "part"], kind="stable")
    assert len(list(out.glob("*.parquet"))) == 3 and lines.crs == table.crs
    failed = lines[lines["error"].notna()]
    assert list(failed["feature"]) == [507] and failed.geometry.isna().all()
    assert list(failed["name"]) == ["lake7"]
    # the same rows as centerlines of the table in one process
    expected = centerlines(table).sort_values(["feature", "part"], kind="stable")
    assert list(lines["feature"]) == list(expected["feature"])
    assert list(lines["kind"].fillna("-")) == list(expected["kind"].fillna("-"))
    assert list(lines["name"]) == list(expected["name"])
    good = lines["error"].isna().to_numpy()
    assert [g.wkb for g in lines.geometry[good]] == [
        g.wkb for g in expected.geometry[expected["error"].isna().to_numpy()]
    ]
    assert set(lines[lines["feature"] == 503]["part"]) == {0, 1}  # every part a row
    with pytest.raises(skelprune.SkelpruneError, match="lines: 'rivers' is not one of"):
        prune_geoparquet(tmp_path / "lakes.parquet", tmp_path / "x", lines="rivers")
