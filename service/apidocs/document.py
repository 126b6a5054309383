"""The OpenAPI document the application serves at ``/openapi.json``, and its pages
``/docs`` (Swagger UI) and ``/redoc`` with their scripts served by the service itself.

FastAPI's document is completed here: the query options without their ``null``
branches, the answers' and requests' models as components, the 200 examples whole and
the API key's security schemes.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

from fastapi import FastAPI
from fastapi.openapi.docs import get_redoc_html, get_swagger_ui_html
from fastapi.openapi.utils import get_openapi
from fastapi.responses import HTMLResponse
from fastapi.staticfiles import StaticFiles
from pydantic.json_schema import models_json_schema

from service.apidocs import examples
from service.http.api_key import OPEN_PATHS
from service.http.schemas import (
    MatchDocument,
    MatchPolygons,
    Problem,
    PruneDocument,
    SkeletonGeoJSON,
    polygon_request_adapter,
)

__all__ = ["install_docs"]

REF_TEMPLATE = "#/components/schemas/{model}"
DOCS_ASSETS = "/docs-assets"  # Swagger UI's and ReDoc's scripts


def install_docs(app: FastAPI) -> None:
    """Serve the OpenAPI document (built once, on its first request) and its two pages."""
    app.openapi = _openapi(app)  # type: ignore[method-assign]
    _offline_docs(app)


def _simplify_query_params(schema: dict[str, Any]) -> None:
    """``X | None`` query options: drop the ``null`` branch, a query string cannot be null."""
    for operations in schema.get("paths", {}).values():
        for op in operations.values():
            for param in op.get("parameters", []):
                sub = param.get("schema", {})
                branches = sub.get("anyOf")
                if param.get("in") == "query" and branches:
                    kept = [b for b in branches if b != {"type": "null"}]
                    if len(kept) == 1:
                        del sub["anyOf"]
                        sub.update(kept[0])


def _openapi(app: FastAPI) -> Callable[[], dict[str, Any]]:
    def build() -> dict[str, Any]:
        if app.openapi_schema is None:
            schema = get_openapi(
                title=app.title,
                version=app.version,
                description=app.description,
                routes=app.routes,
            )
            _simplify_query_params(schema)
            # get_openapi drops None values from examples; put the 200 examples back whole.
            ok = schema["paths"]["/v1/prune"]["post"]["responses"]["200"]["content"]
            for media, content in examples.PRUNE_RESPONSES[200]["content"].items():
                if "example" in content:
                    ok[media]["example"] = content["example"]
            components = schema.setdefault("components", {}).setdefault("schemas", {})
            _, defs = models_json_schema(
                [
                    (m, "validation")
                    for m in (Problem, PruneDocument, SkeletonGeoJSON, MatchDocument, MatchPolygons)
                ],
                ref_template=REF_TEMPLATE,
            )
            components.update(defs.get("$defs", {}))
            request = polygon_request_adapter.json_schema(ref_template=REF_TEMPLATE)
            components.update(request.pop("$defs", {}))
            components["PolygonRequest"] = {"title": "PolygonRequest", **request}
            # SKELPRUNE_API_KEY, when set: either header will do; {} = no key configured.
            schema["components"]["securitySchemes"] = {
                "bearer": {
                    "type": "http",
                    "scheme": "bearer",
                    "description": "`Authorization: Bearer <SKELPRUNE_API_KEY>`",
                },
                "apiKey": {
                    "type": "apiKey",
                    "in": "header",
                    "name": "X-API-Key",
                    "description": "`X-API-Key: <SKELPRUNE_API_KEY>`",
                },
            }
            for path, operations in schema["paths"].items():
                if path not in OPEN_PATHS:
                    for op in operations.values():
                        op["security"] = [{"bearer": []}, {"apiKey": []}, {}]
            # Round-trip through JSON so that the document is plain data (stable output).
            app.openapi_schema = json.loads(json.dumps(schema, sort_keys=True))
        return app.openapi_schema

    return build


def _offline_docs(app: FastAPI) -> None:
    """``/docs`` (Swagger UI) and ``/redoc`` with their scripts served by the service
    itself, from the ``fastapi-offline`` package: they work with no network."""
    import fastapi_offline

    assets = Path(fastapi_offline.__file__).parent / "static"
    app.mount(DOCS_ASSETS, StaticFiles(directory=assets), name="docs-assets")

    @app.get("/docs", include_in_schema=False)
    async def swagger_ui() -> HTMLResponse:
        return get_swagger_ui_html(
            openapi_url="/openapi.json",
            title=f"{app.title} - Swagger UI",
            swagger_js_url=f"{DOCS_ASSETS}/swagger-ui-bundle.js",
            swagger_css_url=f"{DOCS_ASSETS}/swagger-ui.css",
            swagger_favicon_url=f"{DOCS_ASSETS}/favicon.png",
        )

    @app.get("/redoc", include_in_schema=False)
    async def redoc() -> HTMLResponse:
        return get_redoc_html(
            openapi_url="/openapi.json",
            title=f"{app.title} - ReDoc",
            redoc_js_url=f"{DOCS_ASSETS}/redoc.standalone.js",
            redoc_favicon_url=f"{DOCS_ASSETS}/favicon.png",
            with_google_fonts=False,
        )
