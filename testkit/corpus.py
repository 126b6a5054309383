"""A corpus of every kind of input, written as files, with the options and answers each
is asked for: what the four fronts (library, command line, service, data-set runs) must
answer with the same bytes (tests/service/test_four_fronts.py).

Small on purpose (each input prunes in well under a second): the point is the ways
through, not the pruning.
"""

from __future__ import annotations

import io
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

#: The answers of a 2-D input and of a volume.
PLANAR_ANSWERS = ("json", "geojson", "csv", "graphml", "png")
VOLUME_ANSWERS = ("json", "csv", "png", "swc")


@dataclass(frozen=True)
class Case:
    """One input file, the options it is pruned with and the answers asked of it."""

    name: str
    path: Path
    options: dict[str, Any] = field(default_factory=dict)
    answers: tuple[str, ...] = PLANAR_ANSWERS
    media: str = "image/png"  # the service's Content-Type for the file's bytes

    @property
    def is_volume(self) -> bool:
        return self.answers == VOLUME_ANSWERS


def _png(path: Path, image: np.ndarray) -> Path:
    Image.fromarray(image).save(path)
    return path


def _lake() -> dict[str, Any]:
    """A lake with two islands (holes): the shape whose junction angles can be undefined."""
    outer = [[0, 0], [120, 0], [120, 80], [0, 80], [0, 0]]
    islands = [
        [[30, 30], [45, 30], [45, 50], [30, 50], [30, 30]],
        [[75, 25], [90, 25], [90, 55], [75, 55], [75, 25]],
    ]
    return {"type": "Polygon", "coordinates": [outer, *islands]}


def _geotiff(mask: np.ndarray) -> bytes:
    """A GeoTIFF's bytes as GDAL writes its tags: 2 m pixels, UTM 33N."""
    import tifffile

    buf = io.BytesIO()
    tags = [
        (33550, 12, 3, (2.0, 2.0, 0.0)),
        (33922, 12, 6, (0.0, 0.0, 0.0, 500_000.0, 6_600_000.0, 0.0)),
        (34735, 3, 16, (1, 1, 0, 3, 1024, 0, 1, 1, 1025, 0, 1, 1, 3072, 0, 1, 32633)),
    ]
    tifffile.imwrite(buf, mask, extratags=tags)
    return buf.getvalue()


def _tube(shape: tuple[int, int, int] = (12, 16, 40)) -> np.ndarray:
    """A bent tube: a bar along x with a branch up along y."""
    vol = np.zeros(shape, bool)
    vol[3:9, 4:10, 3:37] = True
    vol[3:9, 4:15, 18:24] = True
    return vol


def write_corpus(folder: Path) -> list[Case]:
    """Write every input below ``folder``; the cases, in a fixed order."""
    folder.mkdir(parents=True, exist_ok=True)
    cases = []
    mask = np.zeros((60, 90), np.uint8)
    mask[10:50, 10:80] = 255
    mask[25:35, 80:88] = 255  # a stub off the right side
    mask[0:20, 40:50] = 255  # an arm cut by the image's top border
    cases.append(Case("mask", _png(folder / "mask.png", mask)))
    labels = np.zeros((40, 70), np.uint8)
    labels[5:35, 5:35] = 1
    labels[5:35, 35:65] = 2  # touching label 1
    labels[15:25, 20:50] = 3  # across both
    cases.append(Case("labels", _png(folder / "labels.png", labels), {"labels": True}))
    dots = np.zeros((30, 30), np.uint8)
    dots[5, 5] = dots[20, 8] = 255  # one-pixel components
    dots[10:12, 10:25] = 255  # a line two pixels wide
    cases.append(Case("dots", _png(folder / "dots.png", dots)))
    lake = folder / "lake.geojson"
    lake.write_text(json.dumps(_lake()))
    cases.append(Case("lake", lake, {"pixel_size": 1.0}, media="application/geo+json"))
    utm = folder / "utm.geojson"
    ring = [[500_000 + x, 6_600_000 + y] for x, y in [[0, 0], [400, 0], [400, 40], [0, 40], [0, 0]]]
    utm.write_text(json.dumps({"type": "Polygon", "coordinates": [ring]}))
    cases.append(
        Case("utm", utm, {"crs": "EPSG:32633", "pixel_size": 2.0}, media="application/geo+json")
    )
    strip = np.zeros((60, 200), np.uint8)
    strip[20:40, 10:190] = 1
    geotiff = folder / "strip.tif"
    geotiff.write_bytes(_geotiff(strip))
    cases.append(Case("geotiff", geotiff, media="image/tiff"))
    npy = folder / "tube.npy"
    np.save(npy, _tube())
    cases.append(Case("volume", npy, {"spacing": "2,1,1"}, VOLUME_ANSWERS, "application/x-npy"))
    import tifffile

    stack = folder / "stack.tif"
    tifffile.imwrite(stack, _tube((10, 14, 30)).astype(np.uint8) * 255)
    cases.append(Case("stack", stack, {}, VOLUME_ANSWERS, "image/tiff"))
    return cases


def library_options(options: dict[str, Any]) -> dict[str, Any]:
    """A case's options as :func:`skelprune.prune` takes them (``spacing`` a tuple)."""
    out = dict(options)
    if "spacing" in out:
        out["spacing"] = tuple(float(v) for v in str(out["spacing"]).split(","))
    return out


def cli_flags(options: dict[str, Any]) -> list[str]:
    """A case's options as the command line's flags."""
    flags = []
    for name, value in options.items():
        flag = "--" + name.replace("_", "-")
        if value is True:
            flags.append(flag)
        elif value is False:
            flags.append("--no-" + name.replace("_", "-"))
        else:
            flags += [flag, str(value)]
    return flags


def query(options: dict[str, Any]) -> dict[str, str]:
    """A case's options as the service's query."""
    return {k: str(v).lower() if isinstance(v, bool) else str(v) for k, v in options.items()}
