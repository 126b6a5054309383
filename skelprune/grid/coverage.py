"""The area each owner alone covers, exactly up to date (the pruning's area term).

:class:`Coverage` keeps, for each owner (a branch or a junction cluster), the area its
disks alone cover: the area its removal would lose. Each owner's disks are held as one
union, a set of row runs (:mod:`skelprune.grid._intervals`), and the shape is cut into
square tiles: a tile that two owners cover whole holds no pixel with fewer than two
owners, so it is only counted (how many owners cover it whole), and its pixels are
looked at once that count falls below two. Work then follows the pixels near the
owners' edges and the shape's boundary, not the owners' areas, which on a blob-like
shape are huge and pile up.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._intervals import union_runs
from ._tiles import COVER_TILE, _build, _merge, _remove_owner

__all__ = ["COVER_TILE", "Coverage"]


class Coverage:
    """Incremental coverage of a shape by labelled skeleton disks.

    Points with one label form one owner (a branch or a junction cluster); a pixel
    counts its distinct owners ``c`` and the sum ``s`` of their labels, so it has a
    single owner iff ``c == 1``, and that owner is ``s``. Owners are removed and merged
    whole, by label (:meth:`remove_label`, :meth:`merge_label`): a branch's points always
    share its label, and a merge moves whole owners.

    The counts are kept only in the tiles (``tile`` × ``tile`` pixels) that fewer than
    two owners cover whole: elsewhere no pixel can have fewer than two owners, so the
    tile only counts its whole-covering owners, and is opened (its pixels counted from
    the owners' runs) once that count falls below two.

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
    tile : int
        Side of the tiles, default :data:`COVER_TILE`.

    Attributes
    ----------
    lost : int
        Pixels of ``D`` no disk covers, ``Λ(D \\ R(S))``.
    exclusive : (n_labels,) int64
        Pixels covered by the disks of one label only: what removing it would lose.
        Exact for the labels still in use; stale for removed or merged ones.

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

    def __init__(self, mask, rows, cols, r2, labels, n_labels: int, tile: int = COVER_TILE) -> None:
        self.mask = np.ascontiguousarray(mask, dtype=np.bool_)
        h, w = self.mask.shape
        self.tile = tile
        self.th, self.tw = -(-h // tile), -(-w // tile)
        n_tiles = self.th * self.tw
        # zeroed lazily by the system: the pages of tiles never opened are never touched
        self.c = np.zeros((n_tiles, tile, tile), np.int32)
        self.s = np.zeros((n_tiles, tile, tile), np.int64)
        self.buf, self.tiles, self.state, lost = _build(
            np.asarray(rows, np.int64),
            np.asarray(cols, np.int64),
            np.asarray(r2, np.int64),
            np.asarray(labels, np.int64),
            n_labels,
            tile,
            self.tw,
            self.mask,
            self.c,
            self.s,
        )
        self.exclusive, self.opened = self.state.excl, self.state.opened
        self.used, self.tused = self.buf.shape[0], self.tiles.size
        self.lost = int(lost)

    def remove_label(self, old: int) -> int:
        """Remove the disks of all points labelled ``old``; returns the newly uncovered area.

        The pruning knows the label of the branch it removes, so no point is looked at.
        """
        lost = int(_remove_label(old, self.state, self.buf, self.tiles))
        self.lost += lost
        return lost

    def merge_label(self, old: int, new: int) -> None:
        """Give all points labelled ``old`` the label ``new``."""
        self.buf, self.tiles, self.used, self.tused, lost = _merge_label(
            old, new, self.used, self.tused, self.state, self.buf, self.tiles
        )
        self.lost += int(lost)

    def counts(self) -> np.ndarray:
        """Owners per pixel where the tiles are open, -1 in the closed ones (where every
        pixel has two owners or more): for checks."""
        h, w, t = self.mask.shape[0], self.mask.shape[1], self.tile
        grid = self.c.reshape(self.th, self.tw, t, t).transpose(0, 2, 1, 3)
        out = grid.reshape(self.th * t, self.tw * t).copy()
        shut = np.repeat(np.repeat(~self.opened.reshape(self.th, self.tw), t, 0), t, 1)
        out[shut] = -1
        return out[:h, :w]

    def uncovered(self) -> np.ndarray:
        """Flat indices (raster order) of the pixels of ``D`` no disk covers."""
        return np.flatnonzero(self.mask & (self.counts() == 0))


@njit(cache=True)
def _remove_label(old, st, buf, tiles):
    """:meth:`Coverage.remove_label` in one compiled call: the pixels left uncovered."""
    lost = _remove_owner(old, st, buf, tiles)
    st.hi[old] = st.lo[old]
    st.thi[old] = st.tlo[old]
    return lost


@njit(cache=True)
def _merge_label(old, new, used, tused, st, buf, tiles):
    """:meth:`Coverage.merge_label` in one compiled call: the union of the two owners'
    runs appended to ``buf`` (``buf[:used]`` in use) and the tiles to ``tiles``
    (``tiles[:tused]``), each grown when full, then :func:`._tiles._merge`. Returns
    ``buf``, ``tiles`` (the same arrays or larger copies), their new ends, and the
    pixels left uncovered."""
    lo, hi, tlo, thi = st.lo, st.hi, st.tlo, st.thi
    if old == new or hi[old] == lo[old]:
        return buf, tiles, used, tused, 0
    merged = union_runs(buf[lo[new] : hi[new]], buf[lo[old] : hi[old]])
    n = merged.shape[0]
    if used + n > buf.shape[0]:
        bigger = np.empty((2 * (used + n), 3), np.int64)
        bigger[:used] = buf[:used]
        buf = bigger
    mlo = used
    buf[mlo : mlo + n] = merged
    used += n
    need = thi[old] - tlo[old] + thi[new] - tlo[new]
    if tused + need > tiles.size:
        more = np.empty(2 * (tused + need), np.int64)
        more[:tused] = tiles[:tused]
        tiles = more
    tused, lost = _merge(old, new, mlo, used, tused, st, buf, tiles)
    return buf, tiles, used, tused, lost
