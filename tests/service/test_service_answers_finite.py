"""Every answer of the service over the awkward corpus (testkit/awkward.py) is 200 and
holds no NaN or infinity: the JSON document, the GeoJSON branches and map lines, both
CSV tables, GraphML, the PNG's headers, a volume's document, table, SWC and image."""

from __future__ import annotations

import io

import numpy as np
import pytest
from fastapi.testclient import TestClient
from PIL import Image

from testkit import awkward

pytestmark = pytest.mark.timeout(900)

# Polygons rasterised small: the corpus is about the answers, not the raster's size.
SETTINGS = {"workers": 1, "queue_size": 8, "polygon_longest_side": 160}

#: Every answer of an image or a polygon: (Accept, query).
IMAGE_ANSWERS = [
    ("application/json", {"sequence": "true"}),
    ("application/geo+json", {}),
    ("application/geo+json", {"simplify": "0", "cut_ends": "true"}),
    ("text/csv", {}),
    ("text/csv", {"table": "component"}),
    ("application/graphml+xml", {}),
    ("image/png", {}),
]
#: The polygon's answers besides: the map lines.
MAP_ANSWERS = [
    ("application/geo+json", {"lines": "map"}),
    ("application/geo+json", {"lines": "main-path"}),
]
VOLUME_ANSWERS = [
    ("application/json", {}),
    ("text/csv", {}),
    ("text/x-swc", {}),
    ("image/png", {}),
]


def check(resp) -> None:  # type: ignore[no-untyped-def]
    """A 200 answer without a number that is not finite, in its body or headers."""
    assert resp.status_code == 200, resp.text
    media = resp.headers["content-type"].split(";")[0]
    if media in ("application/json", "application/geo+json"):
        awkward.assert_finite_json(resp.content)
    elif media == "image/png":
        Image.open(io.BytesIO(resp.content)).verify()
    else:
        awkward.assert_finite_text(resp.text)
    for name, value in resp.headers.items():
        if name.startswith("x-skelprune"):
            awkward.assert_finite_text(value)


def png(mask: np.ndarray) -> bytes:
    buf = io.BytesIO()
    Image.fromarray(mask.astype(np.uint8) * 255).save(buf, "PNG")
    return buf.getvalue()


@pytest.mark.parametrize("name", sorted(awkward.masks()))
def test_every_answer_of_an_awkward_mask(client: TestClient, name: str) -> None:
    body = png(awkward.masks()[name])
    for accept, query in IMAGE_ANSWERS:
        check(
            client.post(
                "/v1/prune",
                content=body,
                # the mask's non-zero pixels, as the library takes an array
                params={"foreground": "nonzero", **query},
                headers={"content-type": "image/png", "accept": accept},
            )
        )


@pytest.mark.parametrize("name", sorted(awkward.polygons()))
def test_every_answer_of_an_awkward_polygon(client: TestClient, name: str) -> None:
    polygon = awkward.polygons()[name]
    for accept, query in IMAGE_ANSWERS + MAP_ANSWERS:
        check(client.post("/v1/prune", json=polygon, params=query, headers={"accept": accept}))


@pytest.mark.parametrize("name", sorted(awkward.volumes()))
def test_every_answer_of_an_awkward_volume(client: TestClient, name: str) -> None:
    buf = io.BytesIO()
    np.save(buf, awkward.volumes()[name])
    for accept, query in VOLUME_ANSWERS:
        check(
            client.post(
                "/v1/prune",
                content=buf.getvalue(),
                params={"spacing": "2,1,1", **query},
                headers={"content-type": "application/x-npy", "accept": accept},
            )
        )


def test_the_noise_mask_answers_null_where_a_number_is_not_defined(client: TestClient) -> None:
    """The awkward case is there: a junction angle between two junctions has no value
    (a branch without direction), and every answer still answers (null, an empty cell)."""
    body = png(awkward.noise())
    image = {"content-type": "image/png"}
    query = {"foreground": "nonzero"}
    resp = client.post(
        "/v1/prune", content=body, params=query, headers={**image, "accept": "text/csv"}
    )
    check(resp)
    header, *rows = [line.split(",") for line in resp.text.splitlines()]
    ends = [header.index("junction_angle_source"), header.index("junction_angle_target")]
    kind = header.index("kind")
    undefined = [r for r in rows if r[kind] == "junction-junction" and "" in {r[i] for i in ends}]
    assert undefined
    gj = client.post(
        "/v1/prune", content=body, params=query, headers={**image, "accept": "application/geo+json"}
    )
    check(gj)
    branches = [
        f["properties"] for f in gj.json()["features"] if f["properties"]["kind"] == "branch"
    ]
    assert any(
        p["branch_kind"] == "junction-junction"
        and None in (p["junction_angle_source"], p["junction_angle_target"])
        for p in branches
    )
