"""Property-based fuzzing of the input decoders and of the HTTP endpoint.

Whatever bytes or JSON arrive, the PNG decoder (``read_mask``, ``png_size``) and the
polygon decoder (``parse_geojson``, ``polygon_mask``) either succeed with a well-formed
answer or raise a documented :class:`skelprune.SkelpruneError`; nothing else, ever.
The endpoint, fed the same material, never answers 5xx.

Every property records what it generated (``hypothesis.event``, shown by
``pytest --hypothesis-show-statistics``) and counts the outcomes: a property whose
generator is meant to reach the success path asserts that it did, so a generator that
only made rejected inputs cannot pass unnoticed.

Bounded: a fixed number of examples per property (``FUZZ_EXAMPLES``, default 150; set
``SKELPRUNE_FUZZ_EXAMPLES`` higher for a long exploratory run), no deadline, derandomised
so that the suite is repeatable.
"""

from __future__ import annotations

import io
import json
import math
import os
import struct
import zlib
from collections import Counter
from typing import Any

import numpy as np
import pytest
from fastapi.testclient import TestClient
from hypothesis import HealthCheck, assume, event, given, settings
from hypothesis import strategies as st
from PIL import Image

from skelprune.errors import SkelpruneError
from skelprune.io.png import PNG_SIGNATURE, png_size, read_mask
from skelprune.io.polygon import parse_geojson, polygon_mask
from testkit.pngfile import chunk as _chunk

pytestmark = pytest.mark.timeout(600)

FUZZ_EXAMPLES = int(os.environ.get("SKELPRUNE_FUZZ_EXAMPLES", "150"))
MAX_PIXELS = 1 << 18
FUZZ = settings(
    max_examples=FUZZ_EXAMPLES,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)


# ------------------------------------------------------------------- seed PNGs
def _save(im: Image.Image, **kw: Any) -> bytes:
    buf = io.BytesIO()
    im.save(buf, "PNG", **kw)
    return buf.getvalue()


def _seeds() -> list[bytes]:
    mask = np.zeros((12, 16), np.uint8)
    mask[2:10, 3:13] = 1
    mask[5:7, 6:9] = 0
    pal = Image.fromarray(mask, "P")
    pal.putpalette([255, 255, 255, 10, 200, 30] + [0] * 762)
    rgba = np.zeros((12, 16, 4), np.uint8)
    rgba[..., :3] = 90
    rgba[..., 3] = mask * 255
    rgb = np.stack([mask * 200, mask * 10, mask * 0 + 7], axis=-1).astype(np.uint8)
    # A hand-written 16-bit RGB file with a tRNS colour key and several IDAT chunks.
    rows = np.zeros((6, 5, 3), ">u2")
    rows[1:5, 1:4] = 40000
    raw = zlib.compress(b"".join(b"\x00" + r.tobytes() for r in rows))
    hand = (
        PNG_SIGNATURE
        + _chunk(b"IHDR", struct.pack(">IIBBBBB", 5, 6, 16, 2, 0, 0, 0))
        + _chunk(b"tRNS", b"\x00\x00" * 3)
        + _chunk(b"IDAT", raw[:10])
        + _chunk(b"IDAT", raw[10:])
        + _chunk(b"IEND", b"")
    )
    return [
        _save(Image.fromarray(mask * 255)),
        _save(Image.fromarray(mask.astype(bool))),
        _save(Image.fromarray(mask.astype(np.uint16) * 50000)),
        _save(pal, transparency=0),
        _save(pal),
        _save(Image.fromarray(rgba, "RGBA")),
        _save(Image.fromarray(rgb, "RGB"), transparency=(0, 0, 7)),
        _save(Image.fromarray(np.stack([mask * 255, mask * 255], -1).astype(np.uint8), "LA")),
        hand,
    ]


SEEDS = _seeds()


def chunk_spans(data: bytes) -> list[tuple[int, int]]:
    """(start, end) of each complete chunk of a well-formed PNG."""
    spans, pos = [], 8
    while pos + 12 <= len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        end = pos + 12 + length
        if end > len(data):
            break
        spans.append((pos, end))
        pos = end
    return spans


