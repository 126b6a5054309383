"""The viewer page: ``GET /`` and its two assets under ``/ui/``, all served from
``service/static`` (no network needed, nothing to build). Not part of the API schema."""

from __future__ import annotations

from pathlib import Path

from fastapi import APIRouter
from fastapi.responses import FileResponse

__all__ = ["STATIC", "router"]

STATIC = Path(__file__).parents[2] / "static"
#: Revalidate on every load (the ETag makes that cheap): a new version shows at once.
HEADERS = {"Cache-Control": "no-cache"}

router = APIRouter(include_in_schema=False)


@router.get("/")
async def index() -> FileResponse:
    return FileResponse(STATIC / "index.html", media_type="text/html", headers=HEADERS)


@router.get("/ui/app.js")
async def script() -> FileResponse:
    return FileResponse(STATIC / "app.js", media_type="text/javascript", headers=HEADERS)


@router.get("/ui/style.css")
async def stylesheet() -> FileResponse:
    return FileResponse(STATIC / "style.css", media_type="text/css", headers=HEADERS)
