"""Shared helpers: dataset loading and timing medians."""

from __future__ import annotations

import time
from collections.abc import Callable

import cv2
import numpy as np
from PIL import Image

from testkit import DATA


def dataset(name: str) -> list[np.ndarray]:
    return [np.asarray(Image.open(p)) > 0 for p in sorted((DATA / name).glob("*.png"))]


def upscale(mask: np.ndarray, longest: int) -> np.ndarray:
    """Smoothly rescale a mask so its longest side is ``longest`` pixels."""
    f = longest / max(mask.shape)
    size = (round(mask.shape[1] * f), round(mask.shape[0] * f))
    return cv2.resize(mask.astype(np.float32), size, interpolation=cv2.INTER_LINEAR) >= 0.5


def median_ms(fn: Callable[[], object], repeat: int = 1) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return 1000 * float(np.median(times))


def table(header: list[str], rows: list[list[object]]) -> str:
    cells = [header] + [[f"{c:.3g}" if isinstance(c, float) else str(c) for c in r] for r in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(header))]
    lines = [
        "| " + " | ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)) + " |" for r in cells
    ]
    lines.insert(1, "|" + "|".join("-" * (w + 2) for w in widths) + "|")
    return "\n".join(lines)
