"""Label images, TIFF bodies, the tables (CSV) and GraphML over HTTP; hostile TIFFs get a
problem, never a 500."""

from __future__ import annotations

import csv
import io

import numpy as np
import tifffile
from fastapi.testclient import TestClient
from PIL import Image

from tests.library.test_tiff import deflate_bomb

SETTINGS = {"workers": 1, "queue_size": 8, "max_pixels": 200_000}


def labels() -> np.ndarray:
    lab = np.zeros((60, 120), np.uint16)
    lab[10:50, 5:60] = 300
    lab[10:50, 60:115] = 40000  # touching 300
    return lab


def tiff(a: np.ndarray, **kw) -> bytes:
    buf = io.BytesIO()
    tifffile.imwrite(buf, a, **kw)
    return buf.getvalue()


def uneven_stack() -> bytes:
    """A TIFF of two pages of different sizes: no image (several pages), no volume."""
    buf = io.BytesIO()
    with tifffile.TiffWriter(buf) as tif:
        tif.write(np.ones((20, 20), np.uint8))
        tif.write(np.ones((20, 21), np.uint8))
    return buf.getvalue()


def png16(a: np.ndarray) -> bytes:
    buf = io.BytesIO()
    Image.fromarray(a).save(buf, "PNG")
    return buf.getvalue()


def test_tiff_body_raw_multipart_and_batch(client: TestClient) -> None:
    data = tiff(labels(), compression="lzw")
    raw = client.post(
        "/v1/prune",
        content=data,
        headers={"content-type": "image/tiff"},
        params={"labels": "true", "curve": "false"},
    )
    assert raw.status_code == 200, raw.text
    doc = raw.json()
    assert [c["label"] for c in doc["components"]] == [300, 40000]
    assert doc["foreground"]["shape"] == "labels"
    form = client.post(
        "/v1/prune",
        files={"file": ("lab.tif", data, "image/tiff")},
        data={"labels": "true", "curve": "false"},
    )
    assert form.status_code == 200 and form.json()["components"] == doc["components"]
    batch = client.post(
        "/v1/prune/batch",
        files=[("file", ("a.tif", data, "image/tiff")), ("file", ("b.png", png16(labels())))],
        params={"labels": "true", "curve": "false"},
    )
    assert batch.status_code == 200
    lines = [line for line in batch.text.splitlines() if line]
    assert len(lines) == 2 and all(
        '"label": 300' in line or '"label":300' in line for line in lines
    )


def test_without_labels_a_label_png_gets_a_hint(client: TestClient) -> None:
    lab = labels()
    lab[20:40, 20:40] = 9  # a third level
    doc = client.post("/v1/prune", content=png16(lab), headers={"content-type": "image/png"})
    assert doc.status_code == 200 and "labels=true" in doc.json()["hint"]


def test_csv_tables_and_graphml(client: TestClient) -> None:
    data = tiff(labels())
    params = {"labels": "true", "pixel_size": 0.5}
    head = {"content-type": "image/tiff"}
    branch = client.post(
        "/v1/prune", content=data, params=params, headers={**head, "accept": "text/csv"}
    )
    assert branch.status_code == 200, branch.text
    assert branch.headers["content-type"].startswith("text/csv")
    rows = list(csv.DictReader(io.StringIO(branch.text)))
    assert {r["label"] for r in rows} == {"300", "40000"} and {r["unit"] for r in rows} == {
        "pixel_size"
    }
    comp = client.post(
        "/v1/prune",
        content=data,
        params={**params, "table": "component"},
        headers={**head, "accept": "text/csv"},
    )
    table = list(csv.DictReader(io.StringIO(comp.text)))
    assert [r["label"] for r in table] == ["300", "40000"]
    assert float(table[0]["area"]) == 40 * 55 * 0.25
    graph = client.post(
        "/v1/prune",
        content=data,
        params=params,
        headers={**head, "accept": "application/graphml+xml"},
    )
    assert graph.status_code == 200
    assert graph.headers["content-type"].startswith("application/graphml+xml")
    import networkx as nx

    g = nx.read_graphml(io.BytesIO(graph.content))
    assert {d["label"] for _, d in g.nodes(data=True)} == {300, 40000}
    assert g.number_of_edges() == len(rows)


