"""Reconstruction of a shape from skeleton disks, and its area term (docs/algorithm.md).

Besides the plain reconstruction, :class:`Coverage` keeps, for every pixel, how many
owners (branches or junction clusters) cover it with their disks and the sum of their
labels: a pixel has one owner iff the count is 1, and the sum is then that owner. So
the area each end branch alone covers, the area its removal would lose, is kept up to
date exactly. Each owner's disks are held as one union, a set of row runs
(:mod:`skelprune._intervals`): removing or merging an owner costs the area of its union
once, not the area of every one of its overlapping disks.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._digital import disk_half_width, isqrt
from ._intervals import owner_runs, union

__all__ = ["Coverage", "count_covered", "reconstruction", "reconstruction_error"]


@njit(cache=True)
def _paint_bool(out, rows, cols, r2):
    for k in range(rows.size):
        v = r2[k]
        h = isqrt(v - 1)
        for dy in range(-h, h + 1):
            w = disk_half_width(v, dy)
            row = out[rows[k] + dy]
            for q in range(cols[k] - w, cols[k] + w + 1):
                row[q] = True


def reconstruction(
    shape: tuple[int, int], rows: np.ndarray, cols: np.ndarray, r2: np.ndarray
) -> np.ndarray:
    """Union of the disks ``|p - s|**2 < r2(s)`` of the given points.

    The disks must lie inside the array (true for radii taken from the shape's
    distance transform when the shape has a background border).

    Examples
    --------
    >>> reconstruction((5, 5), np.array([2]), np.array([2]), np.array([2])).sum()
    np.int64(5)
    """
    out = np.zeros(shape, dtype=np.bool_)
    if len(rows):
        _paint_bool(
            out, np.asarray(rows, np.int64), np.asarray(cols, np.int64), np.asarray(r2, np.int64)
        )
    return out


def reconstruction_error(
    mask: np.ndarray, rows: np.ndarray, cols: np.ndarray, r2: np.ndarray
) -> float:
    """``AR(S) = Λ(D \\ R(S)) / Λ(D)``: the share of the shape the disks miss."""
    area = int(mask.sum())
    if area == 0:
        return 0.0
    rec = reconstruction(mask.shape, rows, cols, r2)
    return float((mask & ~rec).sum()) / area


def count_covered(
    pixels: np.ndarray, width: int, rows: np.ndarray, cols: np.ndarray, r2: np.ndarray
) -> int:
    """How many of ``pixels`` (flat indices, row length ``width``) the disks cover.

    For a few pixels and many disks: a test per pair, no painting.

    Examples
    --------
    >>> count_covered(np.array([0, 7, 24]), 5, np.array([1]), np.array([1]), np.array([2]))
    1
    """
    if len(pixels) == 0 or len(rows) == 0:
        return 0
    return int(
        _count_covered(
            np.asarray(pixels, np.int64) // width,
            np.asarray(pixels, np.int64) % width,
            np.asarray(rows, np.int64),
            np.asarray(cols, np.int64),
            np.asarray(r2, np.int64),
        )
    )


@njit(cache=True)
def _count_covered(py, px, rows, cols, r2):
    n = 0
    for i in range(py.size):
        for k in range(rows.size):
            dy = py[i] - rows[k]
            dx = px[i] - cols[k]
            if dy * dy + dx * dx < r2[k]:
                n += 1
                break
    return n


# Coverage counts owners, not disks: each owner (a branch, or a junction cluster) paints
# the union of its disks once, as a run set (skelprune._intervals). Kernels index a 1-D
# view of each row: measured faster than slice updates and 2-D indexing.


@njit(cache=True)
def _paint_owners(c, s, runs, offsets):
    for b in range(offsets.size - 1):
        for i in range(offsets[b], offsets[b + 1]):
            cr, sr = c[runs[i, 0]], s[runs[i, 0]]
            for q in range(runs[i, 1], runs[i, 2] + 1):
                cr[q] += 1
                sr[q] += b


@njit(cache=True)
def _remove_owner(c, s, runs, lab, excl):
    """Take owner ``lab`` off the pixels of its run set; return the pixels left uncovered.

    Each pixel is visited once (a run set is disjoint), so the pixels left with one
    owner are credited to it at once, without stamps.
    """
    lost = 0
    for i in range(runs.shape[0]):
        cr, sr = c[runs[i, 0]], s[runs[i, 0]]
        for q in range(runs[i, 1], runs[i, 2] + 1):
            cr[q] -= 1
            sr[q] -= lab
            n = cr[q]
            if n == 0:
                lost += 1
            elif n == 1:
                excl[sr[q]] += 1
    return lost


@njit(cache=True)
def _merge_owner(c, s, moved, kept, old, new):
    """Owner ``old`` (run set ``moved``) becomes owner ``new`` (run set ``kept``).

    Pixels both cover lose one owner; the others change label. Returns how many pixels
    of ``moved`` are left with the single owner ``new``: none was before, as ``old``
    covered them too.
    """
    single = 0
    d = new - old
    j = 0
    for i in range(moved.shape[0]):
        r, lo, hi = moved[i, 0], moved[i, 1], moved[i, 2]
        # The first run of kept not wholly before this one (kept is sorted too).
        while j < kept.shape[0] and (kept[j, 0] < r or (kept[j, 0] == r and kept[j, 2] < lo)):
            j += 1
        cr, sr = c[r], s[r]
        k = j
        q = lo
        while q <= hi:
            if k < kept.shape[0] and kept[k, 0] == r and kept[k, 1] <= q:
                # q lies in kept[k]: covered by both owners
                end = min(hi, kept[k, 2])
                for p in range(q, end + 1):
                    cr[p] -= 1
                    sr[p] -= old
                    if cr[p] == 1:
                        single += 1
                k += 1
            else:
                end = hi
                if k < kept.shape[0] and kept[k, 0] == r and kept[k, 1] <= hi:
                    end = kept[k, 1] - 1
                for p in range(q, end + 1):
                    sr[p] += d
                    if cr[p] == 1:
                        single += 1
            q = end + 1
    return single


class Coverage:
    """Incremental coverage of a shape by labelled skeleton disks.

    Points with one label form one owner (a branch or a junction cluster); a pixel
    counts its distinct owners ``c`` and the sum ``s`` of their labels, so it has a
    single owner iff ``c == 1``, and that owner is ``s``. Owners are removed and merged
    whole, by label (:meth:`remove_label`, :meth:`merge_label`): a branch's points always
    share its label, and a merge moves whole owners.

    Parameters
    ----------
    mask : (H, W) bool array
        The shape ``D``, with a background border.
    rows, cols, r2 : (n,) int arrays
        Skeleton points and squared radii.
    labels : (n,) int array
        Owner label of each point, in ``1 .. n_labels - 1``.
    n_labels : int
        Size of the label space.

    Attributes
    ----------
    lost : int
        Pixels of ``D`` no disk covers, ``Λ(D \\ R(S))``.
    exclusive : (n_labels,) int64
        Pixels covered by the disks of one label only: what removing it would lose.
        Exact for the labels still in use; stale for removed or merged ones.
    c : (H, W) int32
        Number of owners covering each pixel.

    Examples
    --------
    Two disjoint disks of 13 pixels, labels 1 and 2, in a 9 x 12 shape:

    >>> cov = Coverage(np.ones((9, 12), bool), np.array([4, 4]), np.array([3, 8]),
    ...                np.array([5, 5]), np.array([1, 2]), 3)
    >>> cov.exclusive.tolist(), cov.lost
    ([0, 13, 13], 82)
    >>> cov.merge_label(2, 1)
    >>> cov.exclusive[1], cov.remove_label(1), cov.lost
    (np.int64(26), 26, 108)
    """

    def __init__(self, mask, rows, cols, r2, labels, n_labels: int) -> None:
        runs, offsets = owner_runs(
            np.asarray(rows, np.int64),
            np.asarray(cols, np.int64),
            np.asarray(r2, np.int64),
            np.asarray(labels, np.int64),
            n_labels,
        )
        self.runs = [runs[offsets[b] : offsets[b + 1]] for b in range(n_labels)]
        self.c = np.zeros(mask.shape, np.int32)
        self.s = np.zeros(mask.shape, np.int64)
        _paint_owners(self.c, self.s, runs, offsets)
        self.exclusive = np.bincount(self.s[self.c == 1], minlength=n_labels).astype(np.int64)
        self.lost = int((mask & (self.c == 0)).sum())

    def remove_label(self, old: int) -> int:
        """Remove the disks of all points labelled ``old``; returns the newly uncovered area.

        The pruning knows the label of the branch it removes, so no point is looked at.
        """
        lost = _remove_owner(self.c, self.s, self.runs[old], old, self.exclusive)
        self.runs[old] = self.runs[old][:0]
        self.lost += lost
        return lost

    def merge_label(self, old: int, new: int) -> None:
        """Give all points labelled ``old`` the label ``new``."""
        if old == new or len(self.runs[old]) == 0:
            return
        self.exclusive[new] += _merge_owner(
            self.c, self.s, self.runs[old], self.runs[new], old, new
        )
        self.runs[new] = union(self.runs[new], self.runs[old])
        self.runs[old] = self.runs[old][:0]
