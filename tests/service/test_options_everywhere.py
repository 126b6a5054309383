"""Every option is honoured or refused in every form it arrives in (query, multipart
field, JSON body) and with every Accept type; the PNG and GeoJSON answers carry the
numbers; error details name what the user sent."""

from __future__ import annotations

import io
import json

import numpy as np
import pytest
from fastapi.testclient import TestClient
from PIL import Image

from service.http.schemas import SkeletonGeoJSON

pytestmark = pytest.mark.timeout(300)

SETTINGS = {"workers": 1, "queue_size": 8}
PNG = {"content-type": "image/png"}
SQUARE = {"type": "Polygon", "coordinates": [[[0, 0], [40, 0], [40, 20], [0, 20], [0, 0]]]}


def rectangle_png() -> bytes:
    mask = np.zeros((40, 70), np.uint8)
    mask[8:32, 6:64] = 255
    buf = io.BytesIO()
    Image.fromarray(mask).save(buf, "PNG")
    return buf.getvalue()


RECT = rectangle_png()


def test_a_multipart_option_is_honoured(client: TestClient) -> None:
    for beta in ("3", "20"):
        resp = client.post(
            "/v1/prune",
            data={"beta": beta, "curve": "false"},
            files={"file": ("r.png", RECT, "image/png")},
        )
        assert resp.status_code == 200, resp.text
        doc = resp.json()
        assert doc["beta"] == float(beta)
        assert "curve" not in doc["components"][0]


@pytest.mark.parametrize(
    ("data", "params", "fragment"),
    [
        ({"beta": "-1"}, {}, "body.beta: beta must be a finite number > 0"),
        ({"betta": "3"}, {}, "body.betta"),
        ({"beta": "3"}, {"beta": "4"}, "both in the query and the body"),
        ({"repair": "false"}, {}, "only apply to polygon"),
    ],
)
def test_a_bad_multipart_option_is_refused(client: TestClient, data, params, fragment) -> None:
    resp = client.post(
        "/v1/prune", data=data, params=params, files={"file": ("r.png", RECT, "image/png")}
    )
    assert resp.status_code == 422, resp.text
    assert fragment in resp.json()["detail"]


@pytest.mark.parametrize("accept", ["image/png", "application/geo+json"])
@pytest.mark.parametrize("option", ["curve=false", "overlay=true"])
def test_json_only_options_are_refused_for_other_answers(
    client: TestClient, accept: str, option: str
) -> None:
    name, value = option.split("=")
    resp = client.post(
        "/v1/prune", params={name: value}, content=RECT, headers={**PNG, "accept": accept}
    )
    assert resp.status_code == 422, resp.text
    detail = resp.json()["detail"]
    assert name in detail and "only apply to the JSON document" in detail and accept in detail
    # in the polygon body too
    resp = client.post(
        "/v1/prune", json={"geojson": SQUARE, name: value == "true"}, headers={"accept": accept}
    )
    assert resp.status_code == 422, resp.text


def test_png_answer_carries_the_numbers(client: TestClient) -> None:
    doc = client.post("/v1/prune", content=RECT, headers=PNG).json()
    resp = client.post("/v1/prune", content=RECT, headers={**PNG, "accept": "image/png"})
    assert resp.status_code == 200 and resp.headers["content-type"] == "image/png"
    comp = doc["components"][0]
    assert resp.headers["x-skelprune-components"] == "1"
    assert float(resp.headers["x-skelprune-rer"]) == comp["rer"]
    assert float(resp.headers["x-skelprune-ss"]) == comp["ss"]
    assert float(resp.headers["x-skelprune-objective"]) == comp["objective"]


def test_geojson_answer_carries_the_numbers(client: TestClient) -> None:
    doc = client.post("/v1/prune", json=SQUARE).json()
    resp = client.post("/v1/prune", json=SQUARE, headers={"accept": "application/geo+json"})
    assert resp.status_code == 200, resp.text
    gj = resp.json()
    SkeletonGeoJSON.model_validate(gj)
    comp = doc["components"][0]
    summary = gj["properties"]["components"][0]
    assert (summary["rer"], summary["ss"], summary["alpha"]) == (
        comp["rer"],
        comp["ss"],
        comp["alpha"],
    )
    assert gj["properties"]["beta"] == doc["beta"]
    assert gj["features"]
    assert all(
        f["properties"]["rer"] == comp["rer"] and f["properties"]["ss"] == comp["ss"]
        for f in gj["features"]
    )


