"""OpenAPI fragments: request bodies, responses and their examples.

Kept static (not computed from the library) so that ``openapi.md`` only changes when
the API does.
"""

from __future__ import annotations

from typing import Any

from service.worker.jobs import PNG_HEADER_COMPONENTS
from skelprune import ALGORITHM_VERSION, __version__

__all__ = [
    "METRICS_EXAMPLE",
    "PRUNE_REQUEST_BODY",
    "PRUNE_RESPONSES",
    "UNAUTHORIZED",
    "problem_example",
]

REF = "#/components/schemas/"

SQUARE_POLYGON = {
    "type": "Polygon",
    "coordinates": [[[0, 0], [40, 0], [40, 20], [0, 20], [0, 0]]],
}

DOCUMENT_EXAMPLE: dict[str, Any] = {
    "version": {"library": __version__, "algorithm": ALGORITHM_VERSION},
    "width": 60,
    "height": 30,
    "method": "bayesian",
    "beta": 9.0,
    "coarse": "dce",
    "choice": "argmin",
    "trim": True,
    "min_margin": 0.01,
    "dce_threshold": None,
    "foreground": {"rule": "auto", "shape": "light", "threshold": 127.5, "border": 1.0},
    "components": [
        {
            "area": 1000,
            "alpha": 8.64,
            "rer": 0.0,
            "ss": 1.28,
            "objective": 1.28,
            "medial_axis": {"rer": 0.0, "length": 71.08, "endpoints": 4, "branches": 5},
            "skeleton": {
                "length": 71.08,
                "nodes": [
                    {
                        "id": 0,
                        "x": 14.0,
                        "y": 14.0,
                        "radius": 10.0,
                        "kind": "junction",
                        "points": [[14.0, 14.0, 10.0], [14.0, 15.0, 10.0]],
                    },
                    {"id": 1, "x": 7.0, "y": 7.0, "radius": 3.0, "kind": "endpoint", "points": []},
                ],
                "branches": [
                    {
                        "id": 0,
                        "source": 0,
                        "target": 1,
                        "length": 9.9,
                        "points": [
                            [13.0, 13.0, 9.0],
                            [12.0, 12.0, 8.0],
                            [11.0, 11.0, 7.0],
                            [10.0, 10.0, 6.0],
                            [9.0, 9.0, 5.0],
                            [8.0, 8.0, 4.0],
                            [7.0, 7.0, 3.0],
                        ],
                        "off_path": [],
                        "margin": 0.046,
                        "removed_at": 1,
                    },
                ],
                "endpoints": [1],
            },
            "curve": [
                {"step": 0, "length": 71.08, "ar": 0.0, "lr": 1.28, "objective": 1.28},
                {"step": 1, "length": 62.18, "ar": 0.014, "lr": 1.19, "objective": 1.31},
            ],
            "chosen_step": 0,
        }
    ],
}

GEOJSON_EXAMPLE: dict[str, Any] = {
    "type": "FeatureCollection",
    "properties": {
        "width": 64,
        "height": 48,
        "method": "bayesian",
        "beta": 9.0,
        "coarse": "dce",
        "choice": "argmin",
        "trim": True,
        "min_margin": 0.01,
        "dce_threshold": None,
        "simplify": 0.5,
        "cut_ends": False,
        "components": [
            {
                "component": 0,
                "area": 1200,
                "alpha": 9.48,
                "rer": 0.0042,
                "ss": 1.79,
                "objective": 1.83,
            }
        ],
    },
    "features": [
        {
            "type": "Feature",
            "geometry": {
                "type": "LineString",
                "coordinates": [
                    [14.0, 14.0],
                    [13.0, 13.0],
                    [12.0, 12.0],
                    [11.0, 11.0],
                    [10.0, 10.0],
                    [9.0, 9.0],
                    [8.0, 8.0],
                    [7.0, 7.0],
                ],
            },
            "properties": {
                "component": 0,
                "kind": "branch",
                "id": 0,
                "source": 0,
                "target": 1,
                "length": 9.9,
                "radii": [10.0, 9.0, 8.0, 7.0, 6.0, 5.0, 4.0, 3.0],
                "margin": 0.046,
                "removed_at": 1,
                "rer": 0.0042,
                "ss": 1.79,
            },
        },
        {
            "type": "Feature",
            "geometry": {"type": "Point", "coordinates": [7.0, 7.0]},
            "properties": {
                "component": 0,
                "kind": "endpoint",
                "id": 1,
                "radius": 3.0,
                "rer": 0.0042,
                "ss": 1.79,
            },
        },
    ],
}