def fix_crcs(data: bytes) -> bytes:
    """Recompute every CRC, so a mutation reaches the decoder instead of the CRC check."""
    out = bytearray(data)
    for start, end in chunk_spans(data):
        out[end - 4 : end] = struct.pack(">I", zlib.crc32(bytes(out[start + 4 : end - 4])))
    return bytes(out)


@st.composite
def mutated_pngs(draw: st.DrawFn) -> bytes:
    data = bytearray(draw(st.sampled_from(SEEDS)))
    spans = chunk_spans(bytes(data))
    for _ in range(draw(st.integers(1, 4))):
        op = draw(
            st.sampled_from(
                [
                    "flip",
                    "byte",
                    "truncate",
                    "length",
                    "crc",
                    "insert",
                    "delete",
                    "dup-chunk",
                    "drop-chunk",
                    "ihdr",
                ]
            )
        )
        if not data:
            break
        pos = draw(st.integers(0, len(data) - 1))
        if op == "flip":
            data[pos] ^= 1 << draw(st.integers(0, 7))
        elif op == "byte":
            data[pos] = draw(st.integers(0, 255))
        elif op == "truncate":
            del data[pos:]
        elif op == "insert":
            data[pos:pos] = draw(st.binary(min_size=1, max_size=16))
        elif op == "delete":
            del data[pos : pos + draw(st.integers(1, 16))]
        elif spans:
            start, end = draw(st.sampled_from(spans))
            if end > len(data):
                continue
            if op == "length":
                value = draw(
                    st.one_of(
                        st.integers(0, 64),
                        st.sampled_from([0x7FFFFFFF, 0x80000000, 0xFFFFFFFF, end - start - 12 + 1]),
                    )
                )
                data[start : start + 4] = struct.pack(">I", value)
            elif op == "crc":
                data[end - 4 : end] = draw(st.binary(min_size=4, max_size=4))
            elif op == "dup-chunk":
                data[end:end] = data[start:end]
            elif op == "drop-chunk":
                del data[start:end]
            elif op == "ihdr":  # any IHDR field: size, depth, colour type, interlace ...
                w, h = draw(st.integers(0, 70_000)), draw(st.integers(0, 70_000))
                fields = struct.pack(
                    ">IIBBBBB",
                    w,
                    h,
                    draw(st.sampled_from([1, 2, 4, 8, 16, 3])),
                    draw(st.sampled_from([0, 2, 3, 4, 6, 1, 7])),
                    draw(st.integers(0, 1)),
                    draw(st.integers(0, 1)),
                    draw(st.integers(0, 2)),
                )
                if len(data) >= 29:
                    data[16:29] = fields
    if draw(st.booleans()):
        return fix_crcs(bytes(data))
    return bytes(data)


def outcome(name: str) -> str:
    """Record one generated case's outcome with hypothesis, and return it for counting."""
    event(name)
    return name


def rejected(exc: SkelpruneError) -> str:
    return outcome(f"rejected: {type(exc).__name__}")


def check_mask(source: bytes, max_pixels: int | None) -> str:
    try:
        mask = read_mask(source, max_pixels=max_pixels)
    except SkelpruneError as exc:
        return rejected(exc)
    assert isinstance(mask, np.ndarray) and mask.dtype == bool and mask.ndim == 2
    assert mask.size > 0 and mask.flags.c_contiguous
    assert max_pixels is None or mask.size <= max_pixels
    w, h = png_size(source)
    assert mask.shape == (h, w)
    return outcome("decoded")


# --------------------------------------------------------------------- PNG fuzz
@FUZZ
@given(st.binary(max_size=512))
def test_random_bytes(data: bytes) -> None:
    # Random bytes are almost never a PNG: this property is about the rejections.
    check_mask(data, MAX_PIXELS)
    try:
        w, h = png_size(data)
    except SkelpruneError:
        return
    assert w > 0 and h > 0


@FUZZ
@given(st.binary(max_size=300))
def test_random_bytes_behind_a_signature(tail: bytes) -> None:
    check_mask(PNG_SIGNATURE + tail, MAX_PIXELS)


