"""Each endpoint's OpenAPI documentation: description, parameters, request body and
responses, built from the examples of :mod:`service.apidocs.examples`.

Kept static, as those are, so that ``openapi.md`` only changes when the API does.
"""

from __future__ import annotations

from dataclasses import fields
from typing import Any

from service.apidocs.examples import (
    METRICS_EXAMPLE,
    PRUNE_REQUEST_BODY,
    PRUNE_RESPONSES,
    SQUARE_POLYGON,
    UNAUTHORIZED,
    problem_example,
)
from service.http.bodies import BATCH_MAX_ITEMS
from service.http.negotiation import NDJSON
from service.http.schemas import PruneQuery, query_parameters
from skelprune import ALGORITHM_VERSION, __version__
from skelprune.options import OutputOptions

Responses = dict[int | str, dict[str, Any]]

# --- POST /v1/prune ----------------------------------------------------------------------

PRUNE_DESCRIPTION = """
Compute the pruned skeleton of a shape.

**Input** (by `Content-Type`):
- `image/png`: the PNG itself as the body; `image/gif`: a one-frame GIF mask, read as a
  PNG is; the body's bytes must be the declared type (415);
- `image/tiff`: a single-image TIFF as the body (docs/tables.md#tiff); a GeoTIFF mask
  (GeoTIFF tags: a north-up grid, an EPSG CRS) is its non-zero pixels but nodata, and
  the GeoJSON answer's lines are in its map coordinates and CRS (docs/gis.md);
- a volume: `application/x-npy` (a `.npy` file of a 3-D boolean or integer array, no
  pickles) or `image/tiff` with several pages (a stack, one page a slice), as the body;
  its voxels count against the pixel limit, `spacing=dz,dy,dx` gives the voxel's size
  (docs/volumes.md). The answer is the 3-D document (`application/json`, points
  `[x, y, z, radius]`), the three projections with the skeleton (`image/png`), the
  branch table (`text/csv`) or the skeleton as SWC (`text/x-swc`, for neuron tools);
- `multipart/form-data`: the PNG, TIFF or GIF in the field `file`;
- `application/json` (or `application/geo+json`): a GeoJSON `Polygon`, `MultiPolygon`,
  `Feature` or `FeatureCollection` (holes allowed), or an object
  `{"geojson": <GeoJSON>, <options>}`. The polygon is rasterised (default: a pixel size
  fitted to the polygon, a few pixels across its narrowest part) and every coordinate,
  radius and length in the answer is in the polygon's own frame and units. Where the
  raster does not hold a part of the polygon as it is (a part vanished or split, a hole
  closed), the answer says so in `warnings`, with a pixel size that holds it.

**Output** (by `Accept`): `application/json` (default) the result document
(`PruneDocument` below: per component its RER, SS, λ and the skeleton graph, nodes with
radii and branches as paths), `image/png` the overlay image (the numbers in the
`X-Skelprune-*` headers), `application/geo+json` the skeleton as GeoJSON (the numbers in
its properties; for a polygon, `lines=map`: the map lines, the GeoJSON `skelprune
centerlines` writes, each Feature pruned on its own; `lines=main-path`: one line per
network, its longest path; docs/gis.md), `text/csv` the branch table (`table=component`:
the component table; docs/tables.md), `application/graphml+xml` the skeleton as GraphML,
`text/x-swc` a volume's skeleton as SWC. `labels=true` reads an integer image as a label
image, each value its own shape. No answer holds NaN or infinity: a number that is not
defined (a junction angle where a branch has no direction) is null (an empty CSV cell).

Options go in the query string, or in the body (multipart fields beside `file`; the
JSON envelope), never both; an option where it does not apply is refused (422).
"""

#: The query options are parsed in the handler (``parse_query``): documented from the model.
PRUNE_PARAMETERS = query_parameters(PruneQuery)
PRUNE_EXTRA = {"requestBody": PRUNE_REQUEST_BODY, "parameters": PRUNE_PARAMETERS}

# --- POST /v1/prune/batch ----------------------------------------------------------------

BATCH_DESCRIPTION = f"""
Prune several shapes in one request; the answer is NDJSON (`{NDJSON}`), one line per
shape in input order: `{{"index": i, "result": <document>}}` or
`{{"index": i, "problem": <problem details>}}`. One shape's failure never fails the others.

**Input**: `multipart/form-data` with the PNGs or TIFFs in repeated fields `file` (options as other
fields or in the query), or `application/json`: a list of GeoJSON objects (`Polygon`,
`MultiPolygon`, `Feature`, `FeatureCollection`; options in the query). At most
{BATCH_MAX_ITEMS} shapes; the body limit is the one of `POST /v1/prune`. The options
apply to every shape. Shapes are pruned one after another, each a job of the same worker
pool and queue as `POST /v1/prune`: a batch holds at most one worker at a time, so single
requests are never starved by it; a shape that meets a full queue gets its 503 problem.
"""

