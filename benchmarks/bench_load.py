"""Load test of a real ``python -m service`` on loopback: throughput, latency, memory.

The script starts its own server (``SKELPRUNE_WORKERS`` = usable cores, a small queue),
then, with an ``httpx.AsyncClient``:

1. warm-up: a few requests of every kind;
2. sustained load: ``--requests`` requests (default 3000) from ``--concurrency`` clients
   (default 8, below workers + queue, so nothing should be refused), a fixed mix of PNG
   bodies, multipart uploads, GeoJSON polygons and bad requests (a truncated PNG, an
   unclosed ring), each checked against the status it must get;
3. overload: ``--overload`` requests (default 600) from more clients than workers +
   queue can hold; the only acceptable refusals are 503s with ``Retry-After``.

It reports throughput, p50/p99 latency, the error count (any answer other than the
expected one; 503 is counted apart and only allowed under overload) and the resident
memory (RSS) of the server process and of its workers before the load, halfway, after
the sustained load and after the overload. Bounded: fixed request counts, a timeout on
every request and a hard cap on the whole run (``--time-cap``, default 300 s); requests
not started by then are skipped and reported.

Run: ``python -m benchmarks load`` or ``python -m benchmarks.bench_load --requests 4000``.
"""

from __future__ import annotations

import argparse
import asyncio
import io
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from collections import Counter
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import httpx
import numpy as np
from PIL import Image

from testkit.realserver import running_server, stop

from .common import DATA

REPO = Path(__file__).resolve().parents[1]
SHAPES = ["bird-10", "elephant-1", "hammer-1", "key-1", "bone-1", "brick-10"]


# ------------------------------------------------------------------------ server
@dataclass
class Server:
    proc: subprocess.Popen[bytes]
    base: str
    workers: int
    queue_size: int


@contextmanager
def server(workers: int, queue_size: int) -> Iterator[Server]:
    """A real ``python -m service`` on a free loopback port; stopped (SIGINT) on exit.

    No API key: the load test measures pruning.
    """
    with (
        tempfile.TemporaryDirectory() as tmp,
        running_server(
            Path(tmp) / "server.log", workers=str(workers), queue_size=str(queue_size)
        ) as (proc, base),
    ):
        yield Server(proc, base, workers, queue_size)
        stop(proc, signal.SIGINT, 60)


def _rss_kib(pid: int) -> int:
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    except OSError:
        pass
    return 0


def _descendants(pid: int) -> list[int]:
    parents: dict[int, int] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            parents[int(entry.name)] = int(stat.rsplit(")", 1)[1].split()[1])
    found: list[int] = []
    frontier = [pid]
    while frontier:
        frontier = [c for c, p in parents.items() if p in frontier]
        found += frontier
    return found


def memory(pid: int) -> tuple[float, float]:
    """(server process RSS, sum of its descendants' RSS) in MiB."""
    return _rss_kib(pid) / 1024, sum(_rss_kib(c) for c in _descendants(pid)) / 1024


# ---------------------------------------------------------------------- requests
def _png(mask: np.ndarray) -> bytes:
    buf = io.BytesIO()
    Image.fromarray(mask.astype(np.uint8) * 255).save(buf, "PNG")
    return buf.getvalue()


@dataclass(frozen=True)
class Req:
    kind: str
    expect: int
    content: bytes | None = None
    files: dict[str, tuple[str, bytes, str]] | None = None
    headers: dict[str, str] = field(default_factory=dict)


def request_mix() -> list[Req]:
    """One cycle of the mix: 20 requests, 2 of them bad on purpose."""
    pngs = [(DATA / "kimia216" / f"{name}.png").read_bytes() for name in SHAPES]
    png_h = {"content-type": "image/png"}
    json_h = {"content-type": "application/json"}
    ring = [[0, 0], [40, 0], [40, 20], [25, 20], [25, 35], [15, 35], [15, 20], [0, 20], [0, 0]]
    poly = json.dumps({"type": "Polygon", "coordinates": [ring]}).encode()
    poly_small = json.dumps(
        {"geojson": {"type": "Polygon", "coordinates": [ring]}, "longest_side": 96, "curve": False}
    ).encode()
    unclosed = json.dumps({"type": "Polygon", "coordinates": [ring[:-1]]}).encode()
    mix: list[Req] = []
    for i in range(12):
        mix.append(Req("png", 200, content=pngs[i % len(pngs)], headers=png_h))
    for i in range(3):
        mix.append(
            Req("multipart", 200, files={"file": ("s.png", pngs[(i + 2) % len(pngs)], "image/png")})
        )
    mix.append(Req("polygon", 200, content=poly_small, headers=json_h))
    mix.append(Req("polygon-512", 200, content=poly, headers=json_h))
    mix.append(
        Req(
            "png-geojson-out",
            200,
            content=_png(np.pad(np.ones((30, 50), bool), 4)),
            headers={**png_h, "accept": "application/geo+json"},
        )
    )
    mix.append(Req("bad-png", 400, content=pngs[0][:100], headers=png_h))
    mix.append(Req("bad-polygon", 422, content=unclosed, headers=json_h))
    return mix


