"""``/docs`` and ``/redoc`` work with no network; every answer says which version made it."""

from __future__ import annotations

import re

import numpy as np
import pytest
from fastapi.testclient import TestClient

import skelprune
from service.http.schemas import Health, PruneDocument, Version

pytestmark = pytest.mark.timeout(120)

SETTINGS = {"workers": 1, "queue_size": 4, "warmup": False}
VERSIONS = {"library": skelprune.__version__, "algorithm": skelprune.ALGORITHM_VERSION}


@pytest.mark.parametrize("page", ["/docs", "/redoc"])
def test_docs_pages_load_everything_from_the_service(client: TestClient, page: str) -> None:
    resp = client.get(page)
    assert resp.status_code == 200 and resp.headers["content-type"].startswith("text/html")
    html = resp.text
    # nothing from elsewhere: no absolute URL in a src or href
    assert not re.search(r"""(src|href)=["']?(https?:)?//""", html), html
    assets = re.findall(r"""(?:src|href)=["']([^"']+)["']""", html)
    assert any(a.endswith(".js") for a in assets), assets
    for asset in assets:
        got = client.get(asset)
        assert got.status_code == 200, asset
        assert len(got.content) > 1000, asset  # the real script or sheet, not a stub


def test_versions_in_healthz_and_v1_version(client: TestClient) -> None:
    health = Health.model_validate(client.get("/healthz").json())
    assert (health.version, health.algorithm) == (
        skelprune.__version__,
        skelprune.ALGORITHM_VERSION,
    )
    version = Version.model_validate(client.get("/v1/version").json())
    assert version.service == version.library == skelprune.__version__
    assert version.algorithm == skelprune.ALGORITHM_VERSION


def test_every_result_document_carries_the_versions(client: TestClient) -> None:
    mask = np.zeros((30, 50), bool)
    mask[5:25, 5:45] = True
    assert skelprune.prune(mask).to_dict()["version"] == VERSIONS
    square = {"type": "Polygon", "coordinates": [[[0, 0], [4, 0], [4, 2], [0, 2], [0, 0]]]}
    doc = client.post("/v1/prune", json=square).json()
    assert PruneDocument.model_validate(doc).version.model_dump() == VERSIONS
