"""Digital topology on the voxel grid: the 26-neighbourhood, simple points, step kinds.

The foreground is 26-connected and the background 6-connected. A neighbourhood is a
26-bit code, bit ``i`` set when the voxel at ``OFFSETS[i]`` is foreground; the tests on
it are bit operations on small adjacency masks, so no 2²⁶-entry table is needed.
A voxel is **simple** (Bertrand & Malandain 1994) when exactly one 26-component of the
foreground touches it in its 26-neighbourhood and exactly one 6-component of the
background in its 18-neighbourhood is 6-adjacent to it: deleting it then changes
neither the components, nor the tunnels, nor the cavities.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from numba import njit

__all__ = [
    "OFFSETS",
    "STEP_KINDS",
    "end_point",
    "is_simple",
    "neighbourhood_code",
    "step_kind",
    "step_lengths",
]

#: The 26 neighbour offsets ``(dz, dy, dx)``, in raster order.
OFFSETS = np.array(
    [o for o in itertools.product((-1, 0, 1), repeat=3) if o != (0, 0, 0)], dtype=np.int64
)


def _masks() -> tuple[np.ndarray, np.ndarray, int, int]:
    """26-adjacency within the neighbourhood, 6-adjacency within its 18-neighbourhood,
    the 18-neighbourhood and the six face neighbours, as bit masks."""
    adj26 = np.zeros(26, dtype=np.int64)
    adj6 = np.zeros(26, dtype=np.int64)
    n18 = faces = 0
    for i, a in enumerate(OFFSETS):
        l1 = int(np.abs(a).sum())
        if l1 <= 2:
            n18 |= 1 << i
        if l1 == 1:
            faces |= 1 << i
        for j, b in enumerate(OFFSETS):
            d = np.abs(a - b)
            if i != j and d.max() <= 1:
                adj26[i] |= 1 << j
            if d.sum() == 1 and l1 <= 2 and int(np.abs(b).sum()) <= 2:
                adj6[i] |= 1 << j
    return adj26, adj6, n18, faces


ADJ26, ADJ6, N18, FACES = _masks()

#: The seven kinds of step between 26-neighbours, by which coordinates change:
#: ``kind = 4·|dz| + 2·|dy| + |dx| − 1``.
STEP_KINDS = np.array([((k + 1) >> 2 & 1, (k + 1) >> 1 & 1, (k + 1) & 1) for k in range(7)])


def step_lengths(spacing: tuple[float, float, float]) -> np.ndarray:
    """Physical length of each step kind (:data:`STEP_KINDS`) for ``spacing = (dz, dy, dx)``.

    The one definition of skeleton length in a volume: paths keep integer counts of
    steps of each kind, turned into a length here, so that two implementations that
    make the same removals agree bit for bit.

    >>> step_lengths((3.0, 1.0, 1.0)).round(3).tolist()
    [1.0, 1.0, 1.414, 3.0, 3.162, 3.162, 3.317]
    """
    s = np.asarray(spacing, dtype=np.float64)
    return np.array([math.sqrt(float(((k * s) ** 2).sum())) for k in STEP_KINDS])


@njit(cache=True, inline="always")
def step_kind(dz: int, dy: int, dx: int) -> int:
    """Index in :data:`STEP_KINDS` of the step ``(dz, dy, dx)`` between 26-neighbours."""
    return 4 * abs(dz) + 2 * abs(dy) + abs(dx) - 1


@njit(cache=True, inline="always")
def neighbourhood_code(flat: np.ndarray, p: int, steps: np.ndarray) -> int:
    """26-bit code of the foreground around voxel ``p`` of the flat array ``flat``
    (``steps``: :data:`OFFSETS` as flat offsets)."""
    code = 0
    for i in range(26):
        if flat[p + steps[i]]:
            code |= 1 << i
    return code


@njit(cache=True, inline="always")
def _flood(seed: int, allowed: int, adj: np.ndarray) -> int:
    """The component of ``allowed`` (a bit mask) that contains ``seed``, under ``adj``."""
    comp = seed
    frontier = seed
    while frontier:
        grown = 0
        for i in range(26):
            if frontier >> i & 1:
                grown |= adj[i]
        frontier = grown & allowed & ~comp
        comp |= frontier
    return comp


@njit(cache=True)
def is_simple(code: int, adj26: np.ndarray, adj6: np.ndarray, n18: int, faces: int) -> bool:
    """Whether a voxel with neighbourhood ``code`` is simple for (26, 6) connectivity."""
    if code == 0:
        return False  # an isolated voxel is a component of its own
    first = code & -code
    if _flood(first, code, adj26) != code:
        return False  # two or more foreground components around it
    background = ~code & n18
    open_faces = background & faces
    if open_faces == 0:
        return False  # interior voxel: deleting it makes a cavity
    first = open_faces & -open_faces
    return (open_faces & ~_flood(first, background, adj6)) == 0


@njit(cache=True, inline="always")
def end_point(code: int) -> bool:
    """Whether a voxel with neighbourhood ``code`` has exactly one 26-neighbour."""
    return code != 0 and (code & (code - 1)) == 0
