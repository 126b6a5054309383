"""Security: API key, CORS, no file paths from requests, request IDs, structured logs.

- ``SKELPRUNE_API_KEY`` set: every endpoint except ``/healthz`` and ``/readyz`` needs
  ``Authorization: Bearer <key>`` or ``X-API-Key: <key>``; otherwise 401 problem+json
  with ``WWW-Authenticate``. Unset: everything is open.
- CORS headers only for the origins in ``SKELPRUNE_CORS_ORIGINS`` (none by default).
- No request can make the service read a file: inputs are bytes, options are numbers,
  booleans or fixed words.
- ``X-Request-ID`` is taken from the request (if sane) or generated, echoed in the
  response and in every problem body, and logged on the request's one JSON log line.
- Neither responses nor logs carry the key, the Authorization header or a stack trace.
"""

from __future__ import annotations

import json
import logging
import re
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any, get_args

import httpx
import pytest
from fastapi.testclient import TestClient

import service.http.api_key
from service.app import create_app
from service.http.routes.prune import job_function
from service.http.schemas import PolygonJob, Problem, PruneQuery
from service.logs import JsonFormatter
from service.settings import Settings
from service.worker.jobs import Job, run_job
from skelprune.errors import InvalidImageError, InvalidOptionError
from skelprune.options import RasterOptions, VolumeOptions
from testkit import DATA, REPO
from testkit.realserver import running_server, stop

pytestmark = pytest.mark.timeout(300)

BIRD = (DATA / "kimia216" / "bird-10.png").read_bytes()
KEY = "s3cret-Key_0123456789"
ORIGIN = "https://app.example"
PNG = {"content-type": "image/png"}
PROBLEM = "application/problem+json"
HEX_ID = re.compile(r"^[0-9a-f]{32}$")


@pytest.fixture(scope="module")
def open_client() -> Iterator[TestClient]:
    with TestClient(create_app(Settings(workers=1, queue_size=4))) as c:
        yield c


@pytest.fixture(scope="module")
def locked_app() -> Iterator[Any]:
    app = create_app(Settings(workers=1, queue_size=4, api_key=KEY, cors_origins=[ORIGIN]))
    with TestClient(app, raise_server_exceptions=False) as c:
        app.state.test_client = c
        yield app
    app.dependency_overrides.clear()


@pytest.fixture
def locked(locked_app: Any) -> TestClient:
    return locked_app.state.test_client


def auth(**extra: str) -> dict[str, str]:
    return {"authorization": f"Bearer {KEY}", **extra}


def assert_problem(resp: httpx.Response, status: int, *fragments: str) -> dict:
    assert resp.status_code == status, resp.text
    assert resp.headers["content-type"] == PROBLEM
    body = resp.json()
    Problem.model_validate(body)
    for fragment in fragments:
        assert fragment in body["detail"], body["detail"]
    assert "Traceback" not in resp.text and 'File "' not in resp.text
    assert body["request_id"] == resp.headers["x-request-id"]
    return body


# ------------------------------------------------------------------------ API key
def test_no_key_configured_means_open(open_client: TestClient) -> None:
    assert open_client.post("/v1/prune", content=BIRD, headers=PNG).status_code == 200
    assert open_client.get("/metrics").status_code == 200
    assert "www-authenticate" not in open_client.get("/readyz").headers


@pytest.mark.parametrize(
    ("headers", "fragment", "error"),
    [
        ({}, "API key required", None),
        ({"authorization": "Bearer wrong-key"}, "invalid API key", "invalid_token"),
        ({"x-api-key": "wrong-key"}, "invalid API key", "invalid_token"),
        ({"authorization": f"Bearer {KEY[:-1]}"}, "invalid API key", "invalid_token"),
        ({"authorization": f"Bearer {KEY}x"}, "invalid API key", "invalid_token"),
        ({"authorization": f"Basic {KEY}"}, "API key required", None),
        ({"authorization": KEY}, "API key required", None),
        ({"authorization": "Bearer "}, "API key required", None),
        ({"x-api-key": ""}, "API key required", None),
    ],
    ids=[
        "missing",
        "wrong-bearer",
        "wrong-x-api-key",
        "prefix",
        "longer",
        "basic-scheme",
        "no-scheme",
        "empty-bearer",
        "empty-x-api-key",
    ],
)
def test_missing_or_wrong_key_is_401(
    locked: TestClient, headers: dict[str, str], fragment: str, error: str | None
) -> None:
    resp = locked.post("/v1/prune", content=BIRD, headers={**PNG, **headers})
    body = assert_problem(resp, 401, fragment)
    assert body["type"] == "urn:skelprune:problem:unauthorized"
    challenge = resp.headers["www-authenticate"]
    assert challenge.startswith('Bearer realm="skelprune"')
    assert (f'error="{error}"' in challenge) == (error is not None)
    assert KEY not in resp.text and "wrong-key" not in resp.text


