"""Cold start: how soon a new process or server answers, and what a generic CPU target costs.

Every figure is a fresh process, started the way a user starts it, with the kernels
compiled ahead as ``make setup`` leaves them (numba's cache next to the sources):

- ``python -m service`` (2 workers): seconds from the start to the port answering
  ``/healthz``, to ``/readyz`` 200, and to the first ``POST /v1/prune`` answered 200;
  and on a port already in use, to its exit;
- a fresh ``python`` process: ``import skelprune`` and its first ``prune()`` of a kimia
  shape (what a script or a notebook meets);
- with an empty numba cache: the compile a first start would pay (``python -m
  service.compile``), which ``make setup`` and the image build do ahead;
- the kernels built for ``NUMBA_CPU_NAME=generic`` (what the image ships, valid on any
  x86-64 host) against the host CPU's: the pipeline on kimia216 and the medial axis of a
  2048-px disk, the two targets alternating process by process.

``python -m benchmarks coldstart`` (about two minutes, most of it the compile).
"""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import tempfile
import time

import httpx
import numpy as np

from testkit import REPO

from .common import DATA, table

ROUNDS = 3
PNG = (DATA / "kimia216" / "bird-2.png").read_bytes()

FIRST_PRUNE = """
import time
t0 = time.perf_counter()
import numpy as np
from PIL import Image
import skelprune
t1 = time.perf_counter()
mask = np.asarray(Image.open({path!r})) > 0
skelprune.prune(mask).to_dict()
t2 = time.perf_counter()
print(t1 - t0, t2 - t1)
"""

# Pipeline on kimia216 (median ms a shape, best of 3) and the medial axis of a 2048-px disk.
RUN_TIME = """
import json, time
import numpy as np
import skelprune
from benchmarks.common import dataset
from skelprune.grid.medial_axis import medial_axis
masks = dataset("kimia216")
skelprune.prune(masks[0])
best = []
for m in masks:
    ts = []
    for _ in range(3):
        t = time.perf_counter(); skelprune.prune(m).to_dict(); ts.append(time.perf_counter() - t)
    best.append(min(ts))
yy, xx = np.mgrid[:2052, :2052]
disk = (yy - 1025.5) ** 2 + (xx - 1025.5) ** 2 < 1024 ** 2
t = time.perf_counter(); medial_axis(disk); axis = time.perf_counter() - t
print(json.dumps([1000 * float(np.median(best)), axis]))
"""


def _env(**extra: str) -> dict[str, str]:
    env = {**os.environ, "OMP_NUM_THREADS": "1", "NUMBA_NUM_THREADS": "1", **extra}
    for key in ("NUMBA_CACHE_DIR", "NUMBA_CPU_NAME", "NUMBA_CPU_FEATURES"):
        if key not in extra:
            env.pop(key, None)
    return env


def _python(code: str, **extra: str) -> str:
    return subprocess.run(
        [sys.executable, "-c", code],
        cwd=REPO,
        env=_env(**extra),
        capture_output=True,
        text=True,
        check=True,
    ).stdout


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _server_times() -> tuple[float, float, float]:
    """Seconds to /healthz, to /readyz 200, to the first prune answered 200."""
    port = _free_port()
    base = f"http://127.0.0.1:{port}"
    t0 = time.monotonic()
    proc = subprocess.Popen(
        [sys.executable, "-m", "service"],
        cwd=REPO,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        env=_env(
            SKELPRUNE_HOST="127.0.0.1",
            SKELPRUNE_PORT=str(port),
            SKELPRUNE_WORKERS="2",
            SKELPRUNE_LOG_LEVEL="warning",
        ),
    )
    health = ready = None
    try:
        while time.monotonic() - t0 < 600:
            try:
                if health is None and httpx.get(f"{base}/healthz", timeout=5).status_code == 200:
                    health = time.monotonic() - t0
                if (
                    health is not None
                    and ready is None
                    and httpx.get(f"{base}/readyz", timeout=5).status_code == 200
                ):
                    ready = time.monotonic() - t0
                if health is not None:
                    r = httpx.post(
                        f"{base}/v1/prune",
                        content=PNG,
                        timeout=60,
                        headers={"Content-Type": "image/png"},
                    )
                    if r.status_code == 200:
                        return health, ready or time.monotonic() - t0, time.monotonic() - t0
            except httpx.TransportError:
                pass
            time.sleep(0.02)
        raise RuntimeError("the server did not answer within 600 s")
    finally:
        proc.terminate()
        proc.wait(60)


