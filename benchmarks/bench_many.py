"""``skelprune prune-many`` on ~300 small masks: 1 worker against 2, and where the time goes.

The data set: kimia216's and kimia99's PNG files (303 masks, 100-156 px across: a few
milliseconds of pruning each), copied into one folder. Three parts, each run for 1 and
for 2 workers, the rounds interleaved (1, 2, 1, 2, ...) so that a slow spell of the
shared machine hits both alike; medians, and the machine's load average at each run:

- **the command, cold**: ``skelprune prune-many IN --out OUT --jobs N`` as a user runs it
  (a local cluster started and closed by the command): wall time, and the CPU time of
  the command and all its processes;
- **its stages**: the same run in a fresh process, through the same code
  (:func:`skelprune.parallel.prune_many` on the local cluster the command starts), each
  stage timed: the client's import of the library and dask; the cluster's start (wall,
  and the CPU time of its processes by then: the workers, and the forkserver they are
  forked from, which loads the library and its kernels once); in the workers, the
  kernels still loaded on a worker's first input (its CPU time past the median input's),
  the pruning itself (read, prune, serialise: CPU time) and what dask costs besides
  (the rest of the workers' CPU time during the run); the client's CPU time during the
  run (the scheduler, which runs in the client's process, receiving, and writing the
  results; the writing apart); the run's wall time from submitting to the last result
  written; and the close;
- **a real Dask cluster** (``dask scheduler`` and N ``dask worker`` processes over TCP, as
  the tests start them): ``skelprune prune-many --scheduler`` on 60 of the masks just
  after the workers start (cold: each worker imports the library and loads its kernels
  in its first task), then on all of them (warm): wall time, and the workers' CPU time.

``python -m benchmarks many`` (about 5 minutes on 2 cores; ``--rounds R``, default 3).
Every output folder is compared with the first one, byte for byte.
"""

from __future__ import annotations

import argparse
import contextlib
import filecmp
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from testkit import DATA

ROUNDS = 3
COLD_INPUTS = 60
CLI = [sys.executable, "-m", "skelprune.cli", "prune-many"]
#: A run's stages in a process of its own (``-c``: no main module for the workers to
#: import): N IN OUT.
_STAGES = (
    "import time; t = time.perf_counter(); import distributed, skelprune.parallel.run; "
    "i = time.perf_counter() - t; import sys, json; from pathlib import Path; "
    "from benchmarks.bench_many import _stages; "
    "print(json.dumps(_stages(Path(sys.argv[2]), Path(sys.argv[3]), int(sys.argv[1]), i)))"
)

#: In a worker: the library's import, and each input's CPU time (the first holds the
#: kernels' loading).
_STATS: dict[str, Any] = {"inputs": []}


def timed_batch(batch: list[Any], job: Any) -> list[Any]:
    """:func:`skelprune.parallel.work.run_batch`, each input's CPU time kept."""
    from skelprune.parallel.work import run_batch

    out = []
    for one in batch:
        t = time.process_time()
        out.extend(run_batch([one], job))
        _STATS["inputs"].append(time.process_time() - t)
    return out


def _stats() -> dict[str, Any]:
    stats = dict(_STATS)
    _STATS.update({"inputs": []})
    return stats


def _load() -> float:
    return float(Path("/proc/loadavg").read_text().split()[0])


def _cpu(pids: list[int]) -> float:
    import psutil

    total = 0.0
    for pid in pids:
        with contextlib.suppress(psutil.Error):
            t = psutil.Process(pid).cpu_times()
            total += t.user + t.system
    return total


def write_inputs(folder: Path) -> list[Path]:
    folder.mkdir(parents=True)
    paths = []
    for name in ("kimia216", "kimia99"):
        for src in sorted((DATA / name).glob("*.png")):
            paths.append(folder / f"{name}-{src.name}")
            shutil.copyfile(src, paths[-1])
    return paths


def _same(a: Path, b: Path) -> bool:
    """The two output folders hold the same files, byte for byte."""
    names = sorted(p.name for p in a.iterdir())
    if names != sorted(p.name for p in b.iterdir()):
        return False
    _, mismatch, errors = filecmp.cmpfiles(a, b, names, shallow=False)
    return not mismatch and not errors