@dataclass
class Tally:
    latencies: list[float] = field(default_factory=list)
    by_kind: dict[str, list[float]] = field(default_factory=dict)
    statuses: Counter[int] = field(default_factory=Counter)
    errors: list[str] = field(default_factory=list)  # unexpected answers / failures
    refused: int = 0  # 503 with Retry-After
    skipped: int = 0  # not started before the time cap
    elapsed: float = 0.0


async def _one(client: httpx.AsyncClient, req: Req, tally: Tally) -> None:
    t = time.perf_counter()
    try:
        resp = await client.post(
            "/v1/prune", content=req.content, files=req.files, headers=req.headers
        )
    except httpx.HTTPError as exc:
        tally.errors.append(f"{req.kind}: {type(exc).__name__}: {exc}")
        return
    took = time.perf_counter() - t
    tally.latencies.append(took)
    tally.by_kind.setdefault(req.kind, []).append(took)
    tally.statuses[resp.status_code] += 1
    if resp.status_code == 503 and "retry-after" in resp.headers:
        tally.refused += 1
    elif resp.status_code != req.expect:
        tally.errors.append(f"{req.kind}: {resp.status_code} {resp.text[:200]}")
    elif resp.status_code >= 400 and resp.headers.get("content-type") != "application/problem+json":
        tally.errors.append(f"{req.kind}: {resp.status_code} without problem+json")


async def drive(base: str, reqs: list[Req], concurrency: int, deadline: float) -> Tally:
    """Send ``reqs`` from ``concurrency`` clients (one connection each) until done or cap."""
    tally = Tally()
    queue: asyncio.Queue[Req] = asyncio.Queue()
    for r in reqs:
        queue.put_nowait(r)
    limits = httpx.Limits(max_connections=concurrency, max_keepalive_connections=concurrency)
    async with httpx.AsyncClient(base_url=base, timeout=120, limits=limits) as client:

        async def worker() -> None:
            while not queue.empty():
                req = queue.get_nowait()
                if time.monotonic() > deadline:
                    tally.skipped += 1
                    continue
                await _one(client, req, tally)

        t = time.perf_counter()
        await asyncio.gather(*(worker() for _ in range(concurrency)))
        tally.elapsed = time.perf_counter() - t
    return tally


# ------------------------------------------------------------------------- report
def _ms(values: list[float], q: float) -> float:
    if not values:
        return float("nan")
    return 1000 * float(np.quantile(values, q))


