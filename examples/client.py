"""A small Python client of the skelprune service (needs ``httpx``).

Run it from the repository, with the service running (``make run``):

    python examples/client.py [http://127.0.0.1:8000 [OVERLAY.png]]

It prunes ``examples/shape.png`` and ``examples/shape.geojson``, prints each answer's
numbers and writes the overlay of the PNG to ``OVERLAY.png`` (default: a file in the
system's temporary folder, so that running it leaves the repository as it was).
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path
from typing import Any

import httpx

HERE = Path(__file__).parent


def prune_png(client: httpx.Client, path: Path, **options: Any) -> dict[str, Any]:
    """The result document of a PNG mask; options go in the query string."""
    resp = client.post(
        "/v1/prune",
        content=path.read_bytes(),
        params=options,
        headers={"Content-Type": "image/png"},
    )
    return answer(resp).json()


def prune_geojson(client: httpx.Client, path: Path, **options: Any) -> dict[str, Any]:
    """The result document of a GeoJSON polygon, in the polygon's own coordinates."""
    resp = client.post(
        "/v1/prune",
        content=path.read_bytes(),
        params=options,
        headers={"Content-Type": "application/geo+json"},
    )
    return answer(resp).json()


def overlay_png(client: httpx.Client, path: Path) -> tuple[bytes, float]:
    """The overlay image of a PNG mask and its RER (from the answer's headers)."""
    resp = client.post(
        "/v1/prune",
        content=path.read_bytes(),
        headers={"Content-Type": "image/png", "Accept": "image/png"},
    )
    answer(resp)
    return resp.content, float(resp.headers["X-Skelprune-RER"].split(",")[0])


def answer(resp: httpx.Response) -> httpx.Response:
    """The response, or an error carrying the service's problem detail."""
    if resp.status_code >= 400:
        problem = resp.json()  # application/problem+json
        raise RuntimeError(f"{resp.status_code} {problem['title']}: {problem['detail']}")
    return resp


def main(base: str = "http://127.0.0.1:8000", overlay: str | None = None) -> None:
    out = Path(overlay) if overlay else Path(tempfile.gettempdir()) / "skelprune-overlay.png"
    with httpx.Client(base_url=base, timeout=60) as client:
        doc = prune_png(client, HERE / "shape.png", beta=9, curve="false")
        comp = doc["components"][0]
        print(
            f"shape.png: RER {comp['rer']:.4f}, SS {comp['ss']:.3f}, "
            f"{len(comp['skeleton']['endpoints'])} endpoints, "
            f"{len(comp['skeleton']['branches'])} branches"
        )
        doc = prune_geojson(client, HERE / "shape.geojson", curve="false")
        comp = doc["components"][0]
        print(
            f"shape.geojson: RER {comp['rer']:.4f}, skeleton length "
            f"{comp['skeleton']['length']:.1f} (polygon units)"
        )
        png, rer = overlay_png(client, HERE / "shape.png")
        out.write_bytes(png)
        print(f"{out} written ({len(png)} bytes, RER {rer:.4f})")


if __name__ == "__main__":
    try:
        main(*sys.argv[1:3])
    except httpx.TransportError as exc:  # no service there: say so in one line
        sys.exit(f"error: no answer from the service ({exc}); start it with `make run`")
