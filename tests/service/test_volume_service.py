"""Volumes through ``POST /v1/prune``: a ``.npy`` or a TIFF stack as the body answers with
the library's 3-D document, picture or table; voxels count against the pixel limit and
the memory budget; what does not apply to a volume is refused by name."""

from __future__ import annotations

import io
import json

import numpy as np
import pytest
import tifffile
from fastapi.testclient import TestClient
from PIL import Image

import skelprune
from skelprune.options import VolumeOptions
from testkit.volumes import tube, y_tubes

SETTINGS = {"workers": 1, "queue_size": 8, "max_pixels": 200_000}
NPY = {"Content-Type": "application/x-npy"}
TIFF = {"Content-Type": "image/tiff"}


def _npy(volume: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.save(buf, volume)
    return buf.getvalue()


def _stack(volume: np.ndarray, **kwargs: object) -> bytes:
    buf = io.BytesIO()
    tifffile.imwrite(buf, volume.astype(np.uint8), photometric="minisblack", **kwargs)
    return buf.getvalue()


@pytest.fixture(scope="module")
def fork() -> np.ndarray:
    return y_tubes(radius=3.0, arm=20.0).volume()


def test_a_npy_and_a_stack_answer_the_librarys_document(
    client: TestClient, fork: np.ndarray
) -> None:
    expected = skelprune.prune(fork, spacing=(2.0, 1.0, 1.0)).to_dict()
    for body, headers in ((_npy(fork), NPY), (_stack(fork, compression="zlib"), TIFF)):
        r = client.post("/v1/prune?spacing=2,1,1", content=body, headers=headers)
        assert r.status_code == 200, r.text
        assert r.json() == json.loads(json.dumps(expected))
        assert r.json()["spacing"] == [2.0, 1.0, 1.0] and r.json()["dimensions"] == 3


def test_a_volume_as_a_picture_and_a_table(client: TestClient, fork: np.ndarray) -> None:
    res = skelprune.prune(fork)
    r = client.post("/v1/prune", content=_npy(fork), headers={**NPY, "Accept": "image/png"})
    assert r.status_code == 200 and r.headers["content-type"] == "image/png"
    from skelprune.output.volume import auto_volume_scale

    # the library's picture at the largest default scale within the pixel limit
    width, height = Image.open(io.BytesIO(r.content)).size
    assert width * height <= SETTINGS["max_pixels"]
    fits = [k for k in range(1, 17) if len(res.render_overlay(k).reshape(-1, 3)) <= 200_000]
    assert r.content == res.overlay_png(min(max(fits), auto_volume_scale(res.shape)))
    assert r.headers["x-skelprune-components"] == "1"
    assert float(r.headers["x-skelprune-rer"]) == pytest.approx(res.components[0].rer)
    r = client.post("/v1/prune", content=_npy(fork), headers={**NPY, "Accept": "text/csv"})
    assert r.status_code == 200 and r.text == res.to_csv()


@pytest.mark.parametrize(
    ("query", "accept", "words"),
    [
        ("", "application/geo+json", "has no GeoJSON answer (application/geo+json)"),
        ("", "application/graphml+xml", "has no GraphML graph (application/graphml+xml)"),
        ("?labels=true", "application/json", "only apply to image input"),
        ("?overlay=true", "application/json", "of image or polygon input"),
        ("?method=dce", "application/json", "images only"),
        ("?scope=local", "application/json", "images only"),
    ],
)
def test_what_does_not_apply_to_a_volume_is_refused(
    client: TestClient, query: str, accept: str, words: str
) -> None:
    volume = tube(length=16.0, radius=2.0).volume()
    r = client.post(f"/v1/prune{query}", content=_npy(volume), headers={**NPY, "Accept": accept})
    assert r.status_code in (400, 422), r.text
    assert words in r.json()["detail"]


def test_spacing_is_checked_and_applies_to_volumes_only(client: TestClient) -> None:
    volume = _npy(tube(length=16.0, radius=2.0).volume())
    r = client.post("/v1/prune?spacing=1,0,1", content=volume, headers=NPY)
    assert r.status_code == 422 and "spacing" in r.text
    r = client.post("/v1/prune?spacing=1,1", content=volume, headers=NPY)
    assert r.status_code == 422
    mask = np.zeros((20, 40), np.uint8)
    mask[5:15, 5:35] = 255
    png = io.BytesIO()
    Image.fromarray(mask).save(png, format="PNG")
    r = client.post(
        "/v1/prune?spacing=2,1,1", content=png.getvalue(), headers={"Content-Type": "image/png"}
    )
    assert r.status_code == 422 and "volume input" in r.json()["detail"]


def test_voxels_count_against_the_pixel_limit_before_decoding(client: TestClient) -> None:
    # a header promising 1024³ voxels and nothing after it: refused from the header
    head = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        head, {"descr": "|b1", "fortran_order": False, "shape": (1024, 1024, 1024)}
    )
    body = head.getvalue()
    assert body.startswith(b"\x93NUMPY")
    r = client.post("/v1/prune", content=body, headers=NPY)
    assert r.status_code == 413 and "1073741824 voxels" in r.json()["detail"]
    stack = _stack(np.ones((10, 150, 150), bool))  # 225,000 voxels > 200,000
    r = client.post("/v1/prune", content=stack, headers=TIFF)
    assert r.status_code == 413 and "voxels" in r.json()["detail"]


@pytest.mark.parametrize(
    ("body", "words"),
    [
        (b"\x93NUMPY garbage", "header"),
        (_npy(np.ones((8, 8, 8), bool))[:200], "truncated"),
        (_npy(np.ones((8, 8), bool)), "3-D"),
        (_npy(np.ones((8, 8, 8), np.float32)), "booleans or integer"),
    ],
)
def test_broken_volumes_are_400_and_the_worker_stays(
    client: TestClient, body: bytes, words: str
) -> None:
    r = client.post("/v1/prune", content=body, headers=NPY)
    assert r.status_code == 400, r.text
    assert words in r.json()["detail"]
    ok = client.post("/v1/prune", content=_npy(tube(length=12.0, radius=2.0).volume()), headers=NPY)
    assert ok.status_code == 200


def test_a_volume_is_screened_by_its_estimate_before_any_work() -> None:
    from service.app import create_app
    from service.settings import Settings

    # time estimates 1000 times slower: a job may be estimated at 30 ms at most
    app = create_app(Settings(workers=1, time_estimate_scale=1000))
    dense = np.ones((64, 64, 64), bool)  # ~0.7 s by its estimate
    small = tube(length=12.0, radius=2.0).volume()  # ~5 ms
    with TestClient(app, raise_server_exceptions=False) as c:
        r = c.post("/v1/prune", content=_npy(dense), headers=NPY)
        assert r.status_code == 413 and r.json()["type"].endswith("job-too-large")
        assert "voxels" in r.json()["detail"]
        assert c.post("/v1/prune", content=_npy(small), headers=NPY).status_code == 200


def test_volume_options_read_a_written_spacing() -> None:
    assert VolumeOptions(spacing="3,1,0.5").spacing == (3.0, 1.0, 0.5)
