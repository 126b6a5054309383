"""Overlay images: the shape, its reconstruction error in red (the paper's Fig. 8),
the pruned skeleton, its endpoints and junctions."""

from __future__ import annotations

import io
import math
from typing import Any

import numpy as np

from ..grid.reconstruction import reconstruction

__all__ = ["COLOURS", "auto_scale", "encode_png", "render_overlay", "result_overlay"]

#: The default overlay makes the longer side at least this many pixels ...
READABLE_SIDE = 512
#: ... with an integer scale of at most this.
MAX_SCALE = 16
#: Skeleton lines are about one pixel wide per this many pixels of the longer side ...
LINE_EVERY = 400
#: ... and node markers this fraction of it in radius ...
MARK_EVERY = 150
#: ... but at most this fraction of their object's skeleton (its pixels) in radius, so
#: that the two end marks of a small object's axis cover at most a sixth of it ...
MARK_SHARE = 1 / 12
#: ... and never under half an input pixel.
MARK_LEAST = 0.5

COLOURS = {
    "background": (255, 255, 255),
    "shape": (150, 210, 150),  # reconstructed part of the shape
    "error": (220, 40, 40),  # shape pixels the skeleton does not reconstruct
    "skeleton": (20, 20, 20),
    "endpoint": (30, 90, 230),
    "junction": (230, 150, 0),
}
#: A label image's shapes, each label in one of these shades (the key's "reconstructed").
LABEL_SHADES = (
    (150, 210, 150),
    (150, 190, 230),
    (230, 200, 140),
    (200, 160, 220),
    (140, 215, 205),
    (235, 170, 170),
    (195, 215, 130),
    (180, 180, 180),
)
#: The legend's text takes at most this many lines; what does not fit is counted.
LEGEND_LINES = 4


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
    if scale == 1 and radius <= 1.5:  # a 3 × 3 square
        img[max(r - 1, 0) : min(r + 2, h), max(c - 1, 0) : min(c + 2, w)] = colour
        return
    cy, cx = (r + 0.5) * scale, (c + 0.5) * scale
    r0, r1 = max(int(cy - radius), 0), min(int(cy + radius) + 1, h)
    c0, c1 = max(int(cx - radius), 0), min(int(cx + radius) + 1, w)
    yy, xx = np.mgrid[r0:r1, c0:c1]
    disc = (yy + 0.5 - cy) ** 2 + (xx + 0.5 - cx) ** 2 <= radius**2
    img[r0:r1, c0:c1][disc] = colour


def _wrap(items: list[str], fits: Any) -> list[str]:
    """``items`` joined into lines that ``fits``, at most :data:`LEGEND_LINES`; the last
    says how many items did not fit."""
    lines: list[str] = []
    for i, item in enumerate(items):
        if lines and fits(lines[-1] + "   " + item):
            lines[-1] += "   " + item
        elif len(lines) < LEGEND_LINES:
            lines.append(item)
        else:
            rest = len(items) - i
            more = f"   … and {rest} more"
            while not fits(lines[-1] + more) and "   " in lines[-1]:
                lines[-1] = lines[-1].rsplit("   ", 1)[0]
                rest += 1
                more = f"   … and {rest} more"
            lines[-1] += more
            break
    return lines


