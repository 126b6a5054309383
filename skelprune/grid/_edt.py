"""Exact squared Euclidean distance transform in integers (the disks' radii)."""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["lower_envelope", "squared_distance"]


def squared_distance(padded: np.ndarray) -> np.ndarray:
    """Exact squared Euclidean distance of each pixel to the nearest background pixel.

    Parameters
    ----------
    padded : (H, W) bool array
        The shape, with at least one background pixel all around.

    Returns
    -------
    (H, W) int64 array, 0 on the background.

    Examples
    --------
    >>> m = np.zeros((5, 5), bool); m[1:4, 1:4] = True
    >>> squared_distance(m)[2, 2]
    np.int64(4)
    """
    padded = np.asarray(padded, dtype=np.bool_)
    if padded.all():  # no background to measure from: scipy's convention
        from scipy import ndimage

        d = ndimage.distance_transform_edt(padded)
        return np.rint(d * d).astype(np.int64)
    return _squared_edt(padded)


# inline="always": also called inside compiled code (the limb test), and a cached callee
# that returns an array must not also be entered from Python (see
# skelprune.grid._disk_counts.coverage).
@njit(cache=True, inline="always")
def _squared_edt(fg: np.ndarray) -> np.ndarray:
    """Exact squared Euclidean distance transform in integers (Meijster, Roerdink &
    Hesselink 2000): the distance along each column, then the lower envelope of the
    parabolas ``(x - i)² + g(i)²`` along each row. Equal to the rounded square of
    scipy's exact transform, with a quarter of its memory and no floating point.
    """
    h, w = fg.shape
    inf = h + w  # more than any distance along a column
    out = np.empty((h, w), dtype=np.int64)
    for x in range(w):  # columns, walked row by row: contiguous in memory
        out[0, x] = 0 if not fg[0, x] else inf
    for y in range(1, h):
        for x in range(w):
            out[y, x] = 0 if not fg[y, x] else min(out[y - 1, x] + 1, inf)
    for y in range(h - 2, -1, -1):
        for x in range(w):
            if out[y + 1, x] + 1 < out[y, x]:
                out[y, x] = out[y + 1, x] + 1
    g = np.empty(w, dtype=np.int64)
    s = np.empty(w, dtype=np.int64)
    t = np.empty(w, dtype=np.int64)
    for y in range(h):
        for x in range(w):
            g[x] = out[y, x] * out[y, x]
        lower_envelope(g, w, 1, out[y], s, t)
    return out


@njit(cache=True, inline="always")
def lower_envelope(f, m, w, out, s, t) -> None:
    """``out[u] = min_i w·(u − i)² + f[i]`` for ``u < m``, exact in integers: the lower
    envelope of the parabolas rooted at each ``i`` (Felzenszwalb & Huttenlocher), the row
    pass of both grids' distance transforms. ``s`` holds the parabolas on the envelope,
    ``t`` where each starts to be the lowest; ``out`` must not be ``f``.
    """
    q = 0
    s[0] = 0
    t[0] = 0
    for u in range(1, m):
        while q >= 0 and w * (t[q] - s[q]) ** 2 + f[s[q]] > w * (t[q] - u) ** 2 + f[u]:
            q -= 1
        if q < 0:
            q = 0
            s[0] = u
        else:
            i = s[q]
            sep = (w * (u * u - i * i) + f[u] - f[i]) // (2 * w * (u - i))
            if sep + 1 < m:
                q += 1
                s[q] = u
                t[q] = sep + 1
    for u in range(m - 1, -1, -1):
        out[u] = w * (u - s[q]) ** 2 + f[s[q]]
        if u == t[q]:
            q -= 1
