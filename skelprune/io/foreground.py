"""Which pixels of an image are the shape: the foreground rule (docs/service.md).

``foreground="auto"`` (the default for images) picks the shape users mean:

1. An image that uses transparency (some pixel fully transparent): the shape is its
   opaque part, alpha above the middle of its range (so anti-aliased edges count half
   way, as with greys below).
2. Otherwise the image's grey values (luma for colour) are split at the middle of their
   range, ``(min + max) / 2``: *light* pixels are above it, *dark* ones at or below.
   The **background is the side that holds most of the image border**, and the shape is
   the other side. So white-on-black and black-on-white silhouettes both work, a mask
   whose background is 3 and shape 7 works, and anti-aliased edges are thresholded at
   mid-grey instead of growing the shape by a pixel.
3. Edge cases, decided by the same rule: a border split exactly in half has no
   majority, and then the light side is the shape (the non-zero side of a 0/1 mask); a
   shape that covers the whole border is taken as background (its complement is the
   shape), so pass ``foreground="nonzero"`` for such a mask; an image of a single level
   has nothing to split, and its non-zero pixels are the shape.

``foreground="nonzero"`` takes the non-zero pixels (alpha where the image uses
transparency, otherwise any non-zero channel) and ``"zero"`` the others, exactly.
What was taken is reported in the document (:meth:`Foreground.to_dict`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from ..options import FOREGROUND_RULES, check_option

__all__ = [
    "FOREGROUND_RULES",
    "POLYGON_FOREGROUND",
    "Foreground",
    "check_rule",
    "clean_labels",
    "clean_mask",
    "label_boxes",
    "label_hint",
    "label_values",
    "select",
]

_LUMA = np.array([0.299, 0.587, 0.114])  # ITU-R BT.601, as Pillow's "L" mode

Taken = Literal["nonzero", "zero", "light", "dark", "opaque", "polygon", "labels"]


@dataclass(frozen=True)
class Foreground:
    """What was taken as the shape.

    ``rule`` is the rule asked for (``None`` for polygon input). ``shape`` says which
    pixels were taken: ``nonzero``/``zero`` (exact), ``light``/``dark`` (grey values
    above / at or below ``threshold``), ``opaque`` (alpha above ``threshold``) or
    ``polygon``, or ``labels`` (every non-zero value its own shape). ``border`` is the
    share of border pixels on the background side (auto rule on grey values only).
    ``fill_holes`` and ``min_area`` are the cleaning applied (0: none; the document shows
    them only when given).
    """

    rule: str | None
    shape: Taken
    threshold: float | None = None
    border: float | None = None
    fill_holes: int = 0
    min_area: int = 0

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "rule": self.rule,
            "shape": self.shape,
            "threshold": self.threshold,
            "border": self.border,
        }
        if self.fill_holes:
            out["fill_holes"] = self.fill_holes
        if self.min_area:
            out["min_area"] = self.min_area
        return out


POLYGON_FOREGROUND = Foreground(None, "polygon")


def check_rule(rule: object) -> str:
    """The rule, or :class:`InvalidOptionError` for anything not in FOREGROUND_RULES."""
    return check_option("foreground", rule)


def _border(a: np.ndarray) -> np.ndarray:
    if min(a.shape) <= 2:
        return a.ravel()
    return np.concatenate([a[0], a[-1], a[1:-1, 0], a[1:-1, -1]])


def select(
    values: np.ndarray, rule: str = "auto", alpha: np.ndarray | None = None
) -> tuple[np.ndarray, Foreground]:
    """The shape mask of an image by the foreground rule (see the module docstring).

    Parameters
    ----------
    values : (H, W) or (H, W, C) array
        Grey or colour values (no alpha channel).
    rule : {"auto", "nonzero", "zero"}
    alpha : (H, W) array, optional
        The alpha channel, only when the image uses transparency.

    Returns
    -------
    mask : (H, W) bool array
    Foreground
        What was taken.

    Examples
    --------
    >>> img = np.full((5, 5), 255, np.uint8); img[1:4, 1:4] = 0   # black on white
    >>> mask, fg = select(img)
    >>> int(mask.sum()), fg.shape, fg.threshold, fg.border
    (9, 'dark', 127.5, 1.0)
    >>> int(select(img, "nonzero")[0].sum())
    16
    """
    rule = check_rule(rule)
    if alpha is not None:
        a = np.asarray(alpha)
        if rule != "auto":
            nz = a != 0
            return (nz if rule == "nonzero" else ~nz), Foreground(rule, rule)  # type: ignore[arg-type]
        t = (float(a.min()) + float(a.max())) / 2
        return a > t, Foreground(rule, "opaque", t)
    v = np.asarray(values)
    if rule != "auto" or v.size == 0:
        nz = np.any(v != 0, axis=-1) if v.ndim == 3 else v != 0
        taken = "nonzero" if rule == "auto" else rule
        return (nz if taken == "nonzero" else ~nz), Foreground(rule, taken)  # type: ignore[arg-type]
    grey = (
        v @ _LUMA[: v.shape[-1]]
        if v.ndim == 3 and v.shape[-1] == 3
        else (v[..., 0] if v.ndim == 3 else v)
    )
    grey = np.asarray(grey, dtype=np.float64)
    lo, hi = float(grey.min()), float(grey.max())
    if lo == hi:  # one level: nothing to split
        nz = np.any(v != 0, axis=-1) if v.ndim == 3 else v != 0
        return nz, Foreground(rule, "nonzero")
    t = (lo + hi) / 2
    light = grey > t
    border = _border(light)
    n_light = int(border.sum())
    if n_light > border.size - n_light:  # light background: the shape is dark
        return ~light, Foreground(rule, "dark", t, n_light / border.size)
    return light, Foreground(rule, "light", t, 1 - n_light / border.size)


# ------------------------------------------------------------------ label images
def label_values(values: np.ndarray, alpha: np.ndarray | None = None) -> np.ndarray:
    """The label image of an image's values: every distinct non-zero value one label.

    One channel of integers (any width), booleans, or floats holding whole numbers;
    transparent pixels (alpha 0) are background.

    Examples
    --------
    >>> label_values(np.array([[0, 3], [70000, 3]], np.uint32)).tolist()
    [[0, 3], [70000, 3]]
    """
    from ..errors import InvalidImageError

    v = np.asarray(values)
    if v.ndim != 2:
        raise InvalidImageError(
            f"labels needs a one-channel image of integers; this one has {v.shape[-1]} channels"
        )
    if v.dtype.kind == "f":
        if not np.all(np.isfinite(v)) or np.any(v != np.round(v)) or np.any(v < 0):
            raise InvalidImageError(
                "labels needs whole, non-negative values; this image has others"
            )
        if v.size and float(v.max()) >= 2**63:
            raise InvalidImageError("labels needs values below 2**63")
    elif v.dtype.kind == "i" and v.size and int(v.min()) < 0:
        raise InvalidImageError("labels needs non-negative values; this image has negative ones")
    elif v.dtype.kind not in "biu":
        raise InvalidImageError(f"labels needs an image of integers, got {v.dtype}")
    out = v.astype(np.int64)
    if alpha is not None:
        out[np.asarray(alpha) == 0] = 0
    return out


def _small_holes(
    background: np.ndarray, max_area: int
) -> list[tuple[np.ndarray, tuple[slice, ...]]]:
    """4-connected background components not touching the border, of fewer than
    ``max_area`` pixels: each as its boolean crop and the slices of its box."""
    from scipy import ndimage

    lab, n = ndimage.label(background)  # 4-connected: the background's connectivity
    if n == 0:
        return []
    sizes = np.bincount(lab.ravel(), minlength=n + 1)
    edge = np.unique(np.concatenate([lab[0], lab[-1], lab[:, 0], lab[:, -1]]))
    small = sizes < max_area
    small[0] = False
    small[edge] = False
    out = []
    for i, box in enumerate(ndimage.find_objects(lab), start=1):
        if box is not None and small[i]:
            out.append((lab[box] == i, box))
    return out


def clean_mask(mask: np.ndarray, fill_holes: int = 0, min_area: int = 0) -> np.ndarray:
    """The mask with its holes of fewer than ``fill_holes`` pixels filled, then its
    8-connected components of fewer than ``min_area`` pixels dropped (0: neither).

    Examples
    --------
    >>> m = np.zeros((7, 9), bool); m[1:6, 1:6] = True; m[3, 3] = False; m[1, 8] = True
    >>> c = clean_mask(m, fill_holes=2, min_area=2)
    >>> bool(c[3, 3]), bool(c[1, 8]), int(c.sum())
    (True, False, 25)
    """
    from scipy import ndimage

    out = np.array(mask, dtype=bool, copy=True)
    if fill_holes > 1:
        for hole, box in _small_holes(~out, fill_holes):
            out[box] |= hole
    if min_area > 1:
        lab, n = ndimage.label(out, structure=np.ones((3, 3), bool))
        sizes = np.bincount(lab.ravel(), minlength=n + 1)
        out &= (sizes >= min_area)[lab]
    return out


def clean_labels(labels: np.ndarray, fill_holes: int = 0, min_area: int = 0) -> np.ndarray:
    """A label image cleaned as :func:`clean_mask` cleans a mask, label by label.

    A background hole is filled only when one label surrounds it (a gap between two
    touching objects stays); a piece of a label (8-connected) of fewer than ``min_area``
    pixels becomes background. The work follows each label's bounding box.

    Examples
    --------
    >>> lab = np.zeros((5, 8), int); lab[:, :4] = 1; lab[:, 4:] = 2; lab[2, 1] = 0
    >>> lab[0, 7] = 3
    >>> c = clean_labels(lab, fill_holes=2, min_area=2)
    >>> int(c[2, 1]), int(c[0, 7])
    (1, 0)
    """
    from scipy import ndimage

    out = np.array(labels, dtype=np.int64, copy=True)
    if fill_holes > 1:
        for hole, box in _small_holes(out == 0, fill_holes):
            # the hole's 4-neighbours: all labelled (else they would be in the hole)
            grown = ndimage.binary_dilation(np.pad(hole, 1))
            r0, c0 = box[0].start - 1, box[1].start - 1
            rr, cc = np.nonzero(grown & ~np.pad(hole, 1))
            rr, cc = rr + r0, cc + c0
            inside = (rr >= 0) & (rr < out.shape[0]) & (cc >= 0) & (cc < out.shape[1])
            around = np.unique(out[rr[inside], cc[inside]])
            if around.size == 1 and around[0] != 0:
                out[box][hole] = around[0]
    if min_area > 1:
        eight = np.ones((3, 3), bool)
        for v, box in label_boxes(out):
            own = out[box] == v
            lab, n = ndimage.label(own, structure=eight)
            sizes = np.bincount(lab.ravel(), minlength=n + 1)
            drop = own & (sizes < min_area)[lab]
            out[box][drop] = 0
    return out


def label_boxes(labels: np.ndarray) -> list[tuple[int, tuple[slice, slice]]]:
    """Every non-zero label of a label image with the slices of its bounding box, in
    order of value: one pass over the image (a count per value where the values are
    small, as 16-bit labels are; a sort otherwise).

    >>> lab = np.zeros((3, 4), np.int64); lab[0, 1:3] = 5; lab[2, 0] = 2
    >>> [(v, (b[0].start, b[1].start, b[0].stop, b[1].stop)) for v, b in label_boxes(lab)]
    [(2, (2, 0, 3, 1)), (5, (0, 1, 1, 3))]
    """
    from scipy import ndimage

    if labels.size == 0:
        return []
    top = int(labels.max())
    if top < 1 << 24:  # a count per value: linear, no sort
        present = np.flatnonzero(np.bincount(labels.ravel(), minlength=top + 1))
        values = present[present != 0]
        boxes = ndimage.find_objects(labels.astype(np.int32, copy=False))
        return [(int(v), boxes[v - 1]) for v in values.tolist()]
    values, dense = np.unique(labels, return_inverse=True)
    dense = dense.reshape(labels.shape)
    if values[0] != 0:
        dense += 1
        values = np.concatenate([[0], values])
    boxes = ndimage.find_objects(dense.astype(np.int64, copy=False))
    return [(int(v), boxes[i]) for i, v in enumerate(values[1:].tolist())]


#: A grey level counts as a region of its own once it fills a 3 × 3 block this often.
_FLAT_BLOCKS = 1


def label_hint(values: np.ndarray, alpha: np.ndarray | None = None) -> str | None:
    """A hint when an image read by the foreground rule looks like a label image: more
    than two grey levels, and a level between the extremes that fills a 3 × 3 block
    (an anti-aliased two-level mask has such levels only along its edges).

    Examples
    --------
    >>> lab = np.zeros((9, 20), np.uint16); lab[2:7, 2:7] = 1; lab[2:7, 8:13] = 2
    >>> lab[2:7, 14:19] = 3
    >>> "labels" in label_hint(lab)
    True
    >>> label_hint((lab > 0).astype(np.uint8) * 255) is None
    True
    """
    v = np.asarray(values)
    if alpha is not None or v.ndim != 2 or v.dtype.kind not in "biuf" or min(v.shape) < 3:
        return None
    lo, hi = v.min(), v.max()
    middle = (v != lo) & (v != hi)
    if not middle.any():
        return None
    same = middle[1:-1, 1:-1].copy()
    centre = v[1:-1, 1:-1]
    for dr in (0, 1, 2):
        for dc in (0, 1, 2):
            same &= v[dr : dr + v.shape[0] - 2, dc : dc + v.shape[1] - 2] == centre
    if int(same.sum()) < _FLAT_BLOCKS:
        return None
    levels = np.unique(v).size
    return (
        f"this image has {levels} grey levels, with regions of levels between its darkest "
        "and lightest: it looks like a label image (each object its own value). The "
        "foreground rule kept one side of mid-grey; labels=true (--labels) prunes every "
        "non-zero value as its own shape."
    )