@pytest.mark.parametrize(
    ("body", "fragment", "forbidden"),
    [
        (
            {"type": "Point", "coordinates": [0, 0]},
            "GeoJSON type 'Point' is not accepted",
            ("_request_tag", "'job'"),
        ),
        ({"geojson": SQUARE, "beta": -1}, "body.beta: beta must be", ("body.job", "Value error")),
        ({"geojson": 5}, "body.geojson", ("PolygonGeometry", "MultiPolygonGeometry")),
        (
            {"type": "Feature", "geometry": {"type": "Polygon", "coordinates": "x"}},
            "body.geometry.coordinates",
            ("Feature.", "Polygon."),
        ),
    ],
)
def test_validation_details_name_what_the_user_sent(
    client: TestClient, body, fragment, forbidden
) -> None:
    resp = client.post(
        "/v1/prune", content=json.dumps(body), headers={"content-type": "application/json"}
    )
    assert resp.status_code == 422, resp.text
    detail = resp.json()["detail"]
    assert fragment in detail, detail
    for word in forbidden:
        assert word not in resp.text, resp.text


def test_overlay_scale_and_legend(client: TestClient) -> None:
    def size(resp) -> tuple[int, int]:
        assert resp.status_code == 200, resp.text
        return Image.open(io.BytesIO(resp.content)).size

    png = {**PNG, "accept": "image/png"}
    assert size(client.post("/v1/prune", content=RECT, headers=png)) == (70 * 8, 40 * 8)
    assert size(
        client.post("/v1/prune", content=RECT, headers=png, params={"overlay_scale": "2"})
    ) == (140, 80)
    legend = size(
        client.post(
            "/v1/prune",
            content=RECT,
            headers=png,
            params={"overlay_scale": "2", "overlay_legend": "true"},
        )
    )
    assert legend[0] == 140 and legend[1] > 80
    # in the JSON document's overlay too; refused where there is no overlay
    doc = client.post(
        "/v1/prune", content=RECT, headers=PNG, params={"overlay": "true", "overlay_scale": "3"}
    ).json()
    import base64

    assert Image.open(io.BytesIO(base64.b64decode(doc["overlay_png"]))).size == (210, 120)
    for accept, params in (("application/json", {}), ("application/geo+json", {})):
        resp = client.post(
            "/v1/prune",
            content=RECT,
            headers={**PNG, "accept": accept},
            params={**params, "overlay_scale": "2"},
        )
        assert resp.status_code == 422 and "only apply to the overlay" in resp.text
    resp = client.post("/v1/prune", content=RECT, headers=png, params={"overlay_scale": "40"})
    assert resp.status_code == 422 and "overlay_scale" in resp.json()["detail"]


def test_trim_and_choice_reach_the_library_from_query_and_body(client: TestClient) -> None:
    import skelprune
    from testkit.shapes import DRAWN

    mask = DRAWN["stick_figure"]()
    buf = io.BytesIO()
    Image.fromarray(mask.astype(np.uint8) * 255).save(buf, "PNG")
    png = buf.getvalue()
    for opts in ({"trim": "false"}, {"choice": "argmin"}, {}):
        query = client.post(
            "/v1/prune", params={**opts, "curve": "false"}, content=png, headers=PNG
        )
        form = client.post(
            "/v1/prune",
            data={**opts, "curve": "false"},
            files={"file": ("s.png", png, "image/png")},
        )
        kw = {"trim": opts.get("trim") != "false", "choice": opts.get("choice", "noise-floor")}
        want = skelprune.prune(mask, **kw).to_dict(curve=False)
        for resp in (query, form):
            assert resp.status_code == 200, resp.text
            doc = resp.json()
            assert (doc["trim"], doc["choice"]) == (kw["trim"], kw["choice"])
            assert doc["components"] == want["components"]
    resp = client.post("/v1/prune", params={"trim": "maybe"}, content=png, headers=PNG)
    assert resp.status_code == 422 and "trim" in resp.text
