"""Overlay images: the shape, its reconstruction error in red (the paper's Fig. 8),
the pruned skeleton, its endpoints and junctions."""

from __future__ import annotations

import io

import numpy as np

from ..grid.reconstruction import reconstruction

__all__ = ["COLOURS", "auto_scale", "encode_png", "render_overlay"]

#: The default overlay makes the longer side at least this many pixels ...
READABLE_SIDE = 512
#: ... with an integer scale of at most this.
MAX_SCALE = 16
#: Skeleton lines are about one pixel wide per this many pixels of the longer side ...
LINE_EVERY = 400
#: ... and node markers this fraction of it in radius.
MARK_EVERY = 150

COLOURS = {
    "background": (255, 255, 255),
    "shape": (150, 210, 150),  # reconstructed part of the shape
    "error": (220, 40, 40),  # shape pixels the skeleton does not reconstruct
    "skeleton": (20, 20, 20),
    "endpoint": (30, 90, 230),
    "junction": (230, 150, 0),
}


def auto_scale(shape: tuple[int, ...]) -> int:
    """The smallest integer scale that makes the longer side at least
    :data:`READABLE_SIDE` pixels (at most :data:`MAX_SCALE`; 1 for large images).

    >>> auto_scale((108, 115)), auto_scale((600, 300)), auto_scale((4, 4))
    (5, 1, 16)
    """
    return int(min(MAX_SCALE, max(1, -(-READABLE_SIDE // max(shape[:2])))))


def _mark(
    img: np.ndarray, r: int, c: int, colour: tuple[int, int, int], scale: int, radius: float
) -> None:
    h, w = img.shape[:2]
    if radius <= 1.5:  # a 3 × 3 square
        img[max(r - 1, 0) : min(r + 2, h), max(c - 1, 0) : min(c + 2, w)] = colour
        return
    cy, cx = (r + 0.5) * scale, (c + 0.5) * scale
    r0, r1 = max(int(cy - radius), 0), min(int(cy + radius) + 1, h)
    c0, c1 = max(int(cx - radius), 0), min(int(cx + radius) + 1, w)
    yy, xx = np.mgrid[r0:r1, c0:c1]
    disc = (yy + 0.5 - cy) ** 2 + (xx + 0.5 - cx) ** 2 <= radius**2
    img[r0:r1, c0:c1][disc] = colour


def _legend(img: np.ndarray, text: str) -> np.ndarray:
    """The image with a white strip below holding ``text`` (and the colour key)."""
    from PIL import Image, ImageDraw, ImageFont

    width = img.shape[1]
    size = max(12, width // 45)
    keys = [
        ("shape", "reconstructed"),
        ("error", "error"),
        ("skeleton", "skeleton"),
        ("endpoint", "endpoint"),
        ("junction", "junction"),
    ]
    strip = Image.new("RGB", (width, 2 * size + 3 * size // 2), COLOURS["background"])
    draw = ImageDraw.Draw(strip)
    font = ImageFont.load_default(size=size)
    x, y = size // 2, size // 3
    for kind, label in keys:
        draw.rectangle([x, y + size // 5, x + size * 3 // 4, y + size], fill=COLOURS[kind])
        x += size
        draw.text((x, y), label, fill=(0, 0, 0), font=font)
        x += int(draw.textlength(label, font=font)) + size
    draw.text((size // 2, y + size + size // 2), text, fill=(0, 0, 0), font=font)
    return np.concatenate([img, np.asarray(strip)], axis=0)


def render_overlay(
    mask: np.ndarray,
    rows: np.ndarray,
    cols: np.ndarray,
    r2: np.ndarray,
    endpoints: np.ndarray | None = None,
    junctions: np.ndarray | None = None,
    scale: int = 1,
    legend: str | None = None,
) -> np.ndarray:
    """RGB overlay of a skeleton on its shape, ``scale`` times the mask's size.

    Parameters
    ----------
    mask : (H, W) bool array
        The shape.
    rows, cols, r2 : (n,) int arrays
        Skeleton pixels and their squared radii; their disks' union is the reconstruction.
    endpoints, junctions : (k, 2) int arrays, optional
        (row, col) of the nodes to mark: a 3 × 3 square at scale 1, else a disc 1.5
        input pixels in radius.
    scale : int
        Each input pixel becomes ``scale`` × ``scale`` pixels (nearest neighbour: the
        mask stays crisp, the skeleton's lines are ``scale`` pixels wide).
    legend : str, optional
        Text for a strip below the image, with the colour key (e.g. RER and SS).

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
    side = max(mask.shape) * scale
    # lines and markers grow with the picture: visible on a large image, too
    widen = int(side // LINE_EVERY) // (2 * scale)
    line = np.zeros(mask.shape, bool)
    line[rows, cols] = True
    if widen:
        from scipy import ndimage  # only for large pictures: kept off the import path

        line = ndimage.binary_dilation(line, iterations=widen)
    img[line] = COLOURS["skeleton"]
    if scale > 1:
        img = np.repeat(np.repeat(img, scale, axis=0), scale, axis=1)
    radius = max(1.5 * scale, side / MARK_EVERY)
    for kind, nodes in (("endpoint", endpoints), ("junction", junctions)):
        for r, c in np.zeros((0, 2), int) if nodes is None else nodes:
            _mark(img, int(r), int(c), COLOURS[kind], scale, radius)
    return img if legend is None else _legend(img, legend)


def encode_png(rgb: np.ndarray) -> bytes:
    """PNG bytes of an RGB image."""
    from PIL import Image  # only when a picture is asked for: kept off the import path

    buf = io.BytesIO()
    Image.fromarray(rgb).save(buf, format="PNG", optimize=False)
    return buf.getvalue()