METRICS_EXAMPLE = (
    "# HELP skelprune_queue_depth Jobs waiting for a free worker.\n"
    "# TYPE skelprune_queue_depth gauge\n"
    "skelprune_queue_depth 0.0\n"
)


def problem_example(
    status: int, slug: str | None, title: str, detail: str, instance: str = "/v1/prune"
) -> dict[str, Any]:
    """A documented problem+json response with one example."""
    example = {
        "type": f"urn:skelprune:problem:{slug}" if slug else "about:blank",
        "title": title,
        "status": status,
        "detail": detail,
        "instance": instance,
    }
    response: dict[str, Any] = {
        "description": title,
        "content": {
            "application/problem+json": {
                "schema": {"$ref": REF + "Problem"},
                "example": example,
            }
        },
    }
    if status == 503:
        response["headers"] = {
            "Retry-After": {
                "description": "Seconds to wait before retrying.",
                "schema": {"type": "integer"},
            }
        }
    return response


#: Only when SKELPRUNE_API_KEY is set.
UNAUTHORIZED: dict[str, Any] = problem_example(
    401,
    "unauthorized",
    "Unauthorized",
    "API key required: send 'Authorization: Bearer <key>' or 'X-API-Key: <key>'",
)
UNAUTHORIZED["description"] = "Unauthorized (only when the service has an API key)"
UNAUTHORIZED["headers"] = {
    "WWW-Authenticate": {
        "description": 'The challenge: `Bearer realm="skelprune"`, with '
        '`error="invalid_token"` for a wrong key.',
        "schema": {"type": "string"},
    }
}

LISTED = (
    "one value a component, comma-separated, in the document's order, for at most "
    f"{PNG_HEADER_COMPONENTS} components"
)

