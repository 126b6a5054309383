"""What one input may cost: :class:`Limits`, the one record of them, and the size of an
answer's image, which counts against them.

:func:`skelprune.prune` takes a ``limits`` value and holds the input to it: the pixels
and positions before they are read, the estimated memory and time
(:mod:`skelprune.budget`) before any work, and the answer's image. The service, a
data-set run and the command line pass theirs; a library call has none by default.
"""

from __future__ import annotations

from dataclasses import dataclass

from .errors import ImageTooLargeError
from .options import OutputOptions

__all__ = ["DATASET_LIMITS", "Limits", "overlay_pixels", "projections_scale"]


@dataclass(frozen=True)
class Limits:
    """What one input may cost; ``None``: no limit.

    ``memory_mb``: memory for one input, what the process holds already included; an
    input whose estimate is over it is refused before any work (``job-too-large``), and
    so is one that runs out all the same. ``seconds``: the time an input may be expected
    to take (the same estimate). ``max_pixels``: the largest image, raster, volume (its
    voxels, from a file's header before it is read) or answer image; ``max_vertices``:
    the largest polygon (its positions).

    >>> Limits(memory_mb=64).memory
    67108864
    """

    memory_mb: int | None = None
    seconds: float | None = None
    max_pixels: int | None = None
    max_vertices: int | None = None

    @property
    def memory(self) -> int | None:
        """The memory limit in bytes."""
        return None if self.memory_mb is None else self.memory_mb * 2**20


#: The limits of a data-set run unless told otherwise: the service's defaults.
DATASET_LIMITS = Limits(memory_mb=2048, seconds=30.0, max_pixels=4096 * 4096, max_vertices=100_000)


def overlay_pixels(shape: tuple[int, ...], output: OutputOptions, max_pixels: int | None) -> int:
    """Pixels of an image's overlay at ``output``'s scale.

    Raises
    ------
    ImageTooLargeError
        When ``overlay_scale`` makes the overlay larger than ``max_pixels``.
    """
    from .output.render import auto_scale

    scale = auto_scale(shape) if output.overlay_scale is None else output.overlay_scale
    height, width = shape[0] * scale, shape[1] * scale
    if max_pixels is not None and width * height > max_pixels:
        raise ImageTooLargeError(
            f"the overlay image would have {width * height} pixels ({width}×{height}: "
            f"overlay_scale {scale} on {shape[1]}×{shape[0]}), the limit is "
            f"{max_pixels}; use a smaller overlay_scale"
        )
    return width * height


def projections_scale(
    shape: tuple[int, ...], output: OutputOptions, max_pixels: int | None
) -> tuple[int, int]:
    """The scale and pixels of a volume's projections image: ``overlay_scale``, or the
    default scale made smaller until the image fits ``max_pixels``.

    Raises
    ------
    ImageTooLargeError
        When the image is over ``max_pixels`` at the scale asked for (or at 1).
    """
    from .output.volume import auto_volume_scale

    z, y, x = shape
    base = (y + z + 4) * (x + z + 4)
    given = output.overlay_scale
    scale = given or auto_volume_scale(shape)
    if given is None and max_pixels is not None:
        while scale > 1 and base * scale * scale > max_pixels:
            scale -= 1
    pixels = base * scale * scale
    if max_pixels is not None and pixels > max_pixels:
        raise ImageTooLargeError(
            f"the projections image would have {pixels} pixels (overlay_scale {scale} "
            f"on a {x}×{y}×{z} volume), the limit is {max_pixels}; use a smaller "
            "overlay_scale"
        )
    return scale, pixels
