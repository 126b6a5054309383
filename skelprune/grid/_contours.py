"""Boundary polygons of a binary shape: crack curves traced by marching squares.

The DCE partition (:mod:`skelprune.grid.dce`) works on these polygons. Kept apart because the
tracer is long and has one job: give exactly the curves of skimage's ``find_contours``
on the padded mask, without skimage's Python-level assembly.
"""

from __future__ import annotations

from itertools import pairwise

import numba
import numpy as np

__all__ = ["boundary_polygons", "trace_boundaries"]


def boundary_polygons(mask: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Closed crack polygons (float row/col) with their background pixels (int row/col).

    Exactly the polygons of ``find_contours(pad(mask, 1), 0.5, fully_connected="high",
    positive_orientation="high")`` with the closing vertex dropped: same vertices, same
    start vertex and orientation, same polygon order (``tests/library/test_dce_fast.py`` checks
    this against skimage). The DCE tie-breaking depends on vertex indices, so the start
    vertex matters.
    """
    xy, bg, bounds = trace_boundaries(np.ascontiguousarray(mask, dtype=np.bool_))
    return [(xy[a:b], bg[a:b]) for a, b in pairwise(bounds.tolist())]


@numba.njit(cache=True)
def trace_boundaries(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Marching squares at level 0.5 on the mask padded by one pixel, shape 8-connected.

    A replay of skimage's ``find_contours`` on a binary image: the same raster scan of
    2x2 squares, the same directed segments per square case (shape on the right of each
    segment; the diagonal cases 6 and 9 connect the shape pixels) and the same assembly of
    segments into chains (a chain absorbs a later-created one, so a closed curve keeps the
    number and start of the first chain it grew from). skimage's dict of deques becomes
    linked lists over point ids: every crack midpoint ends exactly one segment and starts
    exactly one, since the padding keeps every curve closed. The output walks each curve
    backwards from its start, which is skimage's ``positive_orientation="high"`` reversal
    (shape on the left).

    Point ids: ``2 * (r * w + c)`` is the midpoint between padded pixels ``(r, c)`` and
    ``(r, c + 1)``, ``2 * (r * w + c) + 1`` the one between ``(r, c)`` and ``(r + 1, c)``.

    Returns
    -------
    xy : (n, 2) float array
        All vertices, row/col in the frame of ``mask`` (half-integer on one axis).
    bg : (n, 2) int array
        The background pixel of each vertex.
    bounds : (m + 1,) int array
        Polygon ``i`` is ``xy[bounds[i]:bounds[i + 1]]``.
    """
    h, w = mask.shape[0] + 2, mask.shape[1] + 2
    padded = np.zeros((h, w), np.bool_)
    padded[1:-1, 1:-1] = mask
    n_ids = 2 * h * w
    prv = np.empty(n_ids, np.int64)  # previous point of the chain (skimage's deque order)
    start_of = np.full(n_ids, -1, np.int32)  # chain that starts at this point, or -1
    end_of = np.full(n_ids, -1, np.int32)  # chain that ends at this point, or -1
    first = [0]  # first / last point of each chain; [0] only types the lists
    last = [0]
    alive = [False]  # False once merged into an earlier chain
    first.pop()
    last.pop()
    alive.pop()
    for r0 in range(h - 1):
        r1 = r0 + 1
        for c0 in range(w - 1):
            c1 = c0 + 1
            case = (
                (1 if padded[r0, c0] else 0)
                + (2 if padded[r0, c1] else 0)
                + (4 if padded[r1, c0] else 0)
                + (8 if padded[r1, c1] else 0)
            )
            if case == 0 or case == 15:
                continue
            top = 2 * (r0 * w + c0)
            bottom = 2 * (r1 * w + c0)
            left = top + 1
            right = 2 * (r0 * w + c1) + 1
            for second in range(2):
                # the segment(s) of the square, in skimage's order and direction
                if second:
                    if case == 6:
                        a, b = right, bottom
                    elif case == 9:
                        a, b = bottom, left
                    else:
                        break
                elif case == 1:
                    a, b = top, left
                elif case == 2:
                    a, b = right, top
                elif case == 3:
                    a, b = right, left
                elif case == 4:
                    a, b = left, bottom
                elif case == 5:
                    a, b = top, bottom
                elif case == 6:
                    a, b = left, top
                elif case == 7:
                    a, b = right, bottom
                elif case == 8:
                    a, b = bottom, right
                elif case == 9:
                    a, b = top, right
                elif case == 10:
                    a, b = bottom, top
                elif case == 11:
                    a, b = bottom, left
                elif case == 12:
                    a, b = left, right
                elif case == 13:
                    a, b = top, right
                else:
                    a, b = left, top
                tail = start_of[b]  # the chain the segment is prepended to
                head = end_of[a]  # the chain the segment is appended to
                start_of[b] = -1
                end_of[a] = -1
                prv[b] = a
                if tail >= 0 and head >= 0:
                    if tail > head:  # tail created later: appended to head
                        last[head] = last[tail]
                        end_of[last[tail]] = head
                        alive[tail] = False
                    elif tail < head:  # head created later: prepended to tail
                        first[tail] = first[head]
                        start_of[first[head]] = tail
                        alive[head] = False
                    # tail == head: the curve closes, nothing more to record
                elif tail < 0 and head < 0:
                    start_of[a] = len(first)
                    end_of[b] = len(first)
                    first.append(a)
                    last.append(b)
                    alive.append(True)
                elif head < 0:
                    first[tail] = a
                    start_of[a] = tail
                else:
                    last[head] = b
                    end_of[b] = head
    n = 0
    for ch in range(len(first)):
        if alive[ch]:
            p = first[ch]
            while True:
                n += 1
                p = prv[p]
                if p == first[ch]:
                    break
    xy = np.empty((n, 2), np.float64)
    bg = np.empty((n, 2), np.int64)
    bounds = [0]
    k = 0
    for ch in range(len(first)):
        if not alive[ch]:
            continue
        p = first[ch]
        while True:
            cell = p // 2
            r = cell // w
            c = cell - r * w
            # back to the frame of mask (padding removed); the background pixel is
            # whichever of the two pixels the midpoint lies between is not shape
            if p % 2 == 0:
                xy[k, 0] = r - 1.0
                xy[k, 1] = c - 0.5
                bg[k, 0] = r - 1
                bg[k, 1] = c if padded[r, c] else c - 1
            else:
                xy[k, 0] = r - 0.5
                xy[k, 1] = c - 1.0
                bg[k, 0] = r if padded[r, c] else r - 1
                bg[k, 1] = c - 1
            k += 1
            p = prv[p]
            if p == first[ch]:
                break
        bounds.append(k)
    return xy, bg, np.array(bounds, np.int64)
