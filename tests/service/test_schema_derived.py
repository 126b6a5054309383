"""The service's response models are the library's document types: built from them,
accepting what the library writes, refusing what it does not."""

from __future__ import annotations

from typing import get_type_hints

import numpy as np
import pydantic
import pytest

import skelprune
from service.http import schemas
from skelprune.output import schema


def _documents() -> tuple[dict, dict, dict, dict]:
    m = np.zeros((30, 50), bool)
    m[5:25, 5:45] = True
    m[12:18, 20:30] = False  # a hole: a loop
    res = skelprune.prune(m)
    polygon = {"type": "Polygon", "coordinates": [[[0, 0], [30, 0], [30, 8], [0, 8], [0, 0]]]}
    poly = skelprune.prune(polygon)
    return (
        res.to_dict(sequence=True, overlay=True),
        poly.to_dict(sequence=True),
        res.to_geojson(cut_ends=True),
        poly.to_geojson(),
    )


def test_the_service_models_accept_the_library_documents() -> None:
    image, polygon, image_geo, polygon_geo = _documents()
    v = np.zeros((12, 14, 40), np.uint8)
    v[3:9, 4:10, 3:20], v[3:9, 4:10, 22:37] = 1, 2  # a label volume
    volume = skelprune.prune(v, spacing=(2.0, 1.0, 1.0)).to_dict()
    for doc in (image, polygon, volume):
        assert schema.problems(doc) == []
        schemas.PruneDocument.model_validate(doc)
    for geo in (image_geo, polygon_geo):
        assert schema.problems(geo, schema.SkeletonGeoJSON) == []
        schemas.SkeletonGeoJSON.model_validate(geo)


def test_the_service_models_refuse_what_the_library_schema_refuses() -> None:
    image, *_ = _documents()
    image["components"][0]["skeleton"]["branches"][0]["colour"] = "red"
    assert schema.problems(image)
    with pytest.raises(pydantic.ValidationError):
        schemas.PruneDocument.model_validate(image)


def test_every_model_has_the_fields_of_its_library_type() -> None:
    for td, model in schemas._MODELS.items():
        hints = get_type_hints(td, include_extras=True)
        assert model.__name__ == td.__name__.removesuffix("Doc")
        assert list(model.model_fields) == list(hints)
        for name, field in model.model_fields.items():
            optional = name in td.__optional_keys__
            assert field.is_required() is not optional, (model.__name__, name)
            doc = [m for m in getattr(hints[name], "__metadata__", ()) if isinstance(m, schema.Doc)]
            if doc:
                assert field.description == doc[0].text
    # every document type of the library has its model
    names = {td.__name__ for td in schemas._MODELS}
    assert {"PruneDocument", "ComponentDoc", "SequenceNodeDoc", "BranchFeatureDoc"} <= names
