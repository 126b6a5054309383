"""The bad-input catalogue: every request a careless or hostile client may send.

One table. Each row is a request and the answer it must get: a 4xx
``application/problem+json`` whose ``detail`` names the problem (never a 5xx), or,
for the odd-but-valid inputs (16-bit, palette with transparency, RGBA, one pixel, all
foreground, a self-intersecting polygon that gets repaired), a normal 200 document.
"""

from __future__ import annotations

import io
import json
import struct
import zlib
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pytest
from fastapi.testclient import TestClient
from PIL import Image

from service.http.schemas import Problem, PruneDocument
from testkit.pngfile import chunk

pytestmark = pytest.mark.timeout(300)

LIMITS = {"max_pixels": 1_000_000, "max_body_bytes": 200_000, "max_vertices": 1000}
PROBLEM = "application/problem+json"
RECT = [[0.0, 0.0], [40.0, 0.0], [40.0, 20.0], [0.0, 20.0], [0.0, 0.0]]
BOW_TIE = [[0, 0], [10, 10], [10, 0], [0, 10], [0, 0]]


# ----------------------------------------------------------------------- builders
def header_only_png(width: int, height: int, depth: int = 8, colour: int = 0) -> bytes:
    """Signature + a valid IHDR claiming ``width`` × ``height``, then nothing useful."""
    ihdr = struct.pack(">IIBBBBB", width, height, depth, colour, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + b"\x00" * 64


def save(im: Image.Image, **kw: Any) -> bytes:
    buf = io.BytesIO()
    im.save(buf, "PNG", **kw)
    return buf.getvalue()


def shape(h: int = 30, w: int = 50) -> np.ndarray:
    mask = np.zeros((h, w), bool)
    mask[5:25, 5:45] = True
    mask[12:18, 20:30] = False  # a hole
    return mask


def grey_png(mask: np.ndarray) -> bytes:
    return save(Image.fromarray(mask.astype(np.uint8) * 255))


def png16() -> bytes:
    return save(Image.fromarray(shape().astype(np.uint16) * 40000))


def palette_transparent_png() -> bytes:
    im = Image.fromarray(shape().astype(np.uint8), "P")  # index 0 outside, 1 inside
    im.putpalette([255, 255, 255, 200, 30, 30] + [0] * (256 * 3 - 6))
    return save(im, transparency=0)  # entry 0 (white!) is transparent


def rgba_png() -> bytes:
    rgba = np.full((*shape().shape, 4), 255, np.uint8)  # white everywhere ...
    rgba[..., 3] = shape() * 255  # ... but only the shape is opaque
    return save(Image.fromarray(rgba, "RGBA"))


def crc_corrupt_png() -> bytes:
    data = bytearray(grey_png(shape()))
    data[29] ^= 0xFF  # a byte of the IHDR payload: its CRC no longer matches
    return bytes(data)


def bad_zlib_png() -> bytes:
    ihdr = struct.pack(">IIBBBBB", 4, 4, 8, 0, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", ihdr)
        + chunk(b"IDAT", b"not zlib at all")
        + chunk(b"IEND", b"")
    )


def bad_depth_png() -> bytes:
    ihdr = struct.pack(">IIBBBBB", 4, 4, 3, 2, 0, 0, 0)  # RGB at 3 bits: not a PNG format
    raw = zlib.compress(b"\x00" * 20)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", raw) + chunk(b"IEND", b"")


def second_ihdr_png() -> bytes:
    """A small first IHDR (what the size check reads), a huge second one (what Pillow used)."""
    small = chunk(b"IHDR", struct.pack(">IIBBBBB", 16, 12, 8, 0, 0, 0, 0))
    big = chunk(b"IHDR", struct.pack(">IIBBBBB", 16, 100_000, 8, 0, 0, 0, 0))
    raw = zlib.compress(b"\x00" * 17 * 100_000)
    return b"\x89PNG\r\n\x1a\n" + small + big + chunk(b"IDAT", raw) + chunk(b"IEND", b"")


def polygon(*rings: Any) -> dict[str, Any]:
    return {"type": "Polygon", "coordinates": list(rings)}


def many_vertices(n: int) -> dict[str, Any]:
    t = np.linspace(0, 2 * np.pi, n - 1, endpoint=False)
    ring = [[float(np.cos(a)), float(np.sin(a))] for a in t]
    return polygon([*ring, ring[0]])


def deep_json(depth: int) -> bytes:
    return b'{"type": "Polygon", "coordinates": ' + b"[" * depth + b"]" * depth + b"}"


def multipart(name: str, filename: str, data: bytes, ctype: str) -> tuple[bytes, str]:
    boundary = "catalogue-boundary"
    body = (
        (
            f'--{boundary}\r\nContent-Disposition: form-data; name="{name}"; '
            f'filename="{filename}"\r\nContent-Type: {ctype}\r\n\r\n'
        ).encode()
        + data
        + (f"\r\n--{boundary}--\r\n").encode()
    )
    return body, f"multipart/form-data; boundary={boundary}"


def multipart_files(n: int) -> tuple[bytes, str]:
    boundary = "catalogue-boundary"
    part = (
        (
            f'--{boundary}\r\nContent-Disposition: form-data; name="file"; '
            f'filename="s.png"\r\nContent-Type: image/png\r\n\r\n'
        ).encode()
        + GOOD
        + b"\r\n"
    )
    return part * n + f"--{boundary}--\r\n".encode(), f"multipart/form-data; boundary={boundary}"


def multipart_fields(n: int) -> tuple[bytes, str]:
    boundary = "catalogue-boundary"
    fields = b"".join(
        f'--{boundary}\r\nContent-Disposition: form-data; name="f{i}"\r\n\r\nx\r\n'.encode()
        for i in range(n)
    )
    body, ctype = multipart("file", "s.png", GOOD, "image/png")
    return fields + body, ctype


# ---------------------------------------------------------------------- the table
@dataclass
class Case:
    id: str
    body: bytes | None
    ctype: str | None
    status: int
    detail: tuple[str, ...] = ()  # fragments the problem's detail must contain
    params: dict[str, str] = field(default_factory=dict)
    headers: dict[str, str] = field(default_factory=dict)


def js(obj: Any) -> bytes:
    return json.dumps(obj).encode()


GOOD = grey_png(shape())
GOOD_POLY = js(polygon(RECT))
MP_PNG = multipart("file", "shape.png", GOOD, "image/png")
MP_GIF = multipart("file", "shape.gif", b"GIF89a" + b"\0" * 40, "image/gif")
MP_WRONG_FIELD = multipart("image", "shape.png", GOOD, "image/png")

CASES = [
    # --- PNG: not a PNG, broken, oversized, degenerate
    Case("not-a-png", b"\xff\xd8\xff" + b"\0" * 64, "image/png", 400, ("not a PNG", "signature")),
    # the body's bytes are another type than its Content-Type declares
    Case("gif-sent-as-png", b"GIF89a" + b"\0" * 64, "image/png", 415, ("image/gif", "image/png")),
    Case("npy-sent-as-png", b"\x93NUMPY" + b"\0" * 64, "image/png", 415, ("x-npy", "image/png")),
    Case("text-as-png", b"hello, world", "image/png", 400, ("not a PNG",)),
    Case("empty-body-png", b"", "image/png", 400, ("not a PNG",)),
    Case("truncated-png", GOOD[: len(GOOD) // 2], "image/png", 400, ("truncated PNG",)),
    Case("signature-only", GOOD[:8], "image/png", 400, ("truncated PNG",)),
    Case("crc-corrupt", crc_corrupt_png(), "image/png", 400, ("CRC mismatch", "IHDR")),
    Case("bad-zlib", bad_zlib_png(), "image/png", 400, ("cannot decode PNG",)),
    Case("bad-bit-depth", bad_depth_png(), "image/png", 400, ("PNG",)),
    Case("second-ihdr", second_ihdr_png(), "image/png", 400, ("second IHDR",)),
    Case(
        "100000x100000-header",
        header_only_png(100_000, 100_000),
        "image/png",
        413,
        ("10000000000 pixels", "100000×100000", "limit is 1000000"),
    ),
    Case(
        "max-dimension-header", header_only_png(2**31 - 1, 1), "image/png", 413, ("pixels", "limit")
    ),
    Case("0-pixel-image", header_only_png(0, 20), "image/png", 400, ("invalid size 0×20",)),
    Case("0x0-image", header_only_png(0, 0), "image/png", 400, ("invalid size",)),
    Case("1-pixel-foreground", grey_png(np.ones((1, 1), bool)), "image/png", 200),
    Case(
        "1-pixel-background", grey_png(np.zeros((1, 1), bool)), "image/png", 422, ("no foreground",)
    ),
    Case("all-zero-mask", grey_png(np.zeros((40, 40), bool)), "image/png", 422, ("no foreground",)),
    Case("all-foreground-mask", grey_png(np.ones((24, 36), bool)), "image/png", 200),
    Case("16-bit", png16(), "image/png", 200),
    Case("palette-transparency", palette_transparent_png(), "image/png", 200),
    Case("rgba", rgba_png(), "image/png", 200),
    Case("multipart-png", MP_PNG[0], MP_PNG[1], 200),
    Case("multipart-not-png", MP_GIF[0], MP_GIF[1], 400, ("corrupt GIF",)),
    Case(
        "multipart-missing-file",
        MP_WRONG_FIELD[0],
        MP_WRONG_FIELD[1],
        422,
        ("multipart field 'file'",),
    ),
    Case("multipart-no-boundary", b"--x\r\nnot a part", "multipart/form-data", 400, ("boundary",)),
    Case("multipart-two-files", *multipart_files(2), 400, ("Too many files",)),
    Case("multipart-too-many-fields", *multipart_fields(40), 400, ("Too many fields",)),
    Case(
        "multipart-empty-file",
        *multipart("file", "empty.png", b"", "image/png"),
        400,
        ("not a PNG",),
    ),
    Case(
        "form-urlencoded",
        b"file=%89PNG",
        "application/x-www-form-urlencoded",
        415,
        ("'application/x-www-form-urlencoded' is not supported",),
    ),
    Case(
        "gzip-content-encoding",
        GOOD,
        "image/png",
        415,
        ("Content-Encoding 'gzip'",),
        headers={"content-encoding": "gzip"},
    ),
    Case("content-type-in-capitals", GOOD, "IMAGE/PNG; foo=bar", 200),
    # --- polygons
    Case(
        "nan-coordinate",
        b'{"type":"Polygon","coordinates":[[[0,0],[NaN,0],[1,1],[0,0]]]}',
        "application/json",
        422,
        ("finite",),
    ),
    Case(
        "infinity-coordinate",
        b'{"type":"Polygon","coordinates":[[[0,0],[Infinity,0],[1,1],[0,0]]]}',
        "application/json",
        422,
        ("finite",),
    ),
    Case(
        "overflowing-literal",
        b'{"type":"Polygon","coordinates":[[[0,0],[1e999,0],[1,1],[0,0]]]}',
        "application/json",
        422,
        ("finite",),
    ),
    Case(
        "astronomical-coordinates",
        js(polygon([[-1e308, -1e308], [1e308, -1e308], [1e308, 1e308], [-1e308, -1e308]])),
        "application/json",
        422,
        ("too large a range",),
    ),
    Case(
        "coordinates-near-float-max",  # lengths in the answer would overflow JSON
        js(polygon([[0, 0], [1e308, 0], [1e308, 1e308], [0, 0]])),
        "application/json",
        422,
        ("too large a range", "within ±1e+150"),
    ),
    Case(
        "coordinates-area-overflows",
        js(polygon([[0, 0], [1e200, 0], [1e200, 1e200], [0, 0]])),
        "application/json",
        422,
        ("too large a range",),
    ),
    Case(
        "far-from-origin-but-small",
        js(polygon([[1e140, 1e140], [1.001e140, 1e140], [1e140, 1.001e140], [1e140, 1e140]])),
        "application/json",
        200,
    ),
    Case(
        "tiny-extent",
        js(polygon([[0, 0], [1e-300, 0], [1e-300, 1e-300], [0, 0]])),
        "application/json",
        422,
        ("zero area",),
    ),
    Case("unclosed-ring", js(polygon(RECT[:-1])), "application/json", 422, ("ring is not closed",)),
    Case("ring-of-3", js(polygon(RECT[:3])), "application/json", 422, ("at least 4",)),
    Case(
        "zero-area",
        js(polygon([[0, 0], [1, 1], [2, 2], [0, 0]])),
        "application/json",
        422,
        ("zero area",),
    ),
    Case("self-intersecting-repaired", js(polygon(BOW_TIE)), "application/json", 200),
    Case(
        "self-intersecting-refused",
        js(polygon(BOW_TIE)),
        "application/json",
        422,
        ("invalid polygon", "Self-intersection"),
        params={"repair": "false"},
    ),
    Case(
        "too-many-vertices",
        js(many_vertices(1500)),
        "application/json",
        422,
        ("too many vertices", "1500 positions", "1000 allowed"),
    ),
    Case(
        "string-coordinate",
        js(polygon([[0, 0], [1, "a"], [1, 1], [0, 0]])),
        "application/json",
        422,
        ("valid number",),
    ),
    Case(
        "collection-too-many-vertices",
        js(
            {
                "type": "FeatureCollection",
                "features": [
                    {"type": "Feature", "geometry": polygon([[i, 0], [i + 0.5, 0], [i, 1], [i, 0]])}
                    for i in range(300)
                ],
            }
        ),
        "application/json",
        422,
        ("1200 positions",),
    ),
    Case(
        "duplicate-type-key",
        b'{"type":"Polygon","type":"Point","coordinates":[[[0,0],[1,0],[1,1],[0,0]]]}',
        "application/json",
        422,
        ("'Point'",),
    ),
    Case(
        "point-geometry",
        js({"type": "Point", "coordinates": [0, 0]}),
        "application/json",
        422,
        ("'Point'",),
    ),
    Case("deeply-nested", deep_json(5000), "application/json", 422, ("body",)),
    Case("malformed-json", b'{"type": "Polygon", ', "application/json", 422, ("JSON",)),
    Case("not-utf8-json", b'{"type": "\xff\xfe"}', "application/json", 422, ("body",)),
    Case("empty-json-body", b"", "application/json", 422, ("body",)),
    Case("json-array", b"[1, 2, 3]", "application/json", 422, ("body",)),
    # --- missing and unknown fields
    Case(
        "missing-coordinates",
        js({"type": "Polygon"}),
        "application/json",
        422,
        ("coordinates", "Field required"),
    ),
    Case(
        "missing-type",
        js({"coordinates": [RECT]}),
        "application/json",
        422,
        ("geojson", "Field required"),
    ),
    Case(
        "envelope-missing-geojson",
        js({"beta": 3}),
        "application/json",
        422,
        ("geojson", "Field required"),
    ),
    Case(
        # foreign members are GeoJSON (RFC 7946 §6.1), but an option there would be ignored
        "option-inside-geojson",
        js({**polygon(RECT), "colour": "red", "beta": 3}),
        "application/json",
        422,
        ("beta", "option inside the GeoJSON"),
    ),
    Case(
        "unknown-envelope-option",
        js({"geojson": polygon(RECT), "path": "/etc/passwd"}),
        "application/json",
        422,
        ("path", "Extra inputs"),
    ),
    Case("unknown-query-parameter", GOOD, "image/png", 422, ("betta",), params={"betta": "9"}),
    # --- content type and size
    Case("wrong-content-type", GOOD, "text/plain", 415, ("'text/plain' is not supported",)),
    Case("missing-content-type", GOOD, None, 415, ("'none' is not supported",)),
    Case("png-sent-as-json", GOOD, "application/json", 422, ("JSON",)),
    Case("json-sent-as-png", GOOD_POLY, "image/png", 400, ("not a PNG",)),
    Case(
        "oversized-body", b"\0" * 300_000, "image/png", 413, ("exceeds the limit of 200000 bytes",)
    ),
    Case(
        "oversized-polygon-raster",
        GOOD_POLY,
        "application/json",
        413,
        ("exceeds the limit of 1000000",),
        params={"pixel_size": "0.01"},
    ),
    Case("not-acceptable", GOOD, "image/png", 406, ("text/html",), headers={"accept": "text/html"}),
    # --- options
    Case("beta-zero", GOOD, "image/png", 422, ("beta", "> 0"), params={"beta": "0"}),
    Case("beta-negative", GOOD, "image/png", 422, ("beta",), params={"beta": "-2"}),
    Case("beta-nan", GOOD, "image/png", 422, ("beta", "finite"), params={"beta": "nan"}),
    Case("beta-infinity", GOOD, "image/png", 422, ("beta", "finite"), params={"beta": "inf"}),
    Case("beta-not-a-number", GOOD, "image/png", 422, ("beta",), params={"beta": "nine"}),
    Case(
        "beta-zero-in-body",
        js({"geojson": polygon(RECT), "beta": 0}),
        "application/json",
        422,
        ("beta", "> 0"),
    ),
    Case(
        "unknown-method",
        GOOD,
        "image/png",
        422,
        ("method", "'bayesian' or 'dce'"),
        params={"method": "magic"},
    ),
    Case("unknown-coarse", GOOD, "image/png", 422, ("coarse",), params={"coarse": "fine"}),
    Case(
        "negative-dce-threshold",
        GOOD,
        "image/png",
        422,
        ("dce_threshold",),
        params={"method": "dce", "dce_threshold": "-1"},
    ),
    Case("curve-not-boolean", GOOD, "image/png", 422, ("curve",), params={"curve": "maybe"}),
    Case(
        "longest-side-too-small",
        GOOD_POLY,
        "application/json",
        422,
        ("longest_side",),
        params={"longest_side": "4"},
    ),
    Case(
        "pixel-size-denormal",
        GOOD_POLY,
        "application/json",
        422,
        ("pixel_size", "1e-12"),
        params={"pixel_size": "5e-324"},
    ),
    Case(
        "polygon-option-on-png",
        GOOD,
        "image/png",
        422,
        ("only apply to polygon",),
        params={"repair": "false"},
    ),
    Case(
        "png-option-on-polygon",
        GOOD_POLY,
        "application/json",
        422,
        ("only apply to image input",),
        params={"foreground": "zero"},
    ),
    Case(
        "png-option-in-polygon-body",
        js({"geojson": polygon(RECT), "foreground": "auto"}),
        "application/json",
        422,
        ("only apply to image input",),
    ),
    Case(
        "unknown-foreground",
        GOOD,
        "image/png",
        422,
        ("foreground",),
        params={"foreground": "white"},
    ),
    Case(
        "option-twice",
        js({"geojson": polygon(RECT), "beta": 2}),
        "application/json",
        422,
        ("both in the query and the body",),
        params={"beta": "3"},
    ),
]


SETTINGS = {"workers": 2, "queue_size": 64, **LIMITS}


def test_catalogue_is_big_and_unique() -> None:
    assert len(CASES) >= 25
    assert len({c.id for c in CASES}) == len(CASES)
    assert sum(c.status >= 400 for c in CASES) >= 25


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_input(client: TestClient, case: Case) -> None:
    headers = dict(case.headers)
    if case.ctype is not None:
        headers["content-type"] = case.ctype
    resp = client.post("/v1/prune", content=case.body, params=case.params, headers=headers)
    assert resp.status_code < 500, resp.text
    assert resp.status_code == case.status, resp.text
    assert "Traceback" not in resp.text and 'File "' not in resp.text
    if case.status == 200:
        assert resp.headers["content-type"] == "application/json"
        doc = PruneDocument.model_validate(resp.json())
        assert doc.components and all(c.area > 0 for c in doc.components)
        return
    assert resp.headers["content-type"] == PROBLEM
    body = resp.json()
    Problem.model_validate(body)
    assert body["status"] == case.status
    assert body["detail"] and body["title"]
    for fragment in case.detail:
        assert fragment in body["detail"], body["detail"]


def test_valid_odd_pngs_give_the_same_shape(client: TestClient) -> None:
    """16-bit, palette-with-transparency, RGBA and multipart: all read as the same mask."""
    docs = []
    for data in (GOOD, png16(), palette_transparent_png(), rgba_png()):
        resp = client.post("/v1/prune", content=data, headers={"content-type": "image/png"})
        assert resp.status_code == 200, resp.text
        docs.append(resp.json())
    # the skeletons are equal; how the shape was found is reported per file
    taken = [d.pop("foreground")["shape"] for d in docs]
    assert taken == ["light", "light", "opaque", "opaque"]
    assert all(d == docs[0] for d in docs[1:])
    assert docs[0]["components"][0]["area"] == int(shape().sum())


def test_a_number_json_cannot_write_is_null() -> None:
    """Should a non-finite number still reach the encoder, it is written as null."""
    from service.worker.jobs import dumps as _dumps

    for value in (float("inf"), float("nan"), float("-inf")):
        assert _dumps({"length": [1.0, value]}) == b'{"length":[1.0,null]}'
