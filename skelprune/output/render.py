"""Overlay images: the shape, its reconstruction error in red (the paper's Fig. 8),
the pruned skeleton, its endpoints and junctions."""

from __future__ import annotations

import io

import numpy as np
from PIL import Image

from ..reconstruction import reconstruction

__all__ = ["COLOURS", "encode_png", "render_overlay"]

COLOURS = {
    "background": (255, 255, 255),
    "shape": (150, 210, 150),  # reconstructed part of the shape
    "error": (220, 40, 40),  # shape pixels the skeleton does not reconstruct
    "skeleton": (20, 20, 20),
    "endpoint": (30, 90, 230),
    "junction": (230, 150, 0),
}


def _mark(img: np.ndarray, r: int, c: int, colour: tuple[int, int, int]) -> None:
    h, w = img.shape[:2]
    img[max(r - 1, 0) : min(r + 2, h), max(c - 1, 0) : min(c + 2, w)] = colour


def render_overlay(
    mask: np.ndarray,
    rows: np.ndarray,
    cols: np.ndarray,
    r2: np.ndarray,
    endpoints: np.ndarray | None = None,
    junctions: np.ndarray | None = None,
) -> np.ndarray:
    """RGB overlay of a skeleton on its shape, same size as the mask.

    Parameters
    ----------
    mask : (H, W) bool array
        The shape.
    rows, cols, r2 : (n,) int arrays
        Skeleton pixels and their squared radii; their disks' union is the reconstruction.
    endpoints, junctions : (k, 2) int arrays, optional
        (row, col) of the nodes to mark with a 3 × 3 square.

    Examples
    --------
    >>> m = np.zeros((20, 40), bool); m[5:15, 5:35] = True
    >>> img = render_overlay(m, np.array([10]), np.array([20]), np.array([25]))
    >>> img.shape, img[10, 20].tolist(), img[6, 6].tolist()
    ((20, 40, 3), [20, 20, 20], [220, 40, 40])
    """
    mask = np.asarray(mask, bool)
    covered = reconstruction(mask.shape, rows, cols, r2) if rows.size else np.zeros_like(mask)
    img = np.empty((*mask.shape, 3), np.uint8)
    img[:] = COLOURS["background"]
    img[mask & covered] = COLOURS["shape"]
    img[mask & ~covered] = COLOURS["error"]
    img[rows, cols] = COLOURS["skeleton"]
    for kind, nodes in (("endpoint", endpoints), ("junction", junctions)):
        for r, c in np.zeros((0, 2), int) if nodes is None else nodes:
            _mark(img, int(r), int(c), COLOURS[kind])
    return img


def encode_png(rgb: np.ndarray) -> bytes:
    """PNG bytes of an RGB image."""
    buf = io.BytesIO()
    Image.fromarray(rgb).save(buf, format="PNG", optimize=False)
    return buf.getvalue()