def _legend(img: np.ndarray, text: str | list[str], shaded: bool = False) -> np.ndarray:
    """The image with a white strip below holding ``text`` (and the colour key); a list
    of items is wrapped to the image's width."""
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
    font = ImageFont.load_default(size=size)
    measure = ImageDraw.Draw(Image.new("RGB", (1, 1)))
    if isinstance(text, str):
        lines = [text]
    else:
        lines = _wrap(text, lambda t: measure.textlength(t, font=font) <= width - size)
    height = 2 * size + 3 * size // 2 + (len(lines) - 1) * (size + size // 3)
    strip = Image.new("RGB", (width, height), COLOURS["background"])
    draw = ImageDraw.Draw(strip)
    x, y = size // 2, size // 3
    for kind, label in keys:
        if shaded and kind == "shape":
            label = "a shade per label"
        fill = COLOURS[kind]
        draw.rectangle([x, y + size // 5, x + size * 3 // 4, y + size], fill=fill)
        x += size
        draw.text((x, y), label, fill=(0, 0, 0), font=font)
        x += int(draw.textlength(label, font=font)) + size
    for i, line in enumerate(lines):
        at = y + size + size // 2 + i * (size + size // 3)
        draw.text((size // 2, at), line, fill=(0, 0, 0), font=font)
    return np.concatenate([img, np.asarray(strip)], axis=0)


def render_overlay(
    mask: np.ndarray,
    rows: np.ndarray,
    cols: np.ndarray,
    r2: np.ndarray,
    endpoints: np.ndarray | None = None,
    junctions: np.ndarray | None = None,
    scale: int = 1,
    legend: str | list[str] | None = None,
    labels: np.ndarray | None = None,
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
        input pixels in radius (larger on a large picture), and at most
        :data:`MARK_SHARE` of the skeleton pixels of the node's object (its label, or
        its 8-connected component), at least :data:`MARK_LEAST` of a pixel: a small
        object's axis stays in sight.
    scale : int
        Each input pixel becomes ``scale`` × ``scale`` pixels (nearest neighbour: the
        mask stays crisp, the skeleton's lines are ``scale`` pixels wide).
    legend : str or list of str, optional
        Text for a strip below the image, with the colour key (e.g. RER and SS); a list's
        items are wrapped to the image's width, on at most :data:`LEGEND_LINES` lines.
    labels : (H, W) int array, optional
        A label image: each label's reconstructed part in its own shade
        (:data:`LABEL_SHADES`).

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
    if labels is not None:
        shades = np.asarray(LABEL_SHADES, np.uint8)
        lit = mask & covered
        # labels in order of value take the shades in turn
        rank = np.unique(labels[lit], return_inverse=True)[1]
        img[lit] = shades[rank.ravel() % len(shades)]
    img[mask & ~covered] = COLOURS["error"]
    side = max(mask.shape) * scale
    # lines and markers grow with the picture: visible on a large image, too
    widen = int(side // LINE_EVERY) // (2 * scale)
    # ... but never past the shape's own width: on a large network (roads a few pixels
    # wide over thousands) lines and marks grown with the picture would cover it
    thick = float(np.sqrt(np.median(r2))) if r2.size else math.inf
    widen = min(widen, int(thick // 3))
    line = np.zeros(mask.shape, bool)
    line[rows, cols] = True
    if widen:
        from scipy import ndimage  # only for large pictures: kept off the import path

        line = ndimage.binary_dilation(line, iterations=widen)
    img[line] = COLOURS["skeleton"]
    if scale > 1:
        img = np.repeat(np.repeat(img, scale, axis=0), scale, axis=1)
    radius = max(1.5 * scale, min(side / MARK_EVERY, thick * scale))
    marks = [
        (kind, np.zeros((0, 2), int) if nodes is None else np.asarray(nodes, int).reshape(-1, 2))
        for kind, nodes in (("endpoint", endpoints), ("junction", junctions))
    ]
    at = np.concatenate([nodes for _, nodes in marks])
    if at.size:
        caps = iter(_object_caps(mask, labels, rows, cols, at) * scale)
    for kind, nodes in marks:
        for r, c in nodes:
            cap = float(next(caps))
            _mark(img, int(r), int(c), COLOURS[kind], scale, min(radius, cap))
    return img if legend is None else _legend(img, legend, labels is not None)


def _object_caps(
    mask: np.ndarray,
    labels: np.ndarray | None,
    rows: np.ndarray,
    cols: np.ndarray,
    at: np.ndarray,
) -> np.ndarray:
    """The largest mark radius (input pixels) at each node ``at`` (row, col): its object's
    skeleton pixels times :data:`MARK_SHARE`, at least :data:`MARK_LEAST`."""
    from scipy import ndimage  # only for a picture with nodes: kept off the import path

    if labels is not None:
        objects = np.unique(labels, return_inverse=True)[1].reshape(labels.shape)
    else:
        objects = ndimage.label(mask, structure=np.ones((3, 3), bool))[0]
    skeleton = np.bincount(objects[rows, cols], minlength=int(objects.max()) + 1)
    r = np.clip(at[:, 0], 0, mask.shape[0] - 1)
    c = np.clip(at[:, 1], 0, mask.shape[1] - 1)
    return np.maximum(skeleton[objects[r, c]] * MARK_SHARE, MARK_LEAST)


def result_overlay(result: Any, scale: int = 1, legend: bool = False) -> np.ndarray:
    """The overlay of a :class:`~skelprune.output.document.PruneResult`: its skeleton,
    nodes, and (``legend``) each component's RER and SS, named by its label in a label
    image (whose labels each get a shade)."""
    rows, cols, r2 = result.skeleton_points()
    marks: dict[str, list[np.ndarray]] = {"endpoint": [], "junction": []}
    for comp in result.components:
        t = comp.table
        at = np.column_stack([t.y[t.node_point], t.x[t.node_point]]).astype(int)
        for kind, code in (("endpoint", 0), ("junction", 1)):
            marks[kind].append(at[t.node_kind == code])
    text: list[str] | None = None
    if legend:  # wrapped to the image's width by the renderer
        several = len(result.components) > 1
        text = [
            (
                f"label {c.label}: "
                if c.label is not None
                else (f"component {i}: " if several else "")
            )
            + f"RER {100 * c.rer:.2f} %, SS {c.ss:.3f}"
            for i, c in enumerate(result.components)
        ]
    return render_overlay(
        result.mask,
        rows,
        cols,
        r2,
        np.concatenate([np.zeros((0, 2), int), *marks["endpoint"]]),
        np.concatenate([np.zeros((0, 2), int), *marks["junction"]]),
        scale=scale,
        legend=text,
        labels=result.input.labels,
    )


def encode_png(rgb: np.ndarray) -> bytes:
    """PNG bytes of an RGB image."""
    from PIL import Image  # only when a picture is asked for: kept off the import path

    buf = io.BytesIO()
    Image.fromarray(rgb).save(buf, format="PNG", optimize=False)
    return buf.getvalue()
