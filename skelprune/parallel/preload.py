"""Imported once by the forkserver a local cluster's workers are forked from
(:func:`skelprune.parallel.run.forked_workers`): dask's worker, the library and the
numba kernels a mask's pruning uses, loaded once for all the workers instead of once in
each. Nothing here may fail: the workers are forked all the same, and load what is
missing on their first input."""

from __future__ import annotations

import contextlib


def load() -> None:
    """Import what a worker runs and prune a small mask: its kernels loaded."""
    import distributed.nanny  # noqa: F401  (what a worker process runs)
    import numpy as np

    from ..api import prune
    from ..output.encode import encode
    from . import work  # noqa: F401  (the tasks' own module)

    mask = np.zeros((24, 32), dtype=bool)
    mask[4:20, 4:28] = True
    mask[10:14, 12:20] = False  # a hole: the loops' code paths
    mask[3, 6:26:3] = True  # bumps along the rim: spurs the coarse stage removes
    encode(prune(mask, answers=("json",)), "json")


with contextlib.suppress(Exception):
    load()
