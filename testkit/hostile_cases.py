"""The red team's hostile requests, each with the answer it must get, and their
measurement against a real server.

``CASES`` is what the regression tests send (tests/service/test_hostile_files.py), and
what ``python -m testkit.hostile_measure`` sends to a real server to measure.
"""

from __future__ import annotations

import io
import json
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from PIL import Image

from .hostile_files import (
    TiffPageSpec,
    empty_pages_tiff,
    looping_tiff,
    npy_bytes,
    npy_with_header,
    tiff_with,
    tile_bomb_tiff,
    write_tiff,
)

__all__ = ["CASES", "Case", "geotiff_with", "label_png", "label_volume"]

SQUARE = {"type": "Polygon", "coordinates": [[[0, 0], [40, 0], [40, 20], [0, 20], [0, 0]]]}


@dataclass(frozen=True)
class Case:
    """One request and the statuses it may get (and words its detail must hold)."""

    name: str
    path: str
    body: Callable[[], tuple[bytes, str]]  # (bytes, content type), built when sent
    statuses: tuple[int, ...]
    words: tuple[str, ...] = ()
    params: dict[str, str] = field(default_factory=dict)
    accept: str | None = None


def _png(values: np.ndarray) -> bytes:
    buf = io.BytesIO()
    Image.fromarray(values).save(buf, "PNG")
    return buf.getvalue()