def _port_in_use() -> float:
    """Seconds until ``python -m service`` on a port already taken has exited."""
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        t0 = time.monotonic()
        proc = subprocess.run(
            [sys.executable, "-m", "service"],
            cwd=REPO,
            capture_output=True,
            check=False,
            env=_env(SKELPRUNE_HOST="127.0.0.1", SKELPRUNE_PORT=str(taken.getsockname()[1])),
        )
        assert proc.returncode == 1, proc.stderr
        return time.monotonic() - t0


def main() -> None:
    rows = []
    busy = [_port_in_use() for _ in range(ROUNDS)]
    rows.append(
        [
            "`python -m service` on a port in use: exited (code 1)",
            f"{np.median(busy):.2f}",
            f"{min(busy):.2f}–{max(busy):.2f}",
        ]
    )
    server = [_server_times() for _ in range(ROUNDS)]
    for i, name in enumerate(("/healthz 200", "/readyz 200", "first POST /v1/prune 200")):
        values = [s[i] for s in server]
        rows.append(
            [
                f"`python -m service`, 2 workers: {name}",
                f"{np.median(values):.2f}",
                f"{min(values):.2f}–{max(values):.2f}",
            ]
        )
    bird = str(DATA / "kimia216" / "bird-2.png")
    fresh = [
        tuple(map(float, _python(FIRST_PRUNE.format(path=bird)).split())) for _ in range(ROUNDS)
    ]
    steps = ("imports (numpy, PIL, skelprune)", "then its first `prune()` (bird-2)")
    for i, name in enumerate(steps):
        values = [f[i] for f in fresh]
        rows.append(
            [
                f"fresh process: {name}",
                f"{np.median(values):.2f}",
                f"{min(values):.2f}–{max(values):.2f}",
            ]
        )
    with tempfile.TemporaryDirectory() as generic:
        t = time.monotonic()
        _python(
            "from service.compile import main; main()",
            NUMBA_CACHE_DIR=generic,
            NUMBA_CPU_NAME="generic",
        )
        compile_s = time.monotonic() - t
        rows.append(
            [
                "empty cache: `python -m service.compile` (generic target)",
                f"{compile_s:.1f}",
                "one run",
            ]
        )
        print(table(["what (fresh processes)", "seconds, median", f"range of {ROUNDS}"], rows))
        host, gen = [], []
        for _ in range(ROUNDS):  # alternating, so that a slow spell hits both
            host.append(json.loads(_python(RUN_TIME)))
            gen.append(
                json.loads(_python(RUN_TIME, NUMBA_CACHE_DIR=generic, NUMBA_CPU_NAME="generic"))
            )
    h, g = np.median(host, axis=0), np.median(gen, axis=0)
    print()
    print(
        table(
            [
                "numba target",
                "kimia216 pipeline, median ms a shape",
                "medial axis, 2048-px disk, s",
            ],
            [
                ["host CPU (`make setup`)", f"{h[0]:.2f}", f"{h[1]:.2f}"],
                ["generic x86-64 (the image)", f"{g[0]:.2f}", f"{g[1]:.2f}"],
                ["generic / host", f"{g[0] / h[0]:.2f}×", f"{g[1] / h[1]:.2f}×"],
            ],
        )
    )
