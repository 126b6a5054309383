"""The shape users mean: the foreground rule in the library, the CLI and the service."""

from __future__ import annotations

import io
import json
import subprocess
import sys

import numpy as np
import pytest
from fastapi.testclient import TestClient
from PIL import Image

import skelprune
from service.app import create_app
from service.settings import Settings
from skelprune.errors import InvalidOptionError
from skelprune.io.png import read_mask, read_shape
from testkit.shapes import dataset

CLI = [sys.executable, "-m", "skelprune.cli"]
DATASETS = [p for name in ("kimia216", "kimia99") for p in dataset(name)]


def png(arr: np.ndarray, mode: str | None = None) -> bytes:
    buf = io.BytesIO()
    Image.fromarray(arr, mode).save(buf, "PNG")
    return buf.getvalue()


def test_datasets_read_exactly_as_before() -> None:
    """Both datasets are white on black: auto takes exactly their non-zero pixels."""
    for path in DATASETS:
        raw = np.asarray(Image.open(path))
        mask, taken = read_shape(path)
        assert np.array_equal(mask, raw != 0), path.name
        assert taken.shape == "light" and taken.border > 0.5


def _skeleton_key(res: skelprune.PruneResult) -> tuple:
    rows, cols, r2 = res.skeleton_points()
    return (
        sorted(zip(rows.tolist(), cols.tolist(), r2.tolist(), strict=True)),
        [(c.rer, c.ss, c.chosen_step, c.graph.n_endpoints()) for c in res.components],
    )


def test_inverted_dataset_shapes_give_the_same_skeleton() -> None:
    """Black-on-white copies of every dataset shape: the same points, radii and numbers."""
    for path in DATASETS:
        raw = np.asarray(Image.open(path))
        res = skelprune.prune(read_mask(path))
        inverted, taken = read_shape(png((255 - raw).astype(np.uint8)))
        assert taken.shape == "dark"
        assert _skeleton_key(skelprune.prune(inverted)) == _skeleton_key(res), path.name


def test_anti_aliased_grey_edges_are_thresholded_at_mid_grey() -> None:
    yy, xx = np.mgrid[:60, :60]
    d = np.hypot(yy - 30, xx - 30)
    exact = d < 20
    grey = np.clip(20.5 - d, 0, 1)  # a one-pixel anti-aliased rim
    black_on_white = (255 * (1 - grey)).round().astype(np.uint8)
    mask, taken = read_shape(png(black_on_white))
    assert taken.shape == "dark" and taken.threshold == 127.5
    assert abs(int(mask.sum()) - int(exact.sum())) < 0.05 * exact.sum()
    # any non-zero grey counts as shape under nonzero: the disk grows by its rim
    white_on_black = 255 - black_on_white
    assert read_mask(png(white_on_black), foreground="nonzero").sum() > mask.sum()
    assert np.array_equal(read_mask(png(white_on_black)), mask)


def test_two_level_mask_with_a_non_zero_background() -> None:
    arr = np.full((30, 40), 3, np.uint8)
    arr[8:22, 5:35] = 7
    mask, taken = read_shape(png(arr))
    assert taken.shape == "light" and taken.threshold == 5.0
    assert np.array_equal(mask, arr == 7)
    assert read_mask(png(arr), foreground="nonzero").all()  # the old reading: everything


def test_alpha_mask_takes_the_opaque_part() -> None:
    rgba = np.zeros((30, 40, 4), np.uint8)
    rgba[..., :3] = 255  # white everywhere: only alpha tells the shape
    rgba[8:22, 5:35, 3] = 255
    rgba[7, 5:35, 3] = 60  # a faint anti-aliased row: below mid-alpha, not shape
    mask, taken = read_shape(png(rgba, "RGBA"))
    assert taken.shape == "opaque" and taken.threshold == 127.5
    assert np.array_equal(mask, rgba[..., 3] > 127)
    assert read_mask(png(rgba, "RGBA"), foreground="nonzero").sum() == mask.sum() + 30


def test_shape_covering_the_whole_border_is_taken_as_background() -> None:
    """The documented edge case: the level on the whole border is the background, so a
    frame-shaped mask reads as its inside; foreground=nonzero reads the frame."""
    arr = np.full((30, 40), 255, np.uint8)
    arr[10:20, 10:30] = 0
    mask, taken = read_shape(png(arr))
    assert taken.shape == "dark" and taken.border == 1.0
    assert np.array_equal(mask, arr == 0)
    assert np.array_equal(read_mask(png(arr), foreground="nonzero"), arr == 255)
    res = skelprune.prune(read_mask(png(arr), foreground="nonzero"))
    assert len(res.to_dict()["components"][0]["skeleton"]["nodes"]) >= 1


