"""Sample data that ships with the plugin, drawn here rather than read from files: a label
image of cells with neurites, and a volume of a branching vessel."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["cells", "sample_cells", "sample_vessel", "vessel"]

LayerData = list[tuple[np.ndarray, dict[str, Any], str]]


def _segment(
    shape: tuple[int, ...], a: tuple[float, ...], b: tuple[float, ...], radius: float
) -> np.ndarray:
    """The pixels (voxels) within ``radius`` of the segment from ``a`` to ``b``."""
    grid = np.indices(shape, dtype=np.float64)
    pa = np.asarray(a, np.float64).reshape(-1, *([1] * len(shape)))
    ab = (np.asarray(b, np.float64) - np.asarray(a, np.float64)).reshape(pa.shape)
    t = np.clip(((grid - pa) * ab).sum(0) / max(float((ab**2).sum()), 1e-12), 0.0, 1.0)
    return _norm(grid - pa - t * ab) <= radius


def _norm(v: np.ndarray) -> np.ndarray:
    return np.sqrt((v**2).sum(0))


def cells() -> np.ndarray:
    """A 160 × 240 label image: three cells (labels 1 to 3), each a body with neurites,
    two of them touching."""
    shape = (160, 240)
    out = np.zeros(shape, np.uint16)
    rows, cols = np.indices(shape)
    bodies = [(60, 60, 22, 16), (90, 130, 18, 24), (110, 200, 14, 14)]
    arms = [
        [((60, 60), (15, 20), 4), ((60, 60), (130, 30), 5), ((60, 60), (30, 110), 3)],
        [((90, 130), (20, 150), 4), ((90, 130), (150, 110), 6)],
        [((110, 200), (40, 225), 3), ((110, 200), (150, 235), 4)],
    ]
    for label, ((r, c, a, b), limbs) in enumerate(zip(bodies, arms, strict=True), 1):
        cell = ((rows - r) / a) ** 2 + ((cols - c) / b) ** 2 <= 1.0
        for p, q, radius in limbs:
            cell |= _segment(shape, p, q, radius)
        out[cell & (out == 0)] = label
    return out


def vessel() -> np.ndarray:
    """A 40 × 96 × 96 boolean volume: a trunk that forks twice, tubes of decreasing
    radius."""
    shape = (40, 96, 96)
    tubes = [
        ((20, 48, 4), (20, 48, 44), 6),
        ((20, 48, 44), (12, 16, 80), 4),
        ((20, 48, 44), (28, 80, 76), 4),
        ((24, 64, 60), (34, 84, 40), 3),
    ]
    out = np.zeros(shape, bool)
    for a, b, radius in tubes:
        out |= _segment(shape, a, b, radius)
    return out


def sample_cells() -> LayerData:
    """napari's sample-data contribution: the label image of :func:`cells`."""
    return [(cells(), {"name": "cells"}, "labels")]


def sample_vessel() -> LayerData:
    """napari's sample-data contribution: the volume of :func:`vessel`."""
    return [(vessel().astype(np.uint8), {"name": "vessel"}, "labels")]