def test_mutated_pngs() -> None:
    seen: Counter[str] = Counter()

    @FUZZ
    @given(mutated_pngs())
    def prop(data: bytes) -> None:
        seen[check_mask(data, MAX_PIXELS)] += 1

    prop()
    assert seen["decoded"] > 0, seen


def test_mutated_pngs_without_a_pixel_limit() -> None:
    seen: Counter[str] = Counter()

    @settings(FUZZ, max_examples=max(10, FUZZ_EXAMPLES // 5))
    @given(mutated_pngs())
    def prop(data: bytes) -> None:
        # Pillow's own decompression-bomb guard is the last line here; it must come out
        # as a SkelpruneError too. Keep the claimed size modest so a success stays cheap.
        try:
            w, h = png_size(data)
        except SkelpruneError as exc:
            seen[rejected(exc)] += 1
            return
        assume(w * h <= 4 * MAX_PIXELS)
        seen[check_mask(data, None)] += 1

    prop()
    assert seen["decoded"] > 0, seen


def test_seeds_decode() -> None:
    for data in SEEDS:
        assert read_mask(data).any()


# ----------------------------------------------------------------- polygon fuzz
NUMBERS = st.one_of(
    st.integers(-(10**6), 10**6),
    st.integers(),  # arbitrary precision: 10**400 cannot be converted to a float
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(-1e3, 1e3),
    st.sampled_from(
        [0, 1, -1, 1e308, -1e308, 5e-324, 2**53 + 1, 10**400, -(10**400), True, None, "1"]
    ),
)
POSITIONS = st.lists(NUMBERS, min_size=0, max_size=4)
SMALL = st.floats(-100, 100, allow_nan=False)
RINGS = st.one_of(
    st.lists(POSITIONS, max_size=8),
    # closed rings of plausible coordinates: these reach shapely and the rasteriser
    st.lists(st.tuples(SMALL, SMALL).map(list), min_size=3, max_size=12).map(lambda r: [*r, r[0]]),
    st.lists(
        st.tuples(st.integers(-3, 3), st.integers(-3, 3)).map(list), min_size=3, max_size=8
    ).map(lambda r: [*r, r[0]]),
)
POLYGON_COORDS = st.lists(RINGS, max_size=3)
JSONISH = st.recursive(
    st.none() | st.booleans() | NUMBERS | st.text(max_size=8),
    lambda inner: (
        st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=6), inner, max_size=4)
    ),
    max_leaves=12,
)


@st.composite
def valid_polygons(draw: st.DrawFn) -> dict[str, Any]:
    """A well-formed Polygon (a rectangle, maybe with a rectangular hole): the success
    path must be among what the fuzzers reach."""
    x0, y0 = draw(st.floats(-1e3, 1e3)), draw(st.floats(-1e3, 1e3))
    w, h = draw(st.floats(4, 200)), draw(st.floats(4, 200))
    rings = [[[x0, y0], [x0 + w, y0], [x0 + w, y0 + h], [x0, y0 + h], [x0, y0]]]
    if draw(st.booleans()):
        a, b = x0 + w / 4, y0 + h / 4
        rings.append([[a, b], [a, b + h / 2], [a + w / 2, b + h / 2], [a + w / 2, b], [a, b]])
    return {"type": "Polygon", "coordinates": rings}


@st.composite
def geojsonish(draw: st.DrawFn, depth: int = 0) -> Any:
    kind = draw(
        st.sampled_from(
            ["Polygon", "MultiPolygon", "Feature", "FeatureCollection", "junk", "Point", "valid"]
        )
    )
    if kind == "valid":
        return draw(valid_polygons())
    if kind == "Polygon":
        obj: Any = {"type": "Polygon", "coordinates": draw(POLYGON_COORDS | JSONISH)}
    elif kind == "MultiPolygon":
        obj = {
            "type": "MultiPolygon",
            "coordinates": draw(st.lists(POLYGON_COORDS, max_size=3) | JSONISH),
        }
    elif kind in ("Feature", "FeatureCollection") and depth < 2:
        inner = st.deferred(lambda: geojsonish(depth + 1))
        if kind == "Feature":
            obj = {"type": "Feature", "geometry": draw(inner | JSONISH)}
        else:
            obj = {"type": "FeatureCollection", "features": draw(st.lists(inner, max_size=3))}
    elif kind == "Point":
        obj = {"type": draw(JSONISH | st.just("Point")), "coordinates": draw(JSONISH)}
    else:
        return draw(JSONISH)
    if draw(st.booleans()):
        obj.pop(draw(st.sampled_from(sorted(obj))))
    return obj


