"""Digital geometry on the pixel grid: neighbourhoods, simple points, discrete disks.

Shared by the medial axis, the skeleton graph and the reconstruction kernels.
A disk of squared radius ``r2`` centred on a pixel is ``{o : |o|**2 < r2}``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["DEGREE", "NEIGHBOURS", "SIMPLE", "disk_half_width", "find_root", "isqrt"]

# Neighbour order used by every lookup table: clockwise from the top-left.
NEIGHBOURS = np.array(
    [(-1, -1), (-1, 0), (-1, 1), (0, 1), (1, 1), (1, 0), (1, -1), (0, -1)], dtype=np.int64
)


@njit(cache=True, inline="always")
def isqrt(x: int) -> int:
    """Integer square root (floor) of a non-negative integer."""
    s = int(math.sqrt(x))
    while s * s > x:
        s -= 1
    while (s + 1) * (s + 1) <= x:
        s += 1
    return s


@njit(cache=True, inline="always")
def disk_half_width(r2: int, dy: int) -> int:
    """Half width of row ``dy`` of the disk ``dy² + dx² < r2`` (-1 if the row is empty).

    Disk kernels walk rows of the disk, contiguous in memory, instead of a list of
    offsets: the same pixels, several times faster on large radii.
    """
    rest = r2 - 1 - dy * dy
    return isqrt(rest) if rest >= 0 else -1


def _build_tables() -> tuple[np.ndarray, np.ndarray]:
    """Simple-point and degree tables over the 256 neighbourhood configurations."""
    simple = np.zeros(256, dtype=np.bool_)
    degree = np.zeros(256, dtype=np.int64)
    nb = [tuple(v) for v in NEIGHBOURS]
    for code in range(256):
        fg = [i for i in range(8) if code >> i & 1]
        bg = [i for i in range(8) if not code >> i & 1]
        degree[code] = len(fg)

        def components(members: list[int], adjacent) -> list[set[int]]:
            seen: set[int] = set()
            comps = []
            for m in members:
                if m in seen:
                    continue
                stack, comp = [m], {m}
                seen.add(m)
                while stack:
                    a = stack.pop()
                    for b in members:
                        if b not in seen and adjacent(nb[a], nb[b]):
                            seen.add(b)
                            comp.add(b)
                            stack.append(b)
                comps.append(comp)
            return comps

        def adj8(a, b):
            return max(abs(a[0] - b[0]), abs(a[1] - b[1])) == 1

        def adj4(a, b):
            return abs(a[0] - b[0]) + abs(a[1] - b[1]) == 1

        fg_comps = components(fg, adj8)
        # Background components count only where 4-adjacent to the centre pixel.
        bg_comps = [
            c for c in components(bg, adj4) if any(abs(nb[i][0]) + abs(nb[i][1]) == 1 for i in c)
        ]
        simple[code] = len(fg_comps) == 1 and len(bg_comps) == 1
    return simple, degree


SIMPLE, DEGREE = _build_tables()


@njit(cache=True)
def neighbourhood_code(fg: np.ndarray, r: int, c: int) -> int:
    code = 0
    for i in range(8):
        if fg[r + NEIGHBOURS[i, 0], c + NEIGHBOURS[i, 1]]:
            code |= 1 << i
    return code


@njit(cache=True)
def heap_push(heap, size, key):
    i = size
    heap[i] = key
    while i > 0:
        parent = (i - 1) // 2
        if heap[parent] <= heap[i]:
            break
        heap[parent], heap[i] = heap[i], heap[parent]
        i = parent
    return size + 1


@njit(cache=True)
def heap_pop(heap, size):
    top = heap[0]
    size -= 1
    heap[0] = heap[size]
    i = 0
    while True:
        a, b, m = 2 * i + 1, 2 * i + 2, i
        if a < size and heap[a] < heap[m]:
            m = a
        if b < size and heap[b] < heap[m]:
            m = b
        if m == i:
            break
        heap[m], heap[i] = heap[i], heap[m]
        i = m
    return top, size


@njit(cache=True, inline="always")
def find_root(parent, x):
    """The root of ``x`` in the union-find forest ``parent``, the path compressed on the
    way: the pixel kernels' one union-find (the first open column of a row, the owner a
    label was merged into)."""
    root = x
    while parent[root] != root:
        root = parent[root]
    while parent[x] != root:
        parent[x], x = root, parent[x]
    return root