def run(
    requests: int,
    concurrency: int,
    overload: int,
    overload_concurrency: int,
    queue_size: int,
    time_cap: float,
) -> str:
    workers = max(1, len(os.sched_getaffinity(0)))
    mix = request_mix()
    started = time.monotonic()
    deadline = started + time_cap
    lines: list[str] = []
    with server(workers, queue_size) as srv:
        pid = srv.proc.pid
        warm = asyncio.run(drive(srv.base, mix * 3, concurrency, deadline))
        mem = {"after warm-up": memory(pid)}
        half = requests // 2
        cycle = (mix * (requests // len(mix) + 1))[:requests]
        first = asyncio.run(drive(srv.base, cycle[:half], concurrency, deadline))
        mem["halfway"] = memory(pid)
        second = asyncio.run(drive(srv.base, cycle[half:], concurrency, deadline))
        mem["after sustained load"] = memory(pid)
        burst = (mix * (overload // len(mix) + 1))[:overload]
        over = asyncio.run(drive(srv.base, burst, overload_concurrency, deadline))
        mem["after overload"] = memory(pid)
        ready = httpx.get(f"{srv.base}/readyz", timeout=10)
        restarts = [
            line
            for line in httpx.get(f"{srv.base}/metrics", timeout=10).text.splitlines()
            if line.startswith("skelprune_worker_restarts ")
        ]

    kinds = {
        k: first.by_kind.get(k, []) + second.by_kind.get(k, [])
        for k in dict.fromkeys(r.kind for r in mix)
    }
    sustained = Tally(
        latencies=first.latencies + second.latencies,
        by_kind=kinds,
        statuses=first.statuses + second.statuses,
        errors=first.errors + second.errors,
        refused=first.refused + second.refused,
        skipped=first.skipped + second.skipped,
        elapsed=first.elapsed + second.elapsed,
    )
    total = time.monotonic() - started
    lines.append(
        f"server: {workers} workers, queue {queue_size}; "
        f"{os.cpu_count()} CPUs, load average " + ", ".join(f"{x:.2f}" for x in os.getloadavg())
    )
    lines.append(
        f"mix per 20 requests: 12 PNG bodies ({', '.join(SHAPES)}), 3 multipart, "
        "2 GeoJSON polygons, 1 PNG -> GeoJSON, 1 truncated PNG (400), "
        "1 unclosed ring (422)"
    )
    lines.append("")
    lines.append(
        "| phase | clients | requests | done | req/s | p50 ms | p99 ms | max ms "
        "| errors | 503 | skipped | statuses |"
    )
    lines.append("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name, n, conc, t in (
        ("warm-up", len(mix) * 3, concurrency, warm),
        ("sustained", requests, concurrency, sustained),
        ("overload", overload, overload_concurrency, over),
    ):
        done = len(t.latencies)
        rate = done / t.elapsed if t.elapsed else float("nan")
        statuses = " ".join(f"{k}×{v}" for k, v in sorted(t.statuses.items()))
        lines.append(
            f"| {name} | {conc} | {n} | {done} | {rate:.1f} | "
            f"{_ms(t.latencies, 0.5):.1f} | {_ms(t.latencies, 0.99):.1f} | "
            f"{_ms(t.latencies, 1.0):.1f} | {len(t.errors)} | {t.refused} | "
            f"{t.skipped} | {statuses} |"
        )
    lines.append("")
    lines.append("| sustained, by request kind | n | p50 ms | p99 ms |")
    lines.append("|---|---|---|---|")
    for kind, values in sustained.by_kind.items():
        lines.append(
            f"| {kind} | {len(values)} | {_ms(values, 0.5):.1f} | {_ms(values, 0.99):.1f} |"
        )
    lines.append("")
    lines.append("| memory (RSS, MiB) | server process | workers + fork server |")
    lines.append("|---|---|---|")
    for name, (main_mib, kids_mib) in mem.items():
        lines.append(f"| {name} | {main_mib:.1f} | {kids_mib:.1f} |")
    lines.append("")
    growth = mem["after sustained load"][0] - mem["after warm-up"][0]
    lines.append(
        f"server RSS growth over the sustained load: {growth:+.1f} MiB; "
        f"/readyz after the run: {ready.status_code}; "
        f"{restarts[0] if restarts else 'skelprune_worker_restarts ?'}; "
        f"whole run {total:.0f} s (cap {time_cap:.0f} s)"
    )
    if sustained.refused:
        lines.append(f"NOTE: {sustained.refused} requests refused (503) below the overload level")
    for tally in (warm, sustained, over):
        for err in tally.errors[:5]:
            lines.append(f"error: {err}")
    if any(t.errors for t in (warm, sustained, over)):
        lines.append("RESULT: errors seen")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--requests", type=int, default=3000, help="sustained-load requests")
    p.add_argument("--concurrency", type=int, default=8, help="clients during sustained load")
    p.add_argument("--overload", type=int, default=600, help="requests in the overload burst")
    p.add_argument(
        "--overload-concurrency",
        type=int,
        default=64,
        help="clients during the burst (more than workers + queue)",
    )
    p.add_argument("--queue-size", type=int, default=16, help="SKELPRUNE_QUEUE_SIZE")
    p.add_argument("--time-cap", type=float, default=300.0, help="hard cap on the run, s")
    args = p.parse_args([] if argv is None else argv)
    print(
        run(
            args.requests,
            args.concurrency,
            args.overload,
            args.overload_concurrency,
            args.queue_size,
            args.time_cap,
        ),
        flush=True,
    )


if __name__ == "__main__":
    main(sys.argv[1:])
