"""The in-process app under test, on the real worker pool."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest
from fastapi.testclient import TestClient

from service.app import create_app
from service.settings import Settings


@pytest.fixture(scope="module")
def client(request: pytest.FixtureRequest) -> Iterator[TestClient]:
    """A TestClient on ``create_app(Settings(**SETTINGS))``, ``SETTINGS`` being the test
    module's (default: one worker, a queue of 8). Server errors come back as answers,
    as a client would see them."""
    settings: dict[str, Any] = getattr(request.module, "SETTINGS", {"workers": 1, "queue_size": 8})
    app = create_app(Settings(**settings))
    with TestClient(app, raise_server_exceptions=False) as c:
        yield c
    app.dependency_overrides.clear()
