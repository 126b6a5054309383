"""The OpenAPI contract: openapi.md is up to date, and schemathesis finds no 5xx and no
answer that breaks the documented schema (bounded number of generated requests)."""

from __future__ import annotations

import io
from collections.abc import Callable

import numpy as np
import pytest
import schemathesis
import tifffile
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st
from schemathesis.checks import not_a_server_error
from schemathesis.specs.openapi.checks import (
    content_type_conformance,
    response_headers_conformance,
    response_schema_conformance,
    status_code_conformance,
)

from service.apidocs.openapi_md import render
from service.app import create_app
from service.settings import Settings
from testkit import REPO

CHECKS = [
    not_a_server_error,
    status_code_conformance,
    content_type_conformance,
    response_headers_conformance,
    response_schema_conformance,
]


def test_openapi_md_is_up_to_date() -> None:
    app = create_app(Settings(workers=1))
    expected = render(app.openapi())
    current = (REPO / "openapi.md").read_text(encoding="utf-8")
    assert current == expected, "openapi.md is stale: run `make openapi`"


def _file(write: Callable[[io.BytesIO], object]) -> bytes:
    buf = io.BytesIO()
    write(buf)
    return buf.getvalue()


def _bodies(valid: list[bytes], signature: bytes) -> st.SearchStrategy[bytes]:
    """Valid files, their truncations and arbitrary bytes behind the format's signature:
    the raw bodies schemathesis cannot make from a schema."""
    return st.one_of(
        st.sampled_from(valid),
        st.tuples(st.sampled_from(valid), st.integers(1, 200)).map(lambda t: t[0][: -t[1]]),
        st.binary(max_size=300).map(lambda b: signature + b),
    )


_BAR = np.zeros((6, 8, 20), np.uint8)
_BAR[2:4, 3:5, 2:18] = 1
schemathesis.openapi.media_type(
    "image/tiff",
    _bodies(
        [
            _file(lambda f: tifffile.imwrite(f, _BAR[2] * 255)),  # an image
            _file(lambda f: tifffile.imwrite(f, _BAR, photometric="minisblack")),  # a stack
        ],
        b"II*\x00",
    ),
)
schemathesis.openapi.media_type(
    "application/x-npy",
    _bodies([_file(lambda f: np.save(f, _BAR.astype(bool)))], b"\x93NUMPY"),
)

# Small limits so that generated inputs stay cheap to prune. Loaded from the dict, not
# from the app, so the pool only starts (lazily, on the first call) when this test runs.
# Room for every long job the generated requests submit (no 503 too-many-jobs).
APP = create_app(
    Settings(
        workers=2,
        queue_size=64,
        max_pixels=256 * 256,
        polygon_longest_side=64,
        job_timeout=60,
        long_jobs=1000,
    )
)
schema = schemathesis.openapi.from_dict(APP.openapi())
schema.app = APP


@pytest.mark.timeout(600)
@schema.parametrize()
@settings(
    max_examples=30,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
)
def test_api_conforms_to_its_schema(case) -> None:  # type: ignore[no-untyped-def]
    case.call_and_validate(checks=CHECKS)


def test_every_setting_is_documented() -> None:
    doc = (REPO / "docs" / "service.md").read_text(encoding="utf-8")
    for name in Settings.model_fields:
        assert f"`SKELPRUNE_{name.upper()}`" in doc, name


def test_settings_come_from_the_environment(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("SKELPRUNE_PORT", "9123")
    monkeypatch.setenv("SKELPRUNE_WORKERS", "3")
    monkeypatch.setenv("SKELPRUNE_JOB_TIMEOUT", "2.5")
    s = Settings()
    assert (s.port, s.workers, s.job_timeout, s.host) == (9123, 3, 2.5, "127.0.0.1")
    monkeypatch.setenv("SKELPRUNE_WORKERS", "0")
    with pytest.raises(ValueError, match="workers"):
        Settings()