BATCH_RESPONSES: Responses = {
    **{k: v for k, v in PRUNE_RESPONSES.items() if k != 200},
    200: {
        "description": "One JSON line per shape, in input order.",
        "content": {
            NDJSON: {
                "schema": {"type": "string"},
                "example": (
                    '{"index":0,"result":{"width":60,"height":30,"components":[…]}}\n'
                    '{"index":1,"problem":{"type":"urn:skelprune:problem:invalid-image",'
                    '"title":"Invalid image","status":400,"detail":"not a PNG file '
                    '(bad signature)"}}\n'
                ),
            }
        },
    },
    413: problem_example(
        413,
        "body-too-large",
        "Request body too large",
        f"a batch holds at most {BATCH_MAX_ITEMS} shapes, got 40",
        "/v1/prune/batch",
    ),
}

BATCH_EXTRA = {
    "parameters": PRUNE_PARAMETERS,
    "requestBody": {
        "required": True,
        "content": {
            "multipart/form-data": {
                "schema": {
                    "type": "object",
                    "properties": {
                        "file": {
                            "type": "array",
                            "items": {"type": "string", "format": "binary"},
                            "maxItems": BATCH_MAX_ITEMS,
                        }
                    },
                    "required": ["file"],
                }
            },
            "application/json": {
                "schema": {
                    "type": "array",
                    "maxItems": BATCH_MAX_ITEMS,
                    "items": {"type": "object"},
                }
            },
        },
    },
}

# --- POST /v1/match ----------------------------------------------------------------------

MATCH_DESCRIPTION = """
Match the skeletons of two shapes by path similarity (Bai & Latecki 2008): the distance
(0 for the same skeleton, symmetric, unchanged by turning, mirroring and scaling up to
what pixels change) and which endpoint of `a` corresponds to which of `b`.

**Input** (by `Content-Type`):
- `multipart/form-data`: two PNG masks in the fields `a` and `b`;
- `application/json`: `{"a": <GeoJSON>, "b": <GeoJSON>}`, each a `Polygon`,
  `MultiPolygon`, `Feature` or `FeatureCollection`; positions in the answer are in each
  polygon's own frame.

Pruning options (`beta`, `method`, `coarse`, …) go in the query and apply to both
shapes; so do `foreground` (PNG) and the raster options (polygons). Each shape's largest
component is matched. A skeleton with fewer than two endpoints (a ring, a disk reduced
to a point) cannot be matched: 422 `unmatchable-shape`.
"""

MATCH_REQUEST_BODY: dict[str, Any] = {
    "required": True,
    "content": {
        "multipart/form-data": {
            "schema": {
                "type": "object",
                "required": ["a", "b"],
                "properties": {
                    "a": {"type": "string", "format": "binary", "description": "PNG mask a."},
                    "b": {"type": "string", "format": "binary", "description": "PNG mask b."},
                },
            },
            "encoding": {"a": {"contentType": "image/png"}, "b": {"contentType": "image/png"}},
        },
        "application/json": {
            "schema": {"$ref": "#/components/schemas/MatchPolygons"},
            "example": {"a": SQUARE_POLYGON, "b": SQUARE_POLYGON},
        },
    },
}

MATCH_EXAMPLE = {
    "distance": 0.0,
    "mirrored": False,
    "endpoints": [4, 4],
    "correspondence": [
        {
            "a": {"component": 0, "node": 2, "x": 1.0, "y": 1.0},
            "b": {"component": 0, "node": 2, "x": 1.0, "y": 1.0},
        },
    ],
}

MATCH_RESPONSES: Responses = {
    **{k: v for k, v in PRUNE_RESPONSES.items() if k not in (200, 406)},
    200: {
        "description": "The distance and the endpoint correspondence.",
        "content": {
            "application/json": {
                "schema": {"$ref": "#/components/schemas/MatchDocument"},
                "example": MATCH_EXAMPLE,
            }
        },
    },
}

MATCH_EXTRA = {
    "requestBody": MATCH_REQUEST_BODY,
    # no output option applies to a match
    "parameters": [
        p for p in PRUNE_PARAMETERS if p["name"] not in {f.name for f in fields(OutputOptions)}
    ],
}

# --- operations ---------------------------------------------------------------------------


def _ok(example: dict[str, Any]) -> dict[str, Any]:
    return {"content": {"application/json": {"example": example}}}


HEALTH_RESPONSES: Responses = {
    200: _ok({"status": "ok", "version": __version__, "algorithm": ALGORITHM_VERSION})
}

VERSION_RESPONSES: Responses = {
    200: _ok({"service": __version__, "library": __version__, "algorithm": ALGORITHM_VERSION})
}

READY_RESPONSES: Responses = {
    200: _ok({"status": "ready", "workers": 4, "busy": 1, "queued": 0, "queue_size": 16}),
    503: problem_example(
        503, "queue-full", "Service busy", "the queue is full (16 jobs waiting)", "/readyz"
    ),
}

METRICS_RESPONSES: Responses = {
    200: {
        "description": "Prometheus text exposition format.",
        "content": {"text/plain": {"schema": {"type": "string"}, "example": METRICS_EXAMPLE}},
    },
    401: UNAUTHORIZED,
}
