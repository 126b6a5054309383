"""The query options of ``POST /v1/prune``: ``service.http.query.parse_query`` against
FastAPI's own handling of ``Annotated[PruneQuery, Query()]``, which it replaces (same
values, same errors), and its place before every other check of the request."""

from __future__ import annotations

import io
from typing import Annotated, Any
from urllib.parse import urlencode

import numpy as np
import pytest
from fastapi import FastAPI, Query, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from fastapi.testclient import TestClient
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image
from starlette.datastructures import QueryParams

from service.app import create_app
from service.http.query import parse_query
from service.http.schemas import PruneQuery
from service.settings import Settings
from skelprune.errors import InvalidOptionError
from skelprune.options import PruneOptions

pytestmark = pytest.mark.timeout(120)


def _reference_app() -> FastAPI:
    """The declaration ``parse_query`` replaced, answering with the values or the errors."""
    app = FastAPI()

    @app.get("/q")
    async def q(query: Annotated[PruneQuery, Query()]) -> dict[str, Any]:
        return {"ok": query.model_dump()}

    async def errors(request: Request, exc: Exception) -> JSONResponse:
        assert isinstance(exc, RequestValidationError)
        return JSONResponse({"errors": _shown(exc)})

    app.add_exception_handler(RequestValidationError, errors)
    return app


def _shown(exc: RequestValidationError) -> list[dict[str, Any]]:
    # what the problem+json handler puts in a 422 answer (service/errors.py)
    return [
        {"loc": [str(p) for p in e["loc"]], "msg": e["msg"], "type": e["type"]}
        for e in exc.errors()
    ]


@pytest.fixture(scope="module")
def reference() -> TestClient:
    return TestClient(_reference_app())


def ours(query_string: str) -> dict[str, Any]:
    try:
        return {"ok": parse_query(QueryParams(query_string)).model_dump()}
    except RequestValidationError as exc:
        return {"errors": _shown(exc)}


CASES = [
    "",
    "beta=3.5&method=dce&coarse=none&dce_threshold=0.02&curve=false&overlay=1"
    "&pixel_size=0.5&longest_side=64&repair=off",
    "betta=9",
    "betta=9&betta=10&beta=0",
    "BETA=3",
    "beta=",
    "beta",
    "&&beta=4&",
    "beta=nan&dce_threshold=-inf&longest_side=8.5&curve=maybe&method=MAGIC",
    "longest_side=8.0&curve=yes&overlay=0&repair=TRUE",
    "longest_side=1e3",
    "beta=%39&method=b%61yesian",
    "x=1&y=2&z=3&beta=-1",
]


def _repeats(query_string: str) -> bool:
    keys = [k for k, _ in QueryParams(query_string).multi_items() if k in PruneQuery.model_fields]
    return len(keys) != len(set(keys))


@pytest.mark.parametrize("query_string", ["beta=1&beta=2", "beta=x&beta=2", "beta=2&beta=x"])
def test_an_option_given_twice_is_refused_naming_it(query_string: str) -> None:
    assert ours(query_string) == {
        "errors": [
            {
                "loc": ["query", "beta"],
                "msg": "given 2 times; give an option once",
                "type": "repeated",
            }
        ]
    }


@pytest.mark.parametrize("query_string", ["beta=1_0", "spacing=1_0,1,1", "min_area=\u0661\u0662"])
def test_numbers_are_plain_ascii_decimals(query_string: str) -> None:
    (error,) = ours(query_string)["errors"]
    assert error["type"] == "number_format" and "ASCII" in error["msg"]


@pytest.mark.parametrize("query_string", CASES)
def test_parse_query_matches_fastapi(reference: TestClient, query_string: str) -> None:
    assert ours(query_string) == reference.get(f"/q?{query_string}").json()


KEYS = st.sampled_from([*PruneQuery.model_fields, "betta", "Beta", "", "a b", "é"])
VALUES = st.sampled_from(
    [
        "",
        "0",
        "1",
        "-1",
        "2.5",
        "1e400",
        "nan",
        "true",
        "off",
        "dce",
        "none",
        "bayesian",
        "64",
        "x",
        " 9 ",
    ]
)


@settings(max_examples=150, deadline=None)
@given(st.lists(st.tuples(KEYS, VALUES), max_size=6))
def test_parse_query_matches_fastapi_on_random_queries(
    reference: TestClient, pairs: list[tuple[str, str]]
) -> None:
    query_string = urlencode(pairs)
    if _repeats(query_string):  # FastAPI keeps the last; an option given twice is refused
        assert any(e["type"] == "repeated" for e in ours(query_string)["errors"])
    else:
        assert ours(query_string) == reference.get(f"/q?{query_string}").json()


def test_bad_options_are_refused_before_anything_else() -> None:
    # No worker pool is started (no lifespan): the answer comes before any job.
    client = TestClient(create_app(Settings(workers=1)), raise_server_exceptions=False)
    for headers in (
        {"content-type": "text/plain"},
        {"accept": "text/html"},
        {"content-type": "image/png", "content-encoding": "gzip"},
    ):
        resp = client.post("/v1/prune?beta=x&betta=1", content=b"x", headers=headers)
        assert resp.status_code == 422, resp.text
        assert resp.headers["content-type"] == "application/problem+json"
        assert [e["loc"] for e in resp.json()["errors"]] == [["query", "beta"], ["query", "betta"]]


def test_option_values_are_checked_once_by_the_option_classes(client: TestClient) -> None:
    # The query model checks wire types only; the options' classes refuse the values,
    # every refused one located where it was given, with the library's own message.
    buf = io.BytesIO()
    Image.fromarray(np.full((8, 8), 255, np.uint8)).save(buf, "PNG")
    resp = client.post(
        "/v1/prune?beta=0&overlay_scale=99&overlay=true",
        content=buf.getvalue(),
        headers={"content-type": "image/png"},
    )
    assert resp.status_code == 422, resp.text
    errors = resp.json()["errors"]
    assert [e["loc"] for e in errors] == [["query", "beta"], ["query", "overlay_scale"]]
    with pytest.raises(InvalidOptionError) as info:
        PruneOptions(beta=0.0)  # the wire type: a float
    assert errors[0]["msg"] == str(info.value)
    body = {"geojson": {"type": "Polygon", "coordinates": [[[0, 0], [9, 0], [9, 9], [0, 0]]]}}
    resp = client.post("/v1/prune?beta=2", json={**body, "longest_side": 4})
    assert [e["loc"] for e in resp.json()["errors"]] == [["body", "longest_side"]]
