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

__all__ = ["FOREGROUND_RULES", "POLYGON_FOREGROUND", "Foreground", "check_rule", "select"]

_LUMA = np.array([0.299, 0.587, 0.114])  # ITU-R BT.601, as Pillow's "L" mode

Taken = Literal["nonzero", "zero", "light", "dark", "opaque", "polygon"]


@dataclass(frozen=True)
class Foreground:
    """What was taken as the shape.

    ``rule`` is the rule asked for (``None`` for polygon input). ``shape`` says which
    pixels were taken: ``nonzero``/``zero`` (exact), ``light``/``dark`` (grey values
    above / at or below ``threshold``), ``opaque`` (alpha above ``threshold``) or
    ``polygon``. ``border`` is the share of border pixels on the background side (auto
    rule on grey values only).
    """

    rule: str | None
    shape: Taken
    threshold: float | None = None
    border: float | None = None

    def to_dict(self) -> dict[str, Any]:
        return {
            "rule": self.rule,
            "shape": self.shape,
            "threshold": self.threshold,
            "border": self.border,
        }


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
