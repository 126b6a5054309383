"""Large networks: ``scope="local"`` on drawn road, vessel and crack networks.

``python -m benchmarks networks`` (sizes from ``SKELPRUNE_NETWORK_SIZES``, default
``4096,8192``). Each run is a fresh process, fed the mask (cleaned as a network needs:
``fill_holes=64``, ``min_area=64``), so that its peak resident memory is the pruning's:

- ``local ×1``: the windows one after the other in one process;
- ``local ×2``: on a local Dask cluster of two single-threaded workers (started and
  warmed before the clock starts); the memory is the largest worker's peak;
- ``global``: the paper's scope, at the smallest size only (for comparison).

Columns: time (s); peak resident memory (MiB) of the process, and of its largest worker
where there are workers; road pixels; time per million road pixels; dead ends found of the
drawing's true ones; roads running off the image kept; components; loops (the cycle rank
of the answer's graphs). One run each (the 8k runs take a minute on a shared machine).

A second table: the pruning of one window alone, by window size, its peak memory over
the process's baseline: the bound per megapixel of window.
"""

from __future__ import annotations

import json
import os
import pickle
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.common import table

SIZES = tuple(int(s) for s in os.environ.get("SKELPRUNE_NETWORK_SIZES", "4096,8192").split(","))
KINDS = ("road", "vessel", "crack")
CLEAN = {"fill_holes": 64, "min_area": 64}


def _reset_peak() -> None:
    """Start the peak resident memory (VmHWM) over from now (Linux)."""
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")


def _rss_mib() -> float:
    """Peak resident memory since the last reset (VmHWM), MiB."""
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    return float("nan")


def _counts(res: Any, net: Any) -> dict[str, int]:
    from testkit.networks import truth_counts

    rows: list[np.ndarray] = []
    cols: list[np.ndarray] = []
    er: list[np.ndarray] = []
    ec: list[np.ndarray] = []
    loops = 0
    for comp in res.components:
        r, c, _ = comp.points()
        rows.append(r)
        cols.append(c)
        t = comp.table
        p = t.node_point[np.array(t.kinds(), dtype=object) == "endpoint"]
        er.append(t.y[p])
        ec.append(t.x[p])
        loops += max(0, t.n_branches - t.n_nodes + 1)
    out = truth_counts(
        net, np.concatenate(rows), np.concatenate(cols), np.concatenate(er), np.concatenate(ec)
    )
    out["components"] = len(res.components)
    out["loops"] = loops
    return out


def child(path: str, mode: str) -> dict[str, Any]:
    """One measured run (in its own process)."""
    import time

    import skelprune
    from skelprune.io.input import read_input
    from skelprune.local import prune_local
    from skelprune.options import PruneOptions, ReadOptions

    with open(path, "rb") as f:
        net = pickle.load(f)
    warm = np.zeros((300, 300), bool)
    warm[100:120, 5:295] = warm[5:295, 100:120] = True
    skelprune.prune(warm, scope="local", window=128)  # kernels loaded
    _reset_peak()
    out: dict[str, Any] = {"baseline_mib": _rss_mib()}
    if mode == "global":
        t = time.perf_counter()
        res = skelprune.prune(net.mask, **CLEAN)
        out["seconds"] = time.perf_counter() - t
    elif mode == "local1":
        t = time.perf_counter()
        res = skelprune.prune(net.mask, scope="local", **CLEAN)
        out["seconds"] = time.perf_counter() - t
    else:
        from dask.distributed import Client, LocalCluster

        with (
            LocalCluster(n_workers=2, threads_per_worker=1, processes=True) as cluster,
            Client(cluster) as client,
        ):
            client.run(lambda: skelprune.prune(np.pad(np.ones((40, 40), bool), 2), scope="local"))
            client.run(_reset_peak)
            t = time.perf_counter()
            shape = read_input(net.mask, read=ReadOptions(**CLEAN))
            res = prune_local(shape, PruneOptions(scope="local").resolved(), client=client)
            out["seconds"] = time.perf_counter() - t
            out["worker_mib"] = max(client.run(_rss_mib).values())
    out["peak_mib"] = _rss_mib()
    out["window"] = res.options.window
    out.update(_counts(res, net))
    return out


def window_child(path: str, side: int) -> dict[str, Any]:
    """One window of ``side`` px (its extent: side + 2 halo) pruned alone."""
    from skelprune.local import prune_window
    from skelprune.options import LOCAL_HALO_FRACTION, PruneOptions

    with open(path, "rb") as f:
        net = pickle.load(f)
    import skelprune

    warm = np.zeros((300, 300), bool)
    warm[100:120, 5:295] = warm[5:295, 100:120] = True
    skelprune.prune(warm)
    halo = int(side * LOCAL_HALO_FRACTION)
    ext = side + 2 * halo
    sub = np.ascontiguousarray(net.mask[:ext, :ext])
    del net
    _reset_peak()
    base = _rss_mib()
    prune_window(sub, (0, 0), (halo, halo + side, halo, halo + side), PruneOptions().resolved())
    return {"extent_mpx": sub.size / 1e6, "delta_mib": _rss_mib() - base}


def _run(args: list[str]) -> dict[str, Any]:
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1])}
    out = subprocess.run(
        [sys.executable, "-m", "benchmarks.bench_networks", *args],
        capture_output=True,
        text=True,
        env=env,
        check=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])  # type: ignore[no-any-return]


def main() -> None:
    from testkit.networks import network

    rows = []
    wrows = []
    with tempfile.TemporaryDirectory() as tmp:
        for size in SIZES:
            for kind in KINDS:
                net = network(kind, size, seed=1)
                path = str(Path(tmp) / f"{kind}{size}.pickle")
                with open(path, "wb") as f:
                    pickle.dump(net, f)
                road = net.road_pixels
                del net
                modes = ["local1", "local2"] + (["global"] if size == SIZES[0] else [])
                for mode in modes:
                    r = _run(["--child", path, mode])
                    rows.append(
                        [
                            f"{kind} {size}",
                            {"local1": "local ×1", "local2": "local ×2", "global": "global"}[mode],
                            r["window"] or "-",
                            round(r["seconds"], 1),
                            round(r["peak_mib"]),
                            round(r.get("worker_mib", 0)) or "-",
                            f"{road / 1e6:.2f}M",
                            round(r["seconds"] / (road / 1e6), 2),
                            f"{r['dead_ends_found']}/{r['dead_ends']}",
                            f"{r['border_roads_kept']}/{r['border_roads']}",
                            r["components"],
                            r["loops"],
                        ]
                    )
                    print(rows[-1], flush=True)
                if kind == "road" and size == SIZES[-1]:
                    for side in (512, 1024, 2048):
                        w = _run(["--window", path, str(side)])
                        wrows.append(
                            [
                                side,
                                round(w["extent_mpx"], 2),
                                round(w["delta_mib"]),
                                round(w["delta_mib"] / w["extent_mpx"]),
                            ]
                        )
    print(
        table(
            [
                "network",
                "scope",
                "window",
                "s",
                "peak MiB",
                "worker MiB",
                "road px",
                "s / road Mpx",
                "dead ends",
                "border roads",
                "components",
                "loops",
            ],
            rows,
        )
    )
    print()
    print(table(["window", "extent Mpx", "peak over baseline MiB", "MiB / Mpx"], wrows))


if __name__ == "__main__":
    if sys.argv[1:2] == ["--child"]:
        print(json.dumps(child(sys.argv[2], sys.argv[3])))
    elif sys.argv[1:2] == ["--window"]:
        print(json.dumps(window_child(sys.argv[2], int(sys.argv[3]))))
    else:
        main()