def label_png(side: int = 512) -> bytes:
    """A 16-bit PNG of touching 2×2 labels, 1 to 65,535 (and one block of 0)."""
    r, c = np.indices((side, side))
    labels = (r // 2) * (side // 2) + c // 2 + 1
    labels[labels > 65535] = 0
    return _png(labels.astype(np.uint16))


def label_volume(side: int = 48) -> bytes:
    """A ``side``³ uint16 volume of 65,535 labels, one voxel each at spread places."""
    v = np.zeros(side**3, np.uint16)
    rng = np.random.default_rng(45)
    v[rng.permutation(v.size)[:65535]] = np.arange(1, 65536, dtype=np.uint16)
    return npy_bytes(v.reshape(side, side, side))


def geotiff_with(keys: list[int] | None = None, **tags: tuple[int, Any]) -> bytes:
    """An 8×8 GeoTIFF with a tie point, a 10 m scale and ``keys`` (the GeoKey
    directory's SHORTs, default EPSG:32633); ``tags`` replace tags by name."""
    mask = np.zeros((8, 8), np.uint8)
    mask[2:6, 1:7] = 1
    named = {
        "scale": (33550, (12, [10.0, 10.0, 0.0])),
        "tie": (33922, (12, [0, 0, 0, 5e5, 6.6e6, 0])),
        "keys": (34735, (3, keys or [1, 1, 0, 2, 1024, 0, 1, 1, 3072, 0, 1, 32633])),
    }
    replace = {code: value for code, value in named.values()}
    for name, value in tags.items():
        code = named[name][0] if name in named else int(name.removeprefix("tag"))
        replace[code] = value
    page = TiffPageSpec(
        [(256, 3, [8]), (257, 3, [8]), (258, 3, [8]), (259, 3, [1]), (262, 3, [1])]
        + [(code, kind, values) for code, (kind, values) in replace.items()],
        [mask.tobytes()],
    )
    return write_tiff([page])


def _body(data: bytes, ctype: str) -> Callable[[], tuple[bytes, str]]:
    return lambda: (data, ctype)


def _lazy(make: Callable[[], bytes], ctype: str) -> Callable[[], tuple[bytes, str]]:
    return lambda: (make(), ctype)


def _form(make: Callable[[], bytes], *fields: str) -> Callable[[], tuple[bytes, str]]:
    def build() -> tuple[bytes, str]:
        data = make()
        parts = b"".join(
            b'--B\r\nContent-Disposition: form-data; name="%s"; filename="x.tif"\r\n'
            b"Content-Type: image/tiff\r\n\r\n%s\r\n" % (f.encode(), data)
            for f in fields
        )
        return parts + b"--B--\r\n", "multipart/form-data; boundary=B"

    return build


def _flat_polygon(numbers: int) -> bytes:
    return b'{"type":"Polygon","coordinates":[' + b",".join([b"0"] * numbers) + b"]}"


def _json(doc: Any) -> Callable[[], tuple[bytes, str]]:
    return lambda: (json.dumps(doc).encode(), "application/json")


TIFF, NPY = "image/tiff", "application/x-npy"
_NPY_HEADERS = {
    "npy-shape-wraps-int64": "(4294967296, 4294967296, 2)",
    "npy-shape-beyond-int64": "(99999999999999999999999, 2, 2)",
    "npy-shape-negative": "(-1, 16, 16)",
    "npy-shape-zero": "(0, 16, 16)",
    "npy-shape-bool": "(True, 16, 16)",
}
_NPY_DTYPES = {
    "npy-dtype-subarray": "('|u1', (2, 2))",
    "npy-dtype-V0": "'|V0'",
    "npy-dtype-timedelta": "'<m8[s]'",
}


def _npy_cases() -> list[Case]:
    out = []
    for name, shape in _NPY_HEADERS.items():
        header = f"{{'descr': '|u1', 'fortran_order': False, 'shape': {shape}, }}"
        big = "wraps" in name or "beyond" in name
        out.append(
            Case(
                name,
                "/v1/prune",
                _body(npy_with_header(header, bytes(4096)), NPY),
                (413,) if big else (400,),
                ("voxels",) if big else ("shape",),
            )
        )
    for name, descr in _NPY_DTYPES.items():
        header = f"{{'descr': {descr}, 'fortran_order': False, 'shape': (2, 2, 2), }}"
        out.append(
            Case(
                name,
                "/v1/prune",
                _body(npy_with_header(header, bytes(64)), NPY),
                (400,),
                ("dtype",),
            )
        )
    short = b"\x93NUMPY\x01\x00\x02\x00{}"
    out.append(Case("npy-header-length-short", "/v1/prune", _body(short, NPY), (400,), ("header",)))
    out.append(
        Case(
            "npy-header-expression",
            "/v1/prune",
            _body(
                npy_with_header("{'descr': '|u1', 'fortran_order': False, 'shape': (1+1, 2, 2), }"),
                NPY,
            ),
            (400,),
            ("header",),
        )
    )
    return out


def _tiff_cases() -> list[Case]:
    loop = looping_tiff(100)
    cases = [
        Case("tiff-page-loop", "/v1/prune", _body(loop, TIFF), (400,), ("loops",)),
        Case("tiff-page-loop-upload", "/v1/prune", _form(lambda: loop, "file"), (400,), ("loops",)),
        Case(
            "tiff-page-loop-batch",
            "/v1/prune/batch",
            _form(lambda: loop, "file"),
            (200,),
            ("loops",),
        ),
        Case(
            "tiff-page-loop-match", "/v1/match", _form(lambda: loop, "a", "b"), (400,), ("loops",)
        ),
        Case(
            "tiff-2.7M-empty-pages",
            "/v1/prune",
            _lazy(lambda: empty_pages_tiff(2_700_000), TIFF),
            (400,),
            ("4096 pages",),
        ),
        Case("tiff-tile-bomb", "/v1/prune", _lazy(tile_bomb_tiff, TIFF), (413,), ("tiles",)),
        Case(
            "tiff-tile-bomb-1MB",
            "/v1/prune",
            _lazy(lambda: tile_bomb_tiff(32768), TIFF),
            (413,),
            ("tiles",),
        ),
        Case(
            "tiff-tile-bomb-200-pages",
            "/v1/prune",
            _lazy(lambda: tile_bomb_tiff(4096, pages=200), TIFF),
            (413,),
            ("tiles",),
        ),
        Case(
            "tiff-width-two-values",
            "/v1/prune",
            _body(tiff_with({256: (3, [4, 4])}), TIFF),
            (400,),
            ("ImageWidth", "2 values"),
        ),
        Case(
            "tiff-width-ascii",
            "/v1/prune",
            _body(tiff_with({256: (2, b"4\x00")}), TIFF),
            (400,),
            ("ImageWidth", "ASCII"),
        ),
        Case(
            "tiff-bits-8-8-16",
            "/v1/prune",
            _body(tiff_with({258: (3, [8, 8, 16]), 277: (3, [3])}), TIFF),
            (400,),
            ("BitsPerSample 8,8,16",),
        ),
        Case(
            "tiff-tile-length-0",
            "/v1/prune",
            _body(tiff_with({322: (3, [16]), 323: (3, [0])}), TIFF),
            (400,),
            ("TileLength",),
        ),
        Case(
            "tiff-orientation",
            "/v1/prune",
            _body(tiff_with({274: (3, [3])}), TIFF),
            (400,),
            ("Orientation 3",),
        ),
    ]
    return cases


def _geo_cases() -> list[Case]:
    keys = [1, 1, 0, 2, 1024, 0, 1, 1, 3072, 0, 1]
    return [
        Case(
            "geotiff-scale-ascii",
            "/v1/prune",
            _body(geotiff_with(scale=(2, b"10,10\x00")), TIFF),
            (400,),
            ("ModelPixelScale",),
        ),
        Case(
            "geotiff-crs-as-doubles",
            "/v1/prune",
            _body(geotiff_with([1, 1, 0, 1, 3072, 34736, 1, 0], tag34736=(12, [32633.0])), TIFF),
            (400,),
            ("3072", "doubles"),
        ),
        Case(
            "geotiff-crs-nan",
            "/v1/prune",
            _body(
                geotiff_with([1, 1, 0, 1, 3072, 34736, 1, 0], tag34736=(12, [float("nan")])), TIFF
            ),
            (400,),
            ("3072",),
        ),
        Case(
            "geotiff-epsg-0",
            "/v1/prune",
            _body(geotiff_with([*keys, 0]), TIFF),
            (400,),
            ("code is 0",),
        ),
        Case(
            "geotiff-epsg-9999",
            "/v1/prune",
            _body(geotiff_with([*keys, 9999]), TIFF),
            (400,),
            ("EPSG:9999",),
        ),
        Case(
            "geotiff-epsg-65535",
            "/v1/prune",
            _body(geotiff_with([*keys, 65535]), TIFF),
            (400,),
            ("EPSG:65535",),
        ),
        Case(
            "geotiff-geocentric",
            "/v1/prune",
            _body(geotiff_with([1, 1, 0, 1, 1024, 0, 1, 3]), TIFF),
            (400,),
            ("geocentric",),
        ),
        Case(
            "geotiff-key-directory-short",
            "/v1/prune",
            _body(geotiff_with([1, 1, 0, 9, 1024]), TIFF),
            (400,),
            ("key directory",),
        ),
    ]


def _volume(shape: tuple[int, ...]) -> Callable[[], tuple[bytes, str]]:
    def build() -> tuple[bytes, str]:
        v = np.zeros(shape, bool)
        v[..., 100:900, 100:900] = True
        return npy_bytes(v), NPY

    return build


CASES: list[Case] = [
    *_tiff_cases(),
    Case(
        "flat-coordinates-10MB",
        "/v1/prune",
        lambda: (_flat_polygon(5_000_000), "application/json"),
        (422,),
        ("coordinates",),
    ),
    Case(
        "flat-coordinates-match",
        "/v1/match",
        lambda: (
            b'{"a":' + _flat_polygon(2_000_000) + b',"b":' + _flat_polygon(2_000_000) + b"}",
            "application/json",
        ),
        (422,),
        ("coordinates",),
    ),
    Case(
        "labels-512-65535",
        "/v1/prune",
        _lazy(label_png, "image/png"),
        (413,),
        ("components", "time limit"),
        params={"labels": "true"},
    ),
    Case(
        "volume-48-65535-labels",
        "/v1/prune",
        _lazy(label_volume, NPY),
        (413,),
        ("labels", "time limit"),
    ),
    *_npy_cases(),
    *_geo_cases(),
    Case(
        "crs-moon",
        "/v1/prune",
        _json(SQUARE),
        (422,),
        ("IAU_2015:30100", "Earth"),
        params={"crs": "IAU_2015:30100"},
    ),
    Case(
        "crs-vertical",
        "/v1/prune",
        _json(SQUARE),
        (422,),
        ("vertical",),
        params={"crs": "EPSG:5703"},
    ),
    Case(
        "crs-geocentric",
        "/v1/prune",
        _json(SQUARE),
        (422,),
        ("geocentric",),
        params={"crs": "EPSG:4978"},
    ),
    Case(
        "volume-overlay-scale-6",
        "/v1/prune",
        _volume((1, 1000, 1000)),
        (413,),
        ("overlay_scale", "limit"),
        params={"overlay_scale": "6"},
        accept="image/png",
    ),
    Case(
        "spacing-1e308-png",
        "/v1/prune",
        _volume((4, 64, 64)),
        (422,),
        ("spacing",),
        params={"spacing": "1e308,1,1"},
        accept="image/png",
    ),
    Case(
        "spacing-1e-308-csv",
        "/v1/prune",
        _volume((4, 64, 64)),
        (422,),
        ("spacing",),
        params={"spacing": "1e-308,1,1"},
        accept="text/csv",
    ),
    Case(
        "spacing-5e-324",
        "/v1/prune",
        _volume((4, 64, 64)),
        (422,),
        ("spacing",),
        params={"spacing": "5e-324,1,1"},
    ),
    Case(
        "pixel-size-1e308-csv",
        "/v1/prune",
        _json(SQUARE),
        (422,),
        ("pixel_size",),
        params={"pixel_size": "1e308"},
        accept="text/csv",
    ),
    Case(
        "pixel-size-1e308-graphml",
        "/v1/prune",
        _json(SQUARE),
        (422,),
        ("pixel_size",),
        params={"pixel_size": "1e308"},
        accept="application/graphml+xml",
    ),
    Case(
        "npy-sent-as-png",
        "/v1/prune",
        _lazy(lambda: npy_bytes(np.ones((3, 8, 8), bool)), "image/png"),
        (415,),
        ("application/x-npy",),
    ),
    Case(
        "match-accept-html",
        "/v1/match",
        _json({"a": SQUARE, "b": SQUARE}),
        (406,),
        ("text/html",),
        accept="text/html",
    ),
]