@pytest.mark.parametrize(
    "headers",
    [
        {"authorization": f"Bearer {KEY}"},
        {"authorization": f"bearer  {KEY} "},
        {"x-api-key": KEY},
        {"authorization": "Bearer nope", "x-api-key": KEY},
    ],
    ids=["bearer", "bearer-case-and-spaces", "x-api-key", "either-header"],
)
def test_right_key_is_let_in(locked: TestClient, headers: dict[str, str]) -> None:
    resp = locked.post("/v1/prune", content=BIRD, headers={**PNG, **headers})
    assert resp.status_code == 200, resp.text
    assert resp.json()["width"] == 116


def test_which_paths_need_the_key(locked: TestClient) -> None:
    # liveness and readiness stay open: probes carry no credentials
    assert locked.get("/healthz").json()["status"] == "ok"
    assert locked.get("/readyz").status_code == 200
    # everything else, metrics and the API description included, needs the key
    for path in ("/metrics", "/openapi.json", "/docs", "/no/such/path"):
        assert_problem(locked.get(path), 401, "API key required")
        assert locked.get(path, headers=auth()).status_code in (200, 404)
    assert locked.get("/metrics", headers={"x-api-key": KEY}).status_code == 200
    # an unauthenticated request learns nothing else: not even that the method is wrong
    assert_problem(locked.get("/v1/prune"), 401)
    assert locked.get("/v1/prune", headers=auth()).status_code == 405