def test_cleaning_options_in_query_and_body(client: TestClient) -> None:
    m = np.zeros((60, 80), np.uint8)
    m[10:50, 10:70] = 255
    m[20:22, 20:22] = 0
    m[2:4, 75:77] = 255
    data = png16(m)
    q = client.post(
        "/v1/prune",
        content=data,
        headers={"content-type": "image/png"},
        params={"fill_holes": 5, "min_area": 5, "curve": "false"},
    )
    assert q.status_code == 200, q.text
    doc = q.json()
    assert doc["foreground"]["fill_holes"] == 5 and len(doc["components"]) == 1
    assert doc["components"][0]["area"] == 40 * 60
    form = client.post(
        "/v1/prune",
        files={"file": ("m.png", data, "image/png")},
        data={"fill_holes": "5", "min_area": "5", "curve": "false"},
    )
    assert form.json()["components"] == doc["components"]
    bad = client.post(
        "/v1/prune", content=data, headers={"content-type": "image/png"}, params={"min_area": -2}
    )
    assert bad.status_code == 422 and "min_area" in bad.text
    polygon = {"type": "Polygon", "coordinates": [[[0, 0], [9, 0], [9, 9], [0, 0]]]}
    refused = client.post("/v1/prune", json=polygon, params={"labels": "true"})
    assert refused.status_code in (400, 422) and "labels" in refused.text


def test_hostile_tiffs_are_problems_never_500(client: TestClient) -> None:
    head = {"content-type": "image/tiff"}
    cases = {
        "bomb": (deflate_bomb(100, 100, 5000), 413, "compression bomb"),
        "short": (deflate_bomb(100, 100, 40), 400, "truncated TIFF"),
        "pages": (uneven_stack(), 400, "differ in size"),  # a stack is a volume: one size
        "large": (tiff(np.zeros((500, 500), np.uint8), compression="zlib"), 413, "250000 pixels"),
        "garbage": (b"II*\x00" + b"\x07" * 100, 400, "TIFF"),
    }
    for name, (data, status, detail) in cases.items():
        resp = client.post("/v1/prune", content=data, headers=head)
        assert resp.status_code == status, (name, resp.text)
        assert resp.headers["content-type"] == "application/problem+json"
        assert detail in resp.json()["detail"], name
    jpeg = client.post("/v1/prune", content=b"\xff\xd8\xff\xe0" + bytes(40), headers=head)
    assert jpeg.status_code == 400 and "PNG, TIFF and GIF" in jpeg.json()["detail"]


def test_hostile_tiffs_against_the_real_server(real_server) -> None:
    import httpx

    from tests.library.test_tiff import forged

    cases = [
        (forged(200, 200, 20000, "lzw"), 413),  # 4 MB decoded for a 40 kB image
        (forged(200, 200, 20000, "packbits"), 413),
        (forged(200, 200, 50, "zlib"), 400),  # a short strip
        (uneven_stack(), 400),
        (tiff(np.ones((3, 200, 200), np.uint8), photometric="minisblack"), 413),  # voxels
    ]
    with (
        real_server(workers="1", max_pixels="100000") as (_, base),
        httpx.Client(base_url=base, timeout=60) as http,
    ):
        for data, status in cases:
            resp = http.post("/v1/prune", content=data, headers={"content-type": "image/tiff"})
            assert resp.status_code == status, resp.text
            assert resp.headers["content-type"] == "application/problem+json"
        good = http.post(
            "/v1/prune",
            content=tiff(labels(), compression="packbits"),
            headers={"content-type": "image/tiff", "accept": "text/csv"},
            params={"labels": "true"},
        )
        assert good.status_code == 200 and good.text.startswith("component,label,branch")


def test_table_options_are_refused_where_they_do_not_apply(client: TestClient) -> None:
    data = tiff(labels())
    head = {"content-type": "image/tiff"}
    for params, accept in (
        ({"table": "component"}, "application/json"),
        ({"table": "component"}, "application/graphml+xml"),
        ({"pixel_size": 0.5}, "application/json"),
        ({"pixel_size": 0.5}, "image/png"),
    ):
        resp = client.post(
            "/v1/prune", content=data, params=params, headers={**head, "accept": accept}
        )
        assert resp.status_code == 422, (params, accept, resp.text)
        assert next(iter(params)) in resp.json()["detail"]
    bad = client.post(
        "/v1/prune",
        content=data,
        params={"table": "node"},
        headers={**head, "accept": "text/csv"},
    )
    assert bad.status_code == 422 and "table" in bad.text
