"""Overlay images: the shape, its reconstruction error in red (the paper's Fig. 8),
the pruned skeleton, its endpoints and junctions."""

from __future__ import annotations

import io
from typing import TYPE_CHECKING

import numpy as np
from PIL import Image

from .reconstruction import reconstruction

if TYPE_CHECKING:
    from .result import PruneResult

__all__ = ["COLOURS", "encode_png", "render_overlay"]

COLOURS = {
    "background": (255, 255, 255),
    "shape": (150, 210, 150),       # reconstructed part of the shape
    "error": (220, 40, 40),         # shape pixels the skeleton does not reconstruct
    "skeleton": (20, 20, 20),
    "endpoint": (30, 90, 230),
    "junction": (230, 150, 0),
}


def _mark(img: np.ndarray, r: int, c: int, colour: tuple[int, int, int]) -> None:
    h, w = img.shape[:2]
    img[max(r - 1, 0) : min(r + 2, h), max(c - 1, 0) : min(c + 2, w)] = colour


def render_overlay(result: PruneResult) -> np.ndarray:
    """RGB overlay of a pruning result, same size as the input mask.

    Examples
    --------
    >>> import skelprune
    >>> m = np.zeros((20, 40), bool); m[5:15, 5:35] = True
    >>> render_overlay(skelprune.prune(m)).shape
    (20, 40, 3)
    """
    mask = result.mask
    rows, cols, r2 = result.skeleton_points()
    covered = reconstruction(mask.shape, rows, cols, r2) if rows.size else np.zeros_like(mask)
    img = np.empty((*mask.shape, 3), np.uint8)
    img[:] = COLOURS["background"]
    img[mask & covered] = COLOURS["shape"]
    img[mask & ~covered] = COLOURS["error"]
    img[rows, cols] = COLOURS["skeleton"]
    for comp in result.components:
        doc_nodes = comp.skeleton_table()[0]
        for n in doc_nodes:
            if n["kind"] in ("endpoint", "junction"):
                _mark(img, int(n["y"]), int(n["x"]), COLOURS[n["kind"]])
    return img


def encode_png(rgb: np.ndarray) -> bytes:
    """PNG bytes of an RGB image."""
    buf = io.BytesIO()
    Image.fromarray(rgb).save(buf, format="PNG", optimize=False)
    return buf.getvalue()
