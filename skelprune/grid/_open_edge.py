"""Where a shape runs off the image: its open edge.

A shape cut by the image's border goes on beyond it, as far as anyone can tell: a vessel
leaving the field of view, a crack running off the photograph. Its end there is not a
tip of the shape. The pipeline pads each component's crop with one background pixel; the
pad pixels that lie outside the image next to a shape pixel are the **open edge**. The
medial axis is found with distances that treat the shape as going on straight across
the open edge (so its axis runs to the border instead of forking into the corners the cut
makes), and the pruning keeps every end at the open edge and never cuts its tip
(docs/algorithm.md, "Ends on the image border").
"""

from __future__ import annotations

import math

import numpy as np
from scipy import ndimage

from ._edt import squared_distance

__all__ = ["open_edge", "open_extension"]


def open_edge(
    crop: np.ndarray, origin: tuple[int, int], image_shape: tuple[int, int], noise: float
) -> np.ndarray | None:
    """The crop's pad pixels where the shape crosses the image's border (None: nowhere).

    They are the pad pixels outside the image 4-adjacent to a shape pixel, taken run by
    run: a run is a crossing when a disk of the shape gone on across it could span it,
    its length at most ``2·√2·r`` (a cut at up to 45°) with ``r`` the largest radius on
    it, runs read on the shape's band along the border, two pixels deeper than the
    boundary's noise (``noise``: how deep it reaches, in pixels, which the caller's rule
    gives); a shape lying along the border (a cut far wider than the shape is thick
    there) stays closed.

    Examples
    --------
    >>> crop = np.zeros((12, 7), bool); crop[1:11, 2:5] = True  # 3 px wide, off the top
    >>> open_edge(crop, (-1, 3), (20, 20), 0.7).nonzero()
    (array([0, 0, 0]), array([2, 3, 4]))
    >>> open_edge(crop, (2, 3), (20, 20), 0.7) is None
    True
    >>> wide = np.zeros((5, 30), bool); wide[1:4, 1:29] = True  # lying along the top
    >>> open_edge(wide, (-1, 3), (20, 40), 0.7) is None
    True
    """
    h, w = crop.shape
    rows = np.arange(h) + origin[0]
    cols = np.arange(w) + origin[1]
    outside = ((rows < 0) | (rows >= image_shape[0]))[:, None] | (
        (cols < 0) | (cols >= image_shape[1])
    )[None, :]
    if not outside.any():
        return None
    edge = outside & ndimage.binary_dilation(crop, ndimage.generate_binary_structure(2, 1))
    if not edge.any():
        return None
    ext, o = open_extension(crop, edge)
    far = squared_distance(ext)[o : o + h, o : o + w]
    # The cut's runs are read on the shape's band along the border, two pixels deeper
    # than the boundary's noise (docs/algorithm.md), which a ragged boundary does not
    # part as it parts the contact itself.
    depth = 2 + math.ceil(noise)
    # within ``depth`` steps (8-connected) of the crop's outside rows and columns: the
    # outside is whole rows and whole columns, so the steps are a row's or a column's gap
    band = crop & (
        (_gap(rows, image_shape[0]) <= depth)[:, None]
        | (_gap(cols, image_shape[1]) <= depth)[None, :]
    )
    runs, n = ndimage.label(band, np.ones((3, 3), bool))
    keep = np.zeros(n + 1, bool)
    for k, box in enumerate(ndimage.find_objects(runs), start=1):
        # the run's mouth lies within a pixel of its box: read there, not over the crop
        near = (
            slice(max(box[0].start - 1, 0), box[0].stop + 1),
            slice(max(box[1].start - 1, 0), box[1].stop + 1),
        )
        run = runs[near] == k
        mouth = edge[near] & ndimage.binary_dilation(run, np.ones((3, 3), bool))
        if not mouth.any():
            continue
        length = max(box[0].stop - box[0].start, box[1].stop - box[1].start)
        r = math.sqrt(float(far[near][mouth].max()))
        keep[k] = length <= 2.0 * math.sqrt(2.0) * r + 2.0
    accepted = ndimage.binary_dilation(keep[runs], np.ones((3, 3), bool))
    edge = edge & accepted
    return edge if edge.any() else None


def _gap(index: np.ndarray, size: int) -> np.ndarray:
    """Each of a crop's rows (columns), given by its index in the image, its distance to
    the crop's nearest row (column) outside the image: 0 outside, a large number where
    the crop holds none."""
    far = np.full(index.shape, np.iinfo(np.int64).max // 2, np.int64)
    if index[0] < 0:
        far = np.minimum(far, index + 1)
    if index[-1] >= size:
        far = np.minimum(far, size - index)
    return far.clip(0)


def open_extension(shape: np.ndarray, edge: np.ndarray) -> tuple[np.ndarray, int]:
    """The shape going on straight out of the crop across its open edge ``edge`` (pad
    pixels of the crop's outer rows and columns), far enough that no disk inside meets
    the continuation's end, with a background border; and the crop's offset in it."""
    reach = math.isqrt(int(squared_distance(shape).max())) + 2
    h, w = shape.shape
    ext = np.zeros((h + 2 * reach + 2, w + 2 * reach + 2), bool)
    o = reach + 1
    ext[o : o + h, o : o + w] = shape | edge
    ext[1:o, o : o + w] |= edge[0][None, :]
    ext[o + h : -1, o : o + w] |= edge[-1][None, :]
    ext[o : o + h, 1:o] |= edge[:, 0][:, None]
    ext[o : o + h, o + w : -1] |= edge[:, -1][:, None]
    return ext, o
