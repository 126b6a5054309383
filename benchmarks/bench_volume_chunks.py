"""A chunked label volume on a local 2-worker Dask cluster (``volumes --labels --large``).

``python -m benchmarks volumes --labels --large`` writes a ``SKELPRUNE_BENCH_LARGE_SIDE``³
(default 1024) Zarr label volume chunk by chunk, never whole in memory: 256³ tiles of
:func:`testkit.volumes.touching_trees` (300 trees each, every tile its own labels),
``SKELPRUNE_BENCH_LARGE_CHUNK`` voxels a chunk side (default 128). It starts a real local
cluster (:func:`testkit.daskcluster.dask_cluster`, two one-thread workers of
``SKELPRUNE_BENCH_LARGE_MEMORY``, default 2GiB, each) and runs
:func:`skelprune.parallel.volume_chunks.prune_zarr_chunked`, then prints the time, the
components, each worker's peak resident memory against its budget, and whether the
answer on the first tile's labels equals :func:`skelprune.prune` of that tile alone
(labels wholly inside one tile are the same objects in both).
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
import time
from pathlib import Path

import cloudpickle
import numpy as np

from .common import table

SIDE = int(os.environ.get("SKELPRUNE_BENCH_LARGE_SIDE", "1024"))
CHUNK = int(os.environ.get("SKELPRUNE_BENCH_LARGE_CHUNK", "128"))
MEMORY = os.environ.get("SKELPRUNE_BENCH_LARGE_MEMORY", "2GiB")
TILE = 256
TREES = 300


def _peak_mb() -> float:
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


# sent to the workers by value: they cannot import this package
cloudpickle.register_pickle_by_value(sys.modules[__name__])


def write_store(path: Path, side: int = SIDE) -> np.ndarray:
    """The tiled label volume written to ``path``; answers the first tile."""
    import zarr

    from testkit.volumes import touching_trees

    z = zarr.open_array(
        str(path), mode="w", shape=(side,) * 3, chunks=(CHUNK,) * 3, dtype=np.uint32
    )
    first = None
    k = 0
    for a in range(0, side, TILE):
        for b in range(0, side, TILE):
            for c in range(0, side, TILE):
                tile = touching_trees(TREES, TILE, seed=k).labels
                tile[tile != 0] += k * TREES
                z[a : a + TILE, b : b + TILE, c : c + TILE] = tile
                if first is None:
                    first = tile
                k += 1
    assert first is not None
    return first


def main() -> None:
    import skelprune
    from skelprune.parallel.volume_chunks import prune_zarr_chunked
    from testkit.daskcluster import dask_cluster

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "large.zarr"
        t = time.perf_counter()
        first = write_store(path)
        written = time.perf_counter() - t
        with dask_cluster(Path(tmp) / "dask", workers=2, memory_limit=MEMORY) as address:
            from dask.distributed import Client

            with Client(address) as client:
                t = time.perf_counter()
                res = prune_zarr_chunked(path, client)
                seconds = time.perf_counter() - t
                peaks = sorted(client.run(_peak_mb).values())
        alone = skelprune.prune(first)
        inner = {c.label for c in alone.components}
        # labels cut by the tile's faces are cut the same way in the large volume
        got = [c.to_dict() for c in res.components if c.label in inner]
        same = json.dumps(got, sort_keys=True) == json.dumps(
            [c.to_dict() for c in alone.components], sort_keys=True
        )
    rows = [
        [
            f"{SIDE}³, {CHUNK}³ chunks",
            f"{(SIDE // TILE) ** 3 * TREES}",
            len(res.components),
            f"{seconds:.1f}",
            f"{written:.1f}",
            ", ".join(f"{p:.0f}" for p in peaks),
            MEMORY,
            "yes" if same else "NO",
        ]
    ]
    header = ["volume", "labels", "components", "s", "write s", "peak MB a worker"]
    header += ["budget", "first tile = unchunked"]
    print("\nA chunked label volume on a local 2-worker Dask cluster:\n")
    print(table(header, rows))


if __name__ == "__main__":
    main()
