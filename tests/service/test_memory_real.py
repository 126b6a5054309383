"""What bounds a job's memory, against the real server: the worker's resident set.

Large ordinary shapes answer 200 one after another, and small ones after them; a
polygon whose libraries reserve gigabytes of address space (and touch little of it)
is answered too. The worker is never refused for virtual memory it does not use.
"""

from __future__ import annotations

import io
import math
from collections.abc import Iterator
from pathlib import Path

import httpx
import numpy as np
import pytest
from PIL import Image

from testkit.realserver import running_server

pytestmark = pytest.mark.timeout(600)

#: Room for a 2048² silhouette (about 450 MiB at its peak, the worker's own included),
#: little more.
BUDGET_MB = 800


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[str, Path]]:
    log = tmp_path_factory.mktemp("memory") / "server.log"
    with running_server(
        log, workers="1", job_memory_mb=str(BUDGET_MB), job_timeout="120", access_log="false"
    ) as (_, base):
        yield base, log


def png(mask: np.ndarray) -> bytes:
    buf = io.BytesIO()
    Image.fromarray(mask.astype(np.uint8) * 255).save(buf, "PNG")
    return buf.getvalue()


def disk(n: int) -> np.ndarray:
    yy, xx = np.mgrid[:n, :n]
    c = (n - 1) / 2
    return (yy - c) ** 2 + (xx - c) ** 2 <= (n / 2 - 2) ** 2


def square(n: int) -> np.ndarray:
    mask = np.zeros((n, n), bool)
    mask[2:-2, 2:-2] = True
    return mask


def ellipse(n: int) -> np.ndarray:
    yy, xx = np.mgrid[:n, :n]
    c = (n - 1) / 2
    return ((yy - c) / (n / 2 - 2)) ** 2 + ((xx - c) / (n / 3)) ** 2 <= 1


def circle_polygon(vertices: int) -> dict[str, object]:
    ring = [
        [1000 * math.cos(2 * math.pi * k / vertices), 1000 * math.sin(2 * math.pi * k / vertices)]
        for k in range(vertices)
    ]
    return {"type": "Polygon", "coordinates": [[*ring, ring[0]]]}


def test_large_ordinary_shapes_in_a_row_then_small_ones_all_answer(
    server: tuple[str, Path],
) -> None:
    base, log = server
    client = httpx.Client(base_url=base, timeout=300)
    large = [png(make(2048)) for make in (disk, square, ellipse)]
    statuses = []
    for body in large * 2:
        r = client.post("/v1/prune", content=body, headers={"content-type": "image/png"})
        statuses.append((r.status_code, r.text[:200] if r.status_code != 200 else ""))
    r = client.post("/v1/prune", json=circle_polygon(31_000))
    statuses.append((r.status_code, r.text[:200] if r.status_code != 200 else ""))
    for n in (64, 256):
        r = client.post("/v1/prune", content=png(disk(n)), headers={"content-type": "image/png"})
        statuses.append((r.status_code, r.text[:200] if r.status_code != 200 else ""))
    r = client.post("/v1/prune", json=circle_polygon(40))
    statuses.append((r.status_code, r.text[:200] if r.status_code != 200 else ""))
    assert statuses == [(200, "")] * len(statuses), statuses
    assert "MemoryError" not in log.read_text()