RASTER = st.one_of(
    st.fixed_dictionaries({"longest_side": st.integers(1, 96)}),
    st.fixed_dictionaries({"pixel_size": st.floats(1e-3, 50)}),
    st.fixed_dictionaries({"pixel_size": st.floats(allow_nan=True, allow_infinity=True)}),
    st.fixed_dictionaries(
        {"longest_side": st.one_of(st.integers(), st.floats(), st.booleans(), st.none())}
    ),
)


def test_parse_geojson() -> None:
    seen: Counter[str] = Counter()

    @FUZZ
    @given(geojsonish(), st.booleans())
    def prop(obj: Any, repair: bool) -> None:
        try:
            geom = parse_geojson(obj, max_vertices=200, repair=repair)
        except SkelpruneError as exc:
            seen[rejected(exc)] += 1
            return
        assert geom.is_valid and geom.area > 0 and math.isfinite(geom.area)
        seen[outcome("parsed")] += 1

    prop()
    assert seen["parsed"] > 0, seen


def test_polygon_mask() -> None:
    seen: Counter[str] = Counter()

    @FUZZ
    @given(st.one_of(valid_polygons(), geojsonish()), RASTER, st.booleans())
    def prop(obj: Any, raster: dict[str, Any], repair: bool) -> None:
        try:
            mask, frame = polygon_mask(
                obj, max_vertices=200, max_pixels=MAX_PIXELS, repair=repair, **raster
            )
        except SkelpruneError as exc:
            seen[rejected(exc)] += 1
            return
        assert mask.dtype == bool and mask.ndim == 2 and 0 < mask.size <= MAX_PIXELS
        assert math.isfinite(frame.pixel_size) and frame.pixel_size > 0
        seen[outcome("rasterised")] += 1

    prop()
    assert seen["rasterised"] > 0, seen


@pytest.mark.parametrize(
    "value",
    [10**400, -(10**400), math.nan, math.inf, "1", None, True, [1.0], {"x": 1}],
    ids=["huge-int", "huge-negative-int", "nan", "inf", "str", "null", "bool", "list", "dict"],
)
def test_nasty_coordinate_in_a_ring(value: Any) -> None:
    """Found while writing the fuzzer: a Python int too big for a float (possible from
    ``json.loads``) raised OverflowError instead of InvalidPolygonError."""
    ring = [[0, 0], [4, 0], [value, 3], [0, 3], [0, 0]]
    with pytest.raises(SkelpruneError, match=r"\$\.coordinates\[0\]\[2\]"):
        polygon_mask({"type": "Polygon", "coordinates": [ring]})


@pytest.mark.parametrize("raster", [{}, {"longest_side": 10**5000}])
def test_huge_int_type_and_option_are_reported(raster: dict[str, Any]) -> None:
    """``repr`` of an int past 4300 digits raises ValueError: messages must not use it."""
    obj = (
        {"type": 10**5000}
        if not raster
        else {"type": "Polygon", "coordinates": [[[0, 0], [4, 0], [4, 3], [0, 0]]]}
    )
    with pytest.raises(SkelpruneError, match="<integer of 16610 bits>"):
        polygon_mask(obj, **raster)


@pytest.mark.parametrize("repair", [True, False])
def test_ring_collapsed_to_a_point_with_holes(repair: bool) -> None:
    """Found by the fuzzer: shapely's make_valid raised GEOSException ("Overlay input is
    mixed-dimension") on an exterior collapsed to one point, with holes."""
    point = [[0.0, 0.0]] * 9
    obj = {
        "type": "Polygon",
        "coordinates": [point, [[1, -3], [1, -3], [2, 3], [1, -1], [1, -3]], point],
    }
    with pytest.raises(SkelpruneError, match="zero area" if repair else "Too few points"):
        parse_geojson(obj, repair=repair)


