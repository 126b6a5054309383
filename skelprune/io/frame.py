"""Mapping from the pixel frame of a raster to a caller's own coordinates."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["PixelFrame"]


@dataclass(frozen=True)
class PixelFrame:
    """Affine map from pixel centres ``(col, row)`` to world ``(x, y)``.

    ``x = x0 + col * pixel_size`` and ``y = y0 - row * pixel_size`` when ``flip_y``
    (the usual GIS orientation, y growing northwards), ``y0 + row * pixel_size``
    otherwise. Radii and lengths scale by ``pixel_size``.

    Examples
    --------
    >>> f = PixelFrame(x0=10.0, y0=5.0, pixel_size=0.5, flip_y=True)
    >>> f.point(2, 4)
    (11.0, 3.0)
    >>> f.distance(3.0)
    1.5
    """

    x0: float = 0.0
    y0: float = 0.0
    pixel_size: float = 1.0
    flip_y: bool = False

    def point(self, col: float, row: float) -> tuple[float, float]:
        x = self.x0 + col * self.pixel_size
        y = self.y0 - row * self.pixel_size if self.flip_y else self.y0 + row * self.pixel_size
        return (float(x), float(y))

    def distance(self, d: float) -> float:
        return float(d * self.pixel_size)


IDENTITY = PixelFrame()
