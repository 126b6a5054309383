"""8-connected components of a binary image, on its row runs.

The pipeline needs the components of the input mask (each is pruned on its own) and the
clusters of junction pixels of a skeleton. ``scipy.ndimage.label`` does both, but
importing ``scipy.ndimage`` costs a fresh process a good share of its first ``prune()``;
these kernels load from numba's cache with the others, and work on row runs (a run per
row and component, not an array of labels per pixel).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["components8", "holes", "label8"]


@njit(cache=True, inline="always")
def _root(parent, i):
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


# inline="always": called from Python (label8) and inside compiled code (_crops); a
# cached callee that returns arrays must not be both (see _disk_counts.coverage).
@njit(cache=True, inline="always")
def _components(mask):
    """Row runs of ``mask`` (row, first, last column) in raster order, the component of
    each (numbered in the raster order of the components' first pixels), the count, and
    each component's box (top, left, bottom, right). One kernel: each kernel a fresh
    process loads from the cache costs it time."""
    h, w = mask.shape
    n = 0
    for y in range(h):
        inside = False
        for x in range(w):
            if mask[y, x] and not inside:
                n += 1
            inside = mask[y, x]
    runs = np.empty((n, 3), np.int64)
    k = 0
    for y in range(h):
        x = 0
        while x < w:
            if mask[y, x]:
                a = x
                while x < w and mask[y, x]:
                    x += 1
                runs[k, 0], runs[k, 1], runs[k, 2] = y, a, x - 1
                k += 1
            else:
                x += 1
    parent = np.arange(n)
    # runs of consecutive rows touch (8-connectivity) iff their columns overlap when
    # widened by one: a sweep over the two rows
    prev = 0  # the first run of the previous row
    cur = 0
    while cur < n:
        y = runs[cur, 0]
        end = cur
        while end < n and runs[end, 0] == y:
            end += 1
        while prev < cur and runs[prev, 0] < y - 1:
            prev += 1
        i = prev
        for j in range(cur, end):
            while i < cur and runs[i, 2] + 1 < runs[j, 1]:
                i += 1
            t = i
            while t < cur and runs[t, 1] <= runs[j, 2] + 1:
                ra, rb = _root(parent, t), _root(parent, j)
                if ra != rb:  # the smaller index (earlier run) stays the root
                    parent[max(ra, rb)] = min(ra, rb)
                t += 1
        prev = cur
        cur = end
    comp = np.empty(n, np.int64)
    count = 0
    for k in range(n):
        r = _root(parent, k)
        if r == k:
            comp[k] = count
            count += 1
        else:
            comp[k] = comp[r]  # r < k: numbered already
    box = np.empty((count, 4), np.int64)
    for c in range(count):
        box[c, 0] = box[c, 1] = h + w
        box[c, 2] = box[c, 3] = -1
    for k in range(n):
        c = comp[k]
        box[c, 0] = min(box[c, 0], runs[k, 0])
        box[c, 1] = min(box[c, 1], runs[k, 1])
        box[c, 2] = max(box[c, 2], runs[k, 0])
        box[c, 3] = max(box[c, 3], runs[k, 2])
    return runs, comp, count, box


def _pixels(runs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rows and columns of the pixels of ``runs``, and the index of each one's run."""
    lengths = runs[:, 2] - runs[:, 1] + 1
    which = np.repeat(np.arange(len(runs)), lengths)
    first = np.cumsum(lengths) - lengths
    return runs[which, 0], runs[which, 1] + np.arange(which.size) - first[which], which


def label8(mask: np.ndarray) -> tuple[np.ndarray, int]:
    """Label the 8-connected components of ``mask`` 1, 2, … in the raster order of their
    first pixels; 0 is the background. The labels of ``scipy.ndimage.label`` with a 3 × 3
    structure.

    Examples
    --------
    >>> m = np.array([[1, 0, 0, 1], [0, 1, 0, 1], [0, 0, 0, 0], [1, 1, 0, 0]], bool)
    >>> lab, n = label8(m)
    >>> n, lab.tolist()
    (3, [[1, 0, 0, 2], [0, 1, 0, 2], [0, 0, 0, 0], [3, 3, 0, 0]])
    """
    runs, comp, n, _ = _components(np.ascontiguousarray(mask, dtype=np.bool_))
    out = np.zeros(np.shape(mask), np.int32)
    rows, cols, which = _pixels(runs)
    out[rows, cols] = comp[which] + 1
    return out, int(n)


def components8(mask: np.ndarray) -> list[tuple[np.ndarray, tuple[int, int]]]:
    """Each 8-connected component of ``mask`` (in :func:`label8`'s order) as a crop of its
    bounding box padded with one background pixel all around, and the image position of
    the crop's corner.

    Examples
    --------
    >>> m = np.zeros((4, 5), bool); m[0, 0] = m[2, 2:4] = True
    >>> [(c.shape, o) for c, o in components8(m)]
    [((3, 3), (-1, -1)), ((3, 4), (1, 1))]
    """
    buf, offsets, box = _crops(np.ascontiguousarray(mask, dtype=np.bool_))
    out = []
    offs = offsets.tolist()
    for c, (top, left, bottom, right) in enumerate(box.tolist()):
        shape = (bottom - top + 3, right - left + 3)
        crop = buf[offs[c] : offs[c] + shape[0] * shape[1]].reshape(shape)
        out.append((crop, (top - 1, left - 1)))
    return out


@njit(cache=True)
def _crops(mask):
    """:func:`components8` in one compiled call: the crops one after another in one
    flat buffer (crop ``c`` at ``offsets[c]``, ``bottom − top + 3`` rows of
    ``right − left + 3``), and the boxes."""
    runs, comp, count, box = _components(mask)
    offsets = np.zeros(count + 1, np.int64)
    for c in range(count):
        offsets[c + 1] = offsets[c] + (box[c, 2] - box[c, 0] + 3) * (box[c, 3] - box[c, 1] + 3)
    buf = np.zeros(offsets[count], np.bool_)
    for k in range(runs.shape[0]):
        c = comp[k]
        width = box[c, 3] - box[c, 1] + 3
        base = offsets[c] + (runs[k, 0] - box[c, 0] + 1) * width - box[c, 1] + 1
        for x in range(runs[k, 1], runs[k, 2] + 1):
            buf[base + x] = True
    return buf, offsets, box


def holes(mask: np.ndarray) -> int:
    """The holes of an 8-connected foreground: 4-connected background pieces that do not
    touch the array's border.

    >>> m = np.ones((5, 6), bool); m[1, 1] = m[3, 3] = m[0, 5] = False
    >>> holes(m)
    2
    """
    from scipy import ndimage  # (not at import: see the module's docstring)

    background, n = ndimage.label(~mask)
    edge = np.concatenate([background[0], background[-1], background[:, 0], background[:, -1]])
    return n - int(np.count_nonzero(np.unique(edge)))
