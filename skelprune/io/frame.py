"""Mapping from the pixel frame of a raster to a caller's own coordinates."""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["PixelFrame"]


@dataclass(frozen=True)
class PixelFrame:
    """Affine map from pixel centres ``(col, row)`` to world ``(x, y)``.

    ``x = x0 + col * pixel_size`` and ``y = y0 - row * pixel_size`` when ``flip_y``
    (the usual GIS orientation, y growing northwards), ``y0 + row * pixel_size``
    otherwise. Radii and lengths scale by ``pixel_size``.

    Mapped values are rounded to :attr:`decimals` places: steps of at most a thousandth
    of a pixel, far below anything the raster resolves, and free of float noise such as
    ``15.049999999999997``. The identity frame (pixel input) maps nothing and rounds
    nothing: pixel centres stay exact integers and radii exact square roots.

    Examples
    --------
    >>> f = PixelFrame(x0=10.0, y0=5.0, pixel_size=0.5, flip_y=True)
    >>> f.point(2, 4)
    (11.0, 3.0)
    >>> f.distance(3.0)
    1.5
    >>> PixelFrame(x0=0.1, y0=15.25, pixel_size=0.1).point(0, 2)
    (0.1, 15.45)
    """

    x0: float = 0.0
    y0: float = 0.0
    pixel_size: float = 1.0
    flip_y: bool = False

    @property
    def decimals(self) -> int:
        """Decimal places of mapped values: the smallest with a step ≤ pixel_size / 1000."""
        return math.ceil(3 - math.log10(self.pixel_size) - 1e-9)

    def _round(self, v: float) -> float:
        return float(v) if self == IDENTITY else float(round(v, self.decimals))

    def point(self, col: float, row: float) -> tuple[float, float]:
        if self is IDENTITY:  # the same values, without a dataclass comparison each
            return (float(col), float(row))
        x = self.x0 + col * self.pixel_size
        y = self.y0 - row * self.pixel_size if self.flip_y else self.y0 + row * self.pixel_size
        return (self._round(x), self._round(y))

    def distance(self, d: float) -> float:
        if self is IDENTITY:
            return float(d)
        return self._round(d * self.pixel_size)


IDENTITY = PixelFrame()