_NUMBERS = {"type": "array", "items": {"type": "number"}}
_POSITION = {**_NUMBERS, "minItems": 2, "maxItems": 3}
_NUMBER_OR_NULL = {"type": ["number", "null"]}
#: The map lines (``lines=map`` or ``lines=main-path``, docs/gis.md): the GeoJSON that
#: ``skelprune centerlines`` writes, one feature per line or point, each with its input
#: Feature's index and properties.
MAP_LINES: dict[str, Any] = {
    "title": "MapLinesGeoJSON",
    "type": "object",
    "required": ["type", "features"],
    "properties": {
        "type": {"const": "FeatureCollection"},
        "name": {"type": "string"},
        "crs": {"type": "object", "description": "The input's CRS, where it named one."},
        "features": {
            "type": "array",
            "items": {
                "type": "object",
                "required": ["type", "properties", "geometry"],
                "properties": {
                    "type": {"const": "Feature"},
                    "properties": {
                        "type": "object",
                        "description": "`feature` (the input Feature's index), `part` (of "
                        "its polygon), `kind` (`line` or `point`), `length` and `width` "
                        "(a point's: its inscribed circle's diameter), `error` (null, or why "
                        "the Feature has no lines: a row without geometry), then the input "
                        "Feature's properties.",
                        "required": ["feature", "part", "kind", "length", "width", "error"],
                        "properties": {
                            "feature": {"type": ["integer", "string"]},
                            "part": {"type": ["integer", "null"]},
                            "kind": {"enum": ["line", "point", None]},
                            "length": _NUMBER_OR_NULL,
                            "width": _NUMBER_OR_NULL,
                            "error": {"type": ["string", "null"]},
                        },
                    },
                    "geometry": {
                        "anyOf": [
                            {
                                "type": "object",
                                "required": ["type", "coordinates"],
                                "properties": {
                                    "type": {"const": "LineString"},
                                    "coordinates": {
                                        "type": "array",
                                        "items": _POSITION,
                                        "minItems": 2,
                                    },
                                },
                            },
                            {
                                "type": "object",
                                "required": ["type", "coordinates"],
                                "properties": {
                                    "type": {"const": "Point"},
                                    "coordinates": _POSITION,
                                },
                            },
                            {"type": "null"},
                        ]
                    },
                },
            },
        },
    },
}
PRUNE_RESPONSES: dict[int | str, dict[str, Any]] = {
    200: {
        "description": "The pruned skeleton, in the format chosen by `Accept`.",
        "headers": {
            f"X-Skelprune-{name}": {
                "description": f"`image/png` answers only: {what}.",
                "schema": {"type": "string"},
            }
            for name, what in (
                ("Components", "the number of components (one value)"),
                ("RER", f"each component's `rer`, {LISTED}"),
                ("SS", f"each component's `ss`, {LISTED}"),
                ("Objective", f"each component's `objective`, {LISTED}"),
                (
                    "Values",
                    f"present when the answer has more than {PNG_HEADER_COMPONENTS} "
                    "components: the three lists are left out (headers stay a few "
                    "kilobytes, what proxies pass); the JSON document has every value",
                ),
            )
        },
        "content": {
            "application/json": {
                # an image's, a polygon's or a volume's document: one schema
                "schema": {"$ref": REF + "PruneDocument"},
                "example": DOCUMENT_EXAMPLE,
            },
            "image/png": {"schema": {"type": "string", "format": "binary"}},
            "application/geo+json": {
                # the skeleton's branches and nodes, or the map lines (lines=map)
                "schema": {"anyOf": [{"$ref": REF + "SkeletonGeoJSON"}, MAP_LINES]},
                "example": GEOJSON_EXAMPLE,
            },
        },
    },
    400: problem_example(
        400,
        "invalid-image",
        "Invalid image",
        "truncated PNG: file ends at byte 60 before the IEND chunk",
    ),
    401: UNAUTHORIZED,
    406: problem_example(
        406,
        "not-acceptable",
        "Not acceptable",
        "cannot produce any of 'text/html'; available: application/json, "
        "image/png, application/geo+json",
    ),
    413: {
        **problem_example(
            413,
            "image-too-large",
            "Image too large",
            "image has 100000000 pixels (10000×10000), the limit is 16777216",
        ),
        "description": "Image too large (`image-too-large`: the image, polygon raster or "
        "overlay over the pixel limit), or job too large (`job-too-large`: its memory or "
        "time, estimated from the input before any work, over the job's budget).",
    },
    415: problem_example(
        415,
        "unsupported-media-type",
        "Unsupported media type",
        "Content-Type 'text/plain' is not supported; send image/png, "
        "multipart/form-data (field 'file') or application/json (GeoJSON)",
    ),
    422: problem_example(
        422,
        "invalid-polygon",
        "Invalid polygon",
        "$.coordinates[0]: ring is not closed, first position [0.0, 0.0] "
        "differs from last [0.0, 20.0]",
    ),
    500: problem_example(
        500,
        "worker-crashed",
        "Worker crashed",
        "the worker process died while running this job (killed by signal "
        "SIGKILL); it has been replaced",
    ),
    503: problem_example(
        503, "queue-full", "Service busy", "all 4 workers are busy and 16 jobs are already waiting"
    ),
    504: problem_example(
        504, "job-timeout", "Job timed out", "job exceeded the time limit of 30 s and was stopped"
    ),
}

PRUNE_REQUEST_BODY: dict[str, Any] = {
    "required": True,
    "content": {
        "image/png": {"schema": {"type": "string", "format": "binary"}},
        "image/gif": {
            "schema": {"type": "string", "format": "binary", "description": "A GIF mask."}
        },
        "image/tiff": {
            "schema": {
                "type": "string",
                "format": "binary",
                "description": "A TIFF mask, a GeoTIFF mask, or a stack of pages (a volume).",
            }
        },
        "application/x-npy": {
            "schema": {
                "type": "string",
                "format": "binary",
                "description": "A volume: a .npy file of a 3-D boolean or integer array.",
            }
        },
        "multipart/form-data": {
            "schema": {
                "type": "object",
                "required": ["file"],
                "properties": {
                    "file": {"type": "string", "format": "binary", "description": "The PNG mask."}
                },
            },
            "encoding": {"file": {"contentType": "image/png"}},
        },
        "application/json": {
            "schema": {"$ref": REF + "PolygonRequest"},
            "examples": {
                "polygon": {"summary": "A bare GeoJSON Polygon", "value": SQUARE_POLYGON},
                "with-options": {
                    "summary": "GeoJSON with options in the body",
                    "value": {"geojson": SQUARE_POLYGON, "beta": 9.0, "pixel_size": 0.1},
                },
            },
        },
        "application/geo+json": {
            "schema": {"$ref": REF + "PolygonRequest"},
            "example": SQUARE_POLYGON,
        },
    },
}