def command(inputs: Path, out: Path, *args: str, env: dict[str, str] | None = None) -> dict:
    """The command's wall time and the CPU time of it and all its processes (sampled
    every 20 ms: a process's last few milliseconds are missed)."""
    import psutil

    load = _load()
    t = time.perf_counter()
    proc = subprocess.Popen(
        [*CLI, str(inputs), "--out", str(out), *args],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        env=env,
    )
    cpu: dict[int, float] = {}
    root = psutil.Process(proc.pid)
    while proc.poll() is None:
        with contextlib.suppress(psutil.Error):
            for p in [root, *root.children(recursive=True)]:
                with contextlib.suppress(psutil.Error):
                    c = p.cpu_times()
                    cpu[p.pid] = c.user + c.system
        time.sleep(0.02)
    wall = time.perf_counter() - t
    if proc.returncode:
        raise RuntimeError(f"prune-many {args} exited with {proc.returncode}")
    return {"wall": wall, "cpu": sum(cpu.values()), "load": load}


def _children_cpu() -> float:
    """CPU time of this process's child processes, all of them (the workers, and the
    forkserver they are forked from)."""
    import psutil

    return _cpu([p.pid for p in psutil.Process().children(recursive=True)])


def stages(inputs: Path, out: Path, n: int) -> dict[str, float]:
    """One run of prune_many on the local cluster the command starts, stage by stage, in
    a fresh process (as the command's)."""
    code = [sys.executable, "-c", _STAGES, str(n), str(inputs), str(out)]
    load = _load()
    done = subprocess.run(code, check=True, capture_output=True, text=True)
    return {"load": load, **json.loads(done.stdout.strip().splitlines()[-1])}


def _stages(inputs: Path, out: Path, n: int, imported: float) -> dict[str, float]:
    from skelprune.limits import DATASET_LIMITS
    from skelprune.parallel import run

    writing = [0.0]
    batch, record = run.run_batch, run._record

    def timed_record(*args: Any) -> Any:
        t = time.process_time()
        try:
            return record(*args)
        finally:
            writing[0] += time.process_time() - t

    t = time.perf_counter()
    with run._client(None, n, DATASET_LIMITS) as client:
        started = time.perf_counter() - t
        start_cpu = _children_cpu()
        run.run_batch, run._record = timed_batch, timed_record
        try:
            c, w = time.process_time(), time.perf_counter()
            run.prune_many(inputs, client=client, out=out)
            wall, client_cpu = time.perf_counter() - w, time.process_time() - c
        finally:
            run.run_batch, run._record = batch, record
        worker_cpu = _children_cpu() - start_cpu
        per_worker = list(client.run(_stats).values())
        t = time.perf_counter()
    closed = time.perf_counter() - t
    kernels = sum(s["inputs"][0] - statistics.median(s["inputs"]) for s in per_worker)
    pruning = sum(sum(s["inputs"]) for s in per_worker) - kernels
    return {
        "import": imported,
        "start": started,
        "start cpu": start_cpu,
        "kernels": kernels,
        "pruning": pruning,
        "dask": worker_cpu - kernels - pruning,
        "client": client_cpu,
        "writing": writing[0],
        "run": wall,
        "close": closed,
    }


def real_cluster(inputs: Path, few: Path, work: Path, n: int, r: int) -> dict[str, float]:
    from distributed import Client

    from testkit.daskcluster import dask_cluster

    with dask_cluster(work / f"dask-{r}-{n}", workers=n) as address:
        with Client(address) as client:
            pids = list(client.run(os.getpid).values())
        cpu0 = _cpu(pids)
        cold = command(few, work / f"cold-{r}-{n}", "--scheduler", address)
        cpu1 = _cpu(pids)
        warm = command(inputs, work / f"warm-{r}-{n}", "--scheduler", address)
        cpu2 = _cpu(pids)
    return {
        "cold": cold["wall"],
        "cold cpu": cpu1 - cpu0,
        "warm": warm["wall"],
        "warm cpu": cpu2 - cpu1,
        "load": warm["load"],
    }