def test_no_border_majority_takes_the_light_side() -> None:
    """Exactly half the border on each side: the light (non-zero) side is the shape."""
    arr = np.zeros((20, 20), np.uint8)
    arr[:, 10:] = 255  # left half dark, right half light: border split 38 / 38
    mask, taken = read_shape(png(arr))
    assert taken.shape == "light" and taken.border == 0.5
    assert np.array_equal(mask, arr == 255)
    arr[0, 9] = 255  # one border pixel more on the light side: now it is the background
    mask, taken = read_shape(png(arr))
    assert taken.shape == "dark" and np.array_equal(mask, arr == 0)


def test_library_option_and_report() -> None:
    arr = np.full((30, 40), 255, np.uint8)
    arr[8:22, 5:35] = 0
    doc = skelprune.prune(arr, foreground="auto").to_dict(curve=False)
    assert doc["foreground"] == {"rule": "auto", "shape": "dark", "threshold": 127.5, "border": 1.0}
    assert doc["components"][0]["area"] == 14 * 30
    assert skelprune.prune(arr, foreground="zero").to_dict()["components"][0]["area"] == 420
    nonzero = skelprune.prune(arr).to_dict(curve=False)  # arrays: non-zero by default
    assert nonzero["foreground"]["shape"] == "nonzero"
    assert nonzero["components"][0]["area"] == 30 * 40 - 420
    for bad in ("white", None, 1):
        with pytest.raises(InvalidOptionError, match="foreground must be one of"):
            skelprune.prune(arr, foreground=bad)  # type: ignore[arg-type]
        with pytest.raises(InvalidOptionError, match="foreground must be one of"):
            read_mask(png(arr), foreground=bad)  # type: ignore[arg-type]


def test_cli_option(tmp_path) -> None:
    arr = np.full((30, 40), 255, np.uint8)
    arr[8:22, 5:35] = 0
    path = tmp_path / "black-on-white.png"
    path.write_bytes(png(arr))
    docs = {}
    for rule in ("auto", "nonzero", "zero"):
        run = subprocess.run(
            [*CLI, "prune", str(path), "--foreground", rule, "--no-curve"],
            capture_output=True,
            text=True,
            timeout=300,
            check=True,
        )
        docs[rule] = json.loads(run.stdout)
    assert docs["auto"]["foreground"]["shape"] == "dark"
    assert docs["auto"]["components"] == docs["zero"]["components"]
    assert docs["nonzero"]["components"][0]["area"] == 30 * 40 - 420
    bad = subprocess.run(
        [*CLI, "prune", str(path), "--foreground", "white"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert bad.returncode == 2 and "--foreground" in bad.stderr and "'nonzero'" in bad.stderr
    assert "Traceback" not in bad.stderr and bad.stderr.count("\n") == 1


@pytest.fixture(scope="module")
def client():
    with TestClient(create_app(Settings(workers=1)), raise_server_exceptions=False) as c:
        yield c


def test_service_option_raw_and_multipart(client: TestClient) -> None:
    arr = np.full((30, 40), 255, np.uint8)
    arr[8:22, 5:35] = 0
    data = png(arr)
    raw = client.post("/v1/prune", content=data, headers={"content-type": "image/png"})
    assert raw.status_code == 200, raw.text
    assert raw.json()["foreground"]["shape"] == "dark"
    assert raw.json()["components"][0]["area"] == 420
    for rule, area in (("nonzero", 780), ("zero", 420), ("auto", 420)):
        resp = client.post(
            "/v1/prune", params={"foreground": rule}, files={"file": ("a.png", data, "image/png")}
        )
        assert resp.status_code == 200, resp.text
        assert resp.json()["components"][0]["area"] == area
        assert resp.json()["foreground"]["rule"] == rule
    # an option as a multipart field is honoured like the query's
    resp = client.post(
        "/v1/prune", data={"foreground": "zero"}, files={"file": ("a.png", data, "image/png")}
    )
    assert resp.status_code == 200, resp.text
    assert resp.json()["foreground"]["rule"] == "zero"
    assert resp.json()["components"][0]["area"] == 420
    resp = client.post(
        "/v1/prune",
        params={"foreground": "black"},
        content=data,
        headers={"content-type": "image/png"},
    )
    assert resp.status_code == 422 and "foreground" in resp.text


def test_service_polygon_reports_its_interior(client: TestClient) -> None:
    poly = {"type": "Polygon", "coordinates": [[[0, 0], [40, 0], [40, 20], [0, 20], [0, 0]]]}
    resp = client.post("/v1/prune", json=poly)
    assert resp.status_code == 200, resp.text
    assert resp.json()["foreground"] == {
        "rule": None,
        "shape": "polygon",
        "threshold": None,
        "border": None,
    }
    for kwargs in (
        {"json": poly, "params": {"foreground": "zero"}},
        {"json": {"geojson": poly, "foreground": "nonzero"}},
    ):
        resp = client.post("/v1/prune", **kwargs)
        assert resp.status_code == 422 and "only apply to image input" in resp.json()["detail"]
