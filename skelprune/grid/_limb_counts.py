"""The limb test's disks, counted on the coverage's own tiles (compiled).

The limb test (:mod:`skelprune.grid.limbs`) asks, for each point of an end branch,
whether its whole disk ``|p − s|² < r²`` is covered by that branch alone.
:class:`~skelprune.grid.coverage.Coverage` already knows it pixel by pixel: a pixel of
the branch's disks has the branch as its only owner iff its tile is open and its owner
count is 1 (a closed tile has at least two owners on every pixel). So each disk is read
where it lies, row by row, and given up at its first pixel with another owner: the work
follows the branch's own disks, never the box around them, and no count of the image is
kept beside the coverage's.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._digital import isqrt

__all__ = ["is_limb_on_tiles", "limb_rule"]


@njit(cache=True, inline="always")
def _run_alone(c, opened, tile, tw, y, a, e):
    """Whether every pixel ``a … e`` of row ``y`` has one owner: tile by tile, a closed
    tile failing at once."""
    ty = y // tile
    yy = y - ty * tile
    for tx in range(a // tile, e // tile + 1):
        t = ty * tw + tx
        if not opened[t]:
            return False
        x0 = tx * tile
        row = c[t, yy]
        for q in range(max(a, x0) - x0, min(e, x0 + tile - 1) - x0 + 1):
            if row[q] != 1:
                return False
    return True


@njit(cache=True, inline="always")
def _disk_alone(c, opened, tile, tw, y, x, r2):
    """Whether every pixel of the disk ``|p − (y, x)|² < r2`` has one owner.

    The rows are read from the centre out, and each row's two ends before its middle: a
    disk that another owner reaches is most often met there first (the centre row is the
    widest, the ends the farthest out)."""
    rad = isqrt(r2 - 1)
    for i in range(2 * rad + 1):
        dy = (i + 1) // 2 if i % 2 else -(i // 2)
        dx = isqrt(r2 - 1 - dy * dy)
        yy = y + dy
        if not (
            _run_alone(c, opened, tile, tw, yy, x - dx, x - dx)
            and _run_alone(c, opened, tile, tw, yy, x + dx, x + dx)
        ):
            return False
    for i in range(2 * rad + 1):
        dy = (i + 1) // 2 if i % 2 else -(i // 2)
        dx = isqrt(r2 - 1 - dy * dy)
        if dx > 0 and not _run_alone(c, opened, tile, tw, y + dy, x - dx + 1, x + dx - 1):
            return False
    return True


@njit(cache=True, inline="always")
def limb_rule(whole, widest):
    """At least ``2·r`` whole disks, ``r²`` the widest of them (docs/algorithm.md)."""
    return whole > 0 and whole >= 2.0 * math.sqrt(float(widest))


@njit(cache=True)
def is_limb_on_tiles(c, opened, tile, tw, rows, cols, r2, rim):
    """Whether at least ``2·r`` of a branch's points deeper than the rim (``r² > rim``)
    have their whole disk covered by the branch alone, ``r²`` the largest squared radius
    among those points (docs/algorithm.md, "Limbs"); never when fewer than 4 points are
    deeper than the rim (``2·r > 2·√2`` needs at least 4).

    ``c``, ``opened``, ``tile``, ``tw``: the owner counts of a
    :class:`~skelprune.grid.coverage.Coverage` in which the branch is one owner.

    The points are read by increasing radius, and the reading stops once the answer is
    known: were any point still to read whole, the whole ones would number at most those
    found so far plus those left, against ``2·r`` of a radius at least the current one.
    When even that falls short, a whole point to come means no limb, and none to come
    leaves the answer of those found so far.
    """
    n = r2.size
    deep = 0
    for k in range(n):
        if r2[k] > rim:
            deep += 1
    if deep < 4:
        return False
    order = np.argsort(r2, kind="mergesort")
    whole = widest = 0  # among the points read so far: the smallest radii
    for i in range(n):
        k = order[i]
        if r2[k] <= rim:
            continue
        # r2 grows along ``order``: every point left (n - i of them, this one included)
        # is deeper than the rim and at least as wide as this one.
        hopeless = not limb_rule(whole + n - i, r2[k])
        if hopeless and not limb_rule(whole, widest):
            return False
        if _disk_alone(c, opened, tile, tw, rows[k], cols[k], r2[k]):
            if hopeless:
                return False  # a whole disk to come: too few for its width
            whole += 1
            widest = max(widest, r2[k])
    return limb_rule(whole, widest)
