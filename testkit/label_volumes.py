"""Label volumes for the long-job tests and benchmark: touching tubes, each its own label."""

from __future__ import annotations

import io

import numpy as np

__all__ = ["npy_bytes", "touching_tubes"]


def touching_tubes(side: int = 512, n: int = 20, seed: int = 0) -> np.ndarray:
    """``n × n`` wavy tubes along x filling a ``side³`` volume, 16-bit labels.

    Tube ``(i, j)``'s centre line wanders a sixth of the pitch around its grid place;
    each voxel within ``0.52 × pitch`` of a centre takes the nearest tube's label, so
    that neighbours touch along their length (a label volume, not a binary one).
    """
    rng = np.random.default_rng(seed)
    pitch = side / n
    radius = 0.52 * pitch
    wander = 0.15 * pitch
    x = np.arange(side)
    nearest = np.full((side, side, side), np.inf, np.float32)
    out = np.zeros((side, side, side), np.uint16)
    values = rng.choice(np.arange(1, 65536), n * n, replace=False).astype(np.uint16)
    for i in range(n):
        for j in range(n):
            phase = rng.uniform(0, 2 * np.pi, 2)
            cz = (i + 0.5) * pitch + wander * np.sin(x / 60 + phase[0])
            cy = (j + 0.5) * pitch + wander * np.sin(x / 45 + phase[1])
            z0, z1 = max(0, int(cz.min() - radius)), min(side, int(cz.max() + radius) + 2)
            y0, y1 = max(0, int(cy.min() - radius)), min(side, int(cy.max() + radius) + 2)
            zz = np.arange(z0, z1)[:, None, None]
            yy = np.arange(y0, y1)[None, :, None]
            d2 = ((zz - cz) ** 2 + (yy - cy) ** 2).astype(np.float32)
            window = nearest[z0:z1, y0:y1]
            take = (d2 < window) & (d2 < radius * radius)
            window[take] = d2[take]
            out[z0:z1, y0:y1][take] = values[i * n + j]
    return out


def npy_bytes(volume: np.ndarray) -> bytes:
    """The volume as a ``.npy`` file's bytes (what ``Content-Type: application/x-npy`` sends)."""
    buf = io.BytesIO()
    np.save(buf, volume, allow_pickle=False)
    return buf.getvalue()