def test_key_is_compared_in_constant_time(
    locked: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    calls: list[tuple[bytes, bytes]] = []
    real = service.http.api_key.hmac.compare_digest

    def spy(a: bytes, b: bytes) -> bool:
        calls.append((a, b))
        return real(a, b)

    monkeypatch.setattr(service.http.api_key.hmac, "compare_digest", spy)
    assert locked.get("/metrics", headers={"x-api-key": "guess"}).status_code == 401
    assert locked.get("/metrics", headers=auth()).status_code == 200
    assert calls and all(isinstance(a, bytes) and isinstance(b, bytes) for a, b in calls)


def test_key_is_secret_in_settings() -> None:
    settings = Settings(api_key=KEY)
    assert KEY not in repr(settings) and KEY not in str(settings.model_dump())
    assert settings.api_key is not None and settings.api_key.get_secret_value() == KEY
    assert Settings(api_key="").api_key is None  # an empty variable means "no key"


def test_key_from_the_environment(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("SKELPRUNE_API_KEY", KEY)
    monkeypatch.setenv("SKELPRUNE_CORS_ORIGINS", f"{ORIGIN}, https://b.example")
    settings = Settings()
    assert settings.api_key is not None and settings.api_key.get_secret_value() == KEY
    assert settings.cors_origins == [ORIGIN, "https://b.example"]


# --------------------------------------------------------------------------- CORS
def preflight(client: TestClient, origin: str) -> httpx.Response:
    return client.options(
        "/v1/prune",
        headers={
            "origin": origin,
            "access-control-request-method": "POST",
            "access-control-request-headers": "authorization, content-type",
        },
    )


def test_cors_is_off_by_default(open_client: TestClient) -> None:
    resp = preflight(open_client, ORIGIN)
    assert "access-control-allow-origin" not in resp.headers
    resp = open_client.post("/v1/prune", content=BIRD, headers={**PNG, "origin": ORIGIN})
    assert resp.status_code == 200
    assert not any(h.startswith("access-control-") for h in resp.headers)


def test_cors_for_configured_origins_only(locked: TestClient) -> None:
    resp = preflight(locked, ORIGIN)  # no key: browsers send none on a preflight
    assert resp.status_code == 200
    assert resp.headers["access-control-allow-origin"] == ORIGIN
    assert "authorization" in resp.headers["access-control-allow-headers"].lower()
    assert "access-control-allow-credentials" not in resp.headers
    other = preflight(locked, "https://evil.example")
    assert other.status_code >= 400
    assert "access-control-allow-origin" not in other.headers
    resp = locked.post("/v1/prune", content=BIRD, headers={**PNG, **auth(), "origin": ORIGIN})
    assert resp.status_code == 200
    assert resp.headers["access-control-allow-origin"] == ORIGIN
    assert "x-request-id" in resp.headers["access-control-expose-headers"].lower()
    resp = locked.post(
        "/v1/prune", content=BIRD, headers={**PNG, **auth(), "origin": "https://evil.example"}
    )
    assert "access-control-allow-origin" not in resp.headers


# -------------------------------------------------------------------- file paths
def test_no_option_can_name_a_path() -> None:
    """Every option is a number, a boolean or one of fixed words: none can carry a path;
    but ``crs``, a text whose check admits an authority code or its URN only, and
    ``spacing``, a text whose check admits three numbers only."""
    for model in (PruneQuery, PolygonJob):
        for name, info in model.model_fields.items():
            if name == "geojson":
                continue
            kinds = {a for a in get_args(info.annotation) or (info.annotation,)}
            for kind in kinds - {type(None)}:
                if kind is str and name in ("crs", "spacing"):
                    continue
                literal = getattr(kind, "__origin__", None) is not None or get_args(kind)
                assert kind in (bool, int, float) or literal, (model.__name__, name, kind)
                assert kind is not str
    for path in ("/etc/passwd", "../../etc/hostname", str(REPO / "README.md"), "+init=x:y"):
        with pytest.raises(InvalidOptionError, match="not a CRS name"):
            RasterOptions(crs=path)
        with pytest.raises(InvalidOptionError, match="three finite numbers"):
            VolumeOptions(spacing=path)


@pytest.mark.parametrize("path", ["/etc/passwd", "../../etc/hostname", str(REPO / "README.md")])
def test_path_as_a_png_body_is_just_bytes(open_client: TestClient, path: str) -> None:
    resp = open_client.post("/v1/prune", content=path.encode(), headers=PNG)
    body = assert_problem(resp, 400, "not a PNG")
    assert "cannot read" not in body["detail"]
    # multipart: the filename is ignored, the part's bytes are the image
    resp = open_client.post("/v1/prune", files={"file": (path, BIRD, "image/png")})
    assert resp.status_code == 200
    resp = open_client.post("/v1/prune", files={"file": (path, path.encode(), "image/png")})
    assert_problem(resp, 400, "not a PNG")
    resp = open_client.post(
        "/v1/prune", content=BIRD, headers=PNG, params={"file": path, "path": path}
    )
    assert_problem(resp, 422, "file")


def test_worker_refuses_a_path_in_place_of_bytes() -> None:
    """Even a route bug handing over a str could not make the worker open a file."""
    readme = str(REPO / "README.md")
    with pytest.raises(InvalidImageError, match="bytes"):
        run_job(Job(media="json", kind="image", data=readme))  # type: ignore[arg-type]


# -------------------------------------------------------------------- request IDs
def test_request_id_generated_and_echoed(open_client: TestClient) -> None:
    ok = open_client.post("/v1/prune", content=BIRD, headers=PNG)
    assert HEX_ID.match(ok.headers["x-request-id"])
    bad = open_client.post("/v1/prune", content=b"nope", headers=PNG)
    body = assert_problem(bad, 400)
    assert HEX_ID.match(body["request_id"]) and body["request_id"] != ok.headers["x-request-id"]
    assert HEX_ID.match(open_client.get("/healthz").headers["x-request-id"])


@pytest.mark.parametrize(
    "rid", ["abc-123", "7b0e6c2e-5a4f-4f57-9d4b-1d1a5b8f8c11", "trace:01HXYZ.span_9", "x" * 128]
)
def test_request_id_taken_from_the_client(open_client: TestClient, rid: str) -> None:
    ok = open_client.post("/v1/prune", content=BIRD, headers={**PNG, "x-request-id": rid})
    assert ok.headers["x-request-id"] == rid
    bad = open_client.post("/v1/prune", content=b"nope", headers={**PNG, "x-request-id": rid})
    assert assert_problem(bad, 400)["request_id"] == rid


@pytest.mark.parametrize(
    "rid", ["", "has space", "x" * 129, "semi;colon", 'quote"', "é-accent", "a\tb"]
)
def test_unusable_request_id_is_replaced(open_client: TestClient, rid: str) -> None:
    resp = open_client.get("/healthz", headers={"x-request-id": rid.encode("utf-8")})
    assert HEX_ID.match(resp.headers["x-request-id"])


def test_request_id_on_every_kind_of_error(locked: TestClient) -> None:
    rid = "req-42"
    for resp, status in (
        (locked.post("/v1/prune", content=BIRD, headers={**PNG, "x-request-id": rid}), 401),
        (
            locked.post(
                "/v1/prune",
                content=b"\0" * (17 * 2**20),
                headers={**PNG, **auth(), "x-request-id": rid},
            ),
            413,
        ),
        (locked.get("/nothing", headers={**auth(), "x-request-id": rid}), 404),
        (
            locked.post(
                "/v1/prune",
                content=b"x",
                headers={**auth(), "x-request-id": rid, "content-type": "text/plain"},
            ),
            415,
        ),
        (
            locked.post(
                "/v1/prune",
                content=BIRD,
                params={"beta": "0"},
                headers={**PNG, **auth(), "x-request-id": rid},
            ),
            422,
        ),
    ):
        assert resp.headers["x-request-id"] == rid
        assert assert_problem(resp, status)["request_id"] == rid


def boom() -> Any:
    raise RuntimeError("secret internals /srv/app/thing.py")


def test_unexpected_error_has_reference_but_no_internals(
    locked_app: Any, locked: TestClient, caplog: pytest.LogCaptureFixture
) -> None:
    locked_app.dependency_overrides[job_function] = boom
    try:
        with caplog.at_level(logging.INFO):
            resp = locked.post(
                "/v1/prune", content=BIRD, headers={**PNG, **auth(), "x-request-id": "boom-1"}
            )
    finally:
        locked_app.dependency_overrides.clear()
    body = assert_problem(resp, 500, "internal error (reference")
    assert body["request_id"] == "boom-1"
    assert "secret internals" not in resp.text and "RuntimeError" not in resp.text
    text = "\n".join(JsonFormatter().format(r) for r in caplog.records)
    assert "boom-1" in text and "Traceback" not in text and 'File "' not in text
    access = [r for r in caplog.records if r.name == "service.access"]
    assert [r.status for r in access] == [500]  # type: ignore[attr-defined]


# --------------------------------------------------------------------------- logs
def test_one_json_log_line_per_request(
    locked: TestClient, caplog: pytest.LogCaptureFixture
) -> None:
    with caplog.at_level(logging.INFO, logger="service.access"):
        locked.post("/v1/prune", content=BIRD, headers={**PNG, **auth(), "x-request-id": "r1"})
        locked.post(
            "/v1/prune",
            content=BIRD,
            headers={**PNG, "authorization": "Bearer not-the-key", "x-request-id": "r2"},
        )
        locked.get("/healthz", headers={"x-request-id": "r3"})
    records = [r for r in caplog.records if r.name == "service.access"]
    lines = [json.loads(JsonFormatter().format(r)) for r in records]
    assert [(d["request_id"], d["method"], d["path"], d["status"]) for d in lines] == [
        ("r1", "POST", "/v1/prune", 200),
        ("r2", "POST", "/v1/prune", 401),
        ("r3", "GET", "/healthz", 200),
    ]
    for d in lines:
        assert d["duration_ms"] >= 0 and d["level"] == "INFO" and d["time"]
    text = "\n".join(JsonFormatter().format(r) for r in caplog.records)
    assert KEY not in text and "not-the-key" not in text and "Bearer" not in text


def test_json_formatter_is_one_line_without_tracebacks() -> None:
    try:
        raise ValueError("multi\nline")
    except ValueError as exc:
        record = logging.LogRecord(
            "service.x", logging.ERROR, __file__, 1, "failed: %s", (exc,), sys.exc_info()
        )
    record.request_id = "abc"
    line = JsonFormatter().format(record)
    assert "\n" not in line
    doc = json.loads(line)
    assert doc["message"] == "failed: multi\nline" and doc["request_id"] == "abc"
    assert doc["error"] == "ValueError" and "Traceback" not in line
    assert "Traceback" in json.loads(JsonFormatter(tracebacks=True).format(record))["traceback"]


def test_real_server_logs_json_lines_without_the_key(tmp_path: Path) -> None:
    log_path = tmp_path / "server.log"
    with running_server(log_path, workers="1", api_key=KEY, log_level="info") as (proc, base):
        ok = httpx.post(
            f"{base}/v1/prune",
            content=BIRD,
            timeout=60,
            headers={**PNG, "x-api-key": KEY, "x-request-id": "real-1"},
        )
        assert ok.status_code == 200 and ok.headers["x-request-id"] == "real-1"
        denied = httpx.post(
            f"{base}/v1/prune",
            content=BIRD,
            timeout=60,
            headers={**PNG, "authorization": "Bearer guessed-key"},
        )
        assert_problem(denied, 401)
        assert denied.headers["www-authenticate"].startswith("Bearer")
        code = stop(proc)
    assert code == 0
    text = log_path.read_text()
    assert KEY not in text and "guessed-key" not in text and "Traceback" not in text
    lines = [json.loads(line) for line in text.splitlines() if line.strip()]
    requests = [d for d in lines if d.get("logger") == "service.access"]
    by_id = {d["request_id"]: d for d in requests}
    assert by_id["real-1"]["status"] == 200 and by_id["real-1"]["path"] == "/v1/prune"
    assert by_id[denied.headers["x-request-id"]]["status"] == 401
    assert all(
        {"method", "path", "status", "duration_ms", "request_id"} <= set(d) for d in requests
    )
    # uvicorn's own lines are JSON too, and its plain-text access log is off
    assert any(d.get("logger", "").startswith("uvicorn") for d in lines)