def _med(runs: list[dict[str, float]], key: str) -> float:
    return statistics.median(r[key] for r in runs)


def _loads(runs: list[dict[str, float]]) -> str:
    return " ".join(f"{r['load']:.1f}" for r in runs)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m benchmarks many")
    parser.add_argument("--rounds", type=int, default=ROUNDS)
    args = parser.parse_args(argv or [])
    work = Path(tempfile.mkdtemp(prefix="bench-many-"))
    try:
        paths = write_inputs(work / "in")
        few = work / "few"
        few.mkdir()
        for p in paths[:: len(paths) // COLD_INPUTS][:COLD_INPUTS]:
            shutil.copyfile(p, few / p.name)
        results: dict[str, dict[int, list[dict[str, float]]]] = {
            k: {1: [], 2: []} for k in ("command", "stages", "real")
        }
        first: Path | None = None
        same = True
        for r in range(args.rounds):
            for n in (1, 2):
                out = work / f"command-{r}-{n}"
                results["command"][n].append(command(work / "in", out, "--jobs", str(n)))
                results["stages"][n].append(stages(work / "in", work / f"stages-{r}-{n}", n))
                results["real"][n].append(real_cluster(work / "in", few, work, n, r))
                for o in (out, work / f"stages-{r}-{n}", work / f"warm-{r}-{n}"):
                    first = first or o
                    same = same and _same(first, o)
                    if o != first:
                        shutil.rmtree(o)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    report(results, len(paths), args.rounds, same)


def report(
    results: dict[str, dict[int, list[dict[str, float]]]], count: int, rounds: int, same: bool
) -> None:
    from .common import table

    cmd, st, real = results["command"], results["stages"], results["real"]

    def row(
        label: str, data: dict[int, list[dict[str, float]]], key: str, ratio: bool
    ) -> list[str]:
        one, two = _med(data[1], key), _med(data[2], key)
        return [label, f"{one:.2f}", f"{two:.2f}", f"{one / two:.2f}x" if ratio else ""]

    print(f"{count} masks (kimia216 + kimia99 PNGs); medians of {rounds} interleaved rounds")
    print()
    rows = [
        row("command, cold: wall s", cmd, "wall", True),
        row("command, cold: CPU s, all processes", cmd, "cpu", False),
        row("stages: the client's import of the library and dask, wall s", st, "import", False),
        row("stages: cluster start, wall s", st, "start", False),
        row("stages: CPU s of the cluster's processes at start", st, "start cpu", False),
        row("stages: kernel loading in the workers, CPU s", st, "kernels", False),
        row("stages: pruning (read, prune, serialise), CPU s", st, "pruning", False),
        row("stages: dask on the workers besides, CPU s", st, "dask", False),
        row("stages: client CPU s (scheduler, receiving, writing)", st, "client", False),
        row("stages: of which writing the results, CPU s", st, "writing", False),
        row("stages: run, submit to last result, wall s", st, "run", True),
        row("stages: close, wall s", st, "close", False),
        row(f"real cluster: {COLD_INPUTS} inputs cold, wall s", real, "cold", True),
        row(f"real cluster: {COLD_INPUTS} inputs cold, workers' CPU s", real, "cold cpu", False),
        row(f"real cluster: {count} inputs warm, wall s", real, "warm", True),
        row(f"real cluster: {count} inputs warm, workers' CPU s", real, "warm cpu", False),
    ]
    print(table(["", "1 worker", "2 workers", "1 / 2"], rows))
    print()
    for name, data in (("command", cmd), ("stages", st), ("real cluster", real)):
        print(
            f"load average at each run, {name}: 1 worker {_loads(data[1])}; "
            f"2 workers {_loads(data[2])}"
        )
    print(f"cores: {len(os.sched_getaffinity(0))} usable, {os.cpu_count()} in the machine")
    print("every output folder byte for byte the same:", "yes" if same else "NO")