def test_second_ihdr_cannot_smuggle_a_size() -> None:
    """Found by the fuzzer: Pillow decodes with the *last* IHDR, the size check read the
    first, so a second header could claim any size behind a small first one."""
    small = _chunk(b"IHDR", struct.pack(">IIBBBBB", 16, 12, 8, 0, 0, 0, 0))
    big = _chunk(b"IHDR", struct.pack(">IIBBBBB", 16, 5000, 8, 0, 0, 0, 0))
    raw = zlib.compress(b"\x00" * 17 * 5000)
    data = PNG_SIGNATURE + small + big + _chunk(b"IDAT", raw) + _chunk(b"IEND", b"")
    assert png_size(data) == (16, 12)
    with pytest.raises(SkelpruneError, match="second IHDR"):
        read_mask(data, max_pixels=1000)


# -------------------------------------------------------------------- HTTP fuzz
SETTINGS = {
    "workers": 1,
    "queue_size": 8,
    "max_pixels": MAX_PIXELS,
    "max_vertices": 200,
    "max_body_bytes": 64 * 1024,
}


QUERY = st.dictionaries(
    st.sampled_from(
        [
            "beta",
            "method",
            "coarse",
            "curve",
            "overlay",
            "pixel_size",
            "longest_side",
            "repair",
            "dce_threshold",
            "x",
        ]
    ),
    st.one_of(
        st.text(max_size=6),
        st.sampled_from(
            ["0", "-1", "nan", "inf", "1e309", "9", "0.5", "true", "false", "dce", "none", "64"]
        ),
    ),
    max_size=3,
)
#: Queries with valid values only, beside the arbitrary ones, so that some requests succeed.
VALID_QUERY = st.dictionaries(
    st.sampled_from(["beta", "method", "coarse", "curve"]),
    st.sampled_from(["9", "0.5", "true", "false"]),
    max_size=1,
).filter(
    lambda q: all(
        (k in ("beta",) and v in ("9", "0.5")) or (k == "curve" and v in ("true", "false"))
        for k, v in q.items()
    )
)
HTTP = settings(FUZZ, max_examples=max(10, FUZZ_EXAMPLES // 3))


def assert_no_5xx(resp: Any) -> str:
    """The answer is a success or a problem+json 4xx; returns which, as an outcome."""
    assert resp.status_code < 500, resp.text
    if resp.status_code >= 400:
        assert resp.headers["content-type"] == "application/problem+json"
        assert resp.json()["detail"]
    return outcome(f"HTTP {resp.status_code}")


def test_http_png_bodies(client: TestClient) -> None:
    seen: Counter[str] = Counter()

    @HTTP
    @given(
        st.one_of(st.sampled_from(SEEDS), mutated_pngs(), st.binary(max_size=200)),
        st.one_of(VALID_QUERY, QUERY),
        st.sampled_from(["image/png", "multipart"]),
    )
    def prop(data: bytes, query: dict[str, str], how: str) -> None:
        if how == "multipart":
            resp = client.post(
                "/v1/prune", files={"file": ("f.png", data, "image/png")}, params=query
            )
        else:
            resp = client.post(
                "/v1/prune", content=data, params=query, headers={"content-type": "image/png"}
            )
        seen[assert_no_5xx(resp)] += 1

    prop()
    assert seen["HTTP 200"] > 0, seen


def test_http_polygon_bodies(client: TestClient) -> None:
    seen: Counter[str] = Counter()

    @HTTP
    @given(
        st.one_of(
            valid_polygons(),
            geojsonish(),
            st.fixed_dictionaries(
                {"geojson": geojsonish()}, optional={"beta": NUMBERS, "longest_side": NUMBERS}
            ),
        ),
        st.one_of(VALID_QUERY, QUERY),
    )
    def prop(obj: Any, query: dict[str, str]) -> None:
        try:
            body = json.dumps(obj)  # NaN / Infinity become the JSON5-ish literals on purpose
        except (ValueError, OverflowError):
            seen[outcome("not JSON")] += 1
            return
        resp = client.post(
            "/v1/prune", content=body, params=query, headers={"content-type": "application/json"}
        )
        seen[assert_no_5xx(resp)] += 1

    prop()
    assert seen["HTTP 200"] > 0, seen
