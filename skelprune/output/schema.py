"""The output document and the skeleton's GeoJSON, as types (docs/graph.md).

The one definition of what :meth:`~skelprune.output.document.PruneResult.to_dict` and
:meth:`~skelprune.output.document.PruneResult.to_geojson` return: ``TypedDict``s, with
each field's description and each list's length bounds as ``Annotated`` metadata
(:class:`Doc`, :class:`Len`). A type checker reads them as they are; the service builds
its response models (and so its OpenAPI schema) from them, field by field, so that the
two cannot drift. A key that may be absent is ``NotRequired`` (annotations are
evaluated, so that ``__required_keys__`` says so at run time too). Each type's name, less a
trailing ``Doc``, is its name in the OpenAPI schema.

The document's types are defined in :mod:`.schema_document`, the GeoJSON's in
:mod:`.schema_geojson`; every one is importable from here, with :func:`problems`, the
check of a value against them.

Examples
--------
>>> from typing import get_type_hints
>>> list(get_type_hints(CurveStepDoc))
['step', 'length', 'ar', 'lr', 'objective']
>>> problems({"step": 0, "length": 1.0, "ar": 0.5, "lr": "x"}, CurveStepDoc)
['$.lr: expected float, got str', '$: missing key objective']
"""

import functools
import math
import types
from typing import (
    Annotated,
    Any,
    Literal,
    NotRequired,
    Union,
    get_args,
    get_origin,
    get_type_hints,
    is_typeddict,
)

# every type of the document and the GeoJSON, importable from here
from .schema_document import DCE_THRESHOLD_APPLIED as DCE_THRESHOLD_APPLIED
from .schema_document import MIN_MARGIN_APPLIED as MIN_MARGIN_APPLIED
from .schema_document import SCOPE_APPLIED as SCOPE_APPLIED
from .schema_document import WINDOW_APPLIED as WINDOW_APPLIED
from .schema_document import BranchDoc as BranchDoc
from .schema_document import Choice as Choice
from .schema_document import Coarse as Coarse
from .schema_document import ComponentDoc as ComponentDoc
from .schema_document import CurveStepDoc as CurveStepDoc
from .schema_document import Doc as Doc
from .schema_document import ForegroundTakenDoc as ForegroundTakenDoc
from .schema_document import GeoreferenceDoc as GeoreferenceDoc
from .schema_document import Len as Len
from .schema_document import MedialAxisSummaryDoc as MedialAxisSummaryDoc
from .schema_document import Method as Method
from .schema_document import NodeDoc as NodeDoc
from .schema_document import NodeKind as NodeKind
from .schema_document import Point2 as Point2
from .schema_document import Point3 as Point3
from .schema_document import PruneDocument as PruneDocument
from .schema_document import RasterInfoDoc as RasterInfoDoc
from .schema_document import RasterWarningItemDoc as RasterWarningItemDoc
from .schema_document import Scope as Scope
from .schema_document import SequenceBranchDoc as SequenceBranchDoc
from .schema_document import SequenceDoc as SequenceDoc
from .schema_document import SequenceFrameDoc as SequenceFrameDoc
from .schema_document import SequenceNodeDoc as SequenceNodeDoc
from .schema_document import SkeletonDoc as SkeletonDoc
from .schema_document import VersionsDoc as VersionsDoc
from .schema_geojson import BranchFeatureDoc as BranchFeatureDoc
from .schema_geojson import BranchPropertiesDoc as BranchPropertiesDoc
from .schema_geojson import CollectionPropertiesDoc as CollectionPropertiesDoc
from .schema_geojson import ComponentSummaryDoc as ComponentSummaryDoc
from .schema_geojson import CrsDoc as CrsDoc
from .schema_geojson import CrsNamePropertiesDoc as CrsNamePropertiesDoc
from .schema_geojson import LineStringDoc as LineStringDoc
from .schema_geojson import NodeFeatureDoc as NodeFeatureDoc
from .schema_geojson import NodePropertiesDoc as NodePropertiesDoc
from .schema_geojson import PointGeometryDoc as PointGeometryDoc
from .schema_geojson import SkeletonGeoJSON as SkeletonGeoJSON

__all__ = [
    "BranchDoc",
    "ComponentDoc",
    "Doc",
    "Len",
    "NodeDoc",
    "PruneDocument",
    "SequenceDoc",
    "SkeletonGeoJSON",
    "problems",
]


@functools.cache
def _hints(td: Any) -> dict[str, Any]:
    return get_type_hints(td, include_extras=True)


def problems(value: Any, hint: Any = PruneDocument, at: str = "$") -> list[str]:
    """Where ``value`` departs from the type ``hint`` (by default the whole document):
    one message per wrong type, missing or unknown key, list of the wrong length or
    value outside its ``Literal``; empty when it conforms. As strict as the service's
    models: an int may stand for a float (JSON does not tell them apart), but a bool is
    no number, and NaN and infinities are not JSON numbers.
    """
    origin, args = get_origin(hint), get_args(hint)
    if origin is NotRequired:
        return problems(value, args[0], at)
    if origin is Annotated:
        out = problems(value, args[0], at)
        for m in args[1:]:
            n = len(value) if isinstance(m, Len) and isinstance(value, list) else None
            if n is not None and not (m.min or 0) <= n <= (n if m.max is None else m.max):
                out.append(f"{at}: length {len(value)} outside [{m.min}, {m.max}]")
        return out
    if origin in (Union, types.UnionType):
        tries = [problems(value, a, at) for a in args]
        return [] if any(not t for t in tries) else min(tries, key=len)
    if origin is Literal:
        return (
            []
            if value in args and type(value) is type(args[0])
            else [f"{at}: {value!r} not in {args}"]
        )
    if hint is type(None):
        return [] if value is None else [f"{at}: expected null, got {type(value).__name__}"]
    if is_typeddict(hint):
        if not isinstance(value, dict):
            return [f"{at}: expected an object, got {type(value).__name__}"]
        out = []
        hints = _hints(hint)
        for key, h in hints.items():
            if key in value:
                out += problems(value[key], h, f"{at}.{key}")
            elif key in hint.__required_keys__:
                out.append(f"{at}: missing key {key}")
        out += [f"{at}: unknown key {key}" for key in value if key not in hints]
        return out
    if origin is list:
        if not isinstance(value, list):
            return [f"{at}: expected a list, got {type(value).__name__}"]
        return [p for i, v in enumerate(value) for p in problems(v, args[0], f"{at}[{i}]")]
    ok = {
        float: lambda v: type(v) in (float, int) and math.isfinite(v),
        int: lambda v: type(v) is int,
        bool: lambda v: type(v) is bool,
        str: lambda v: type(v) is str,
    }[hint](value)
    return [] if ok else [f"{at}: expected {hint.__name__}, got {type(value).__name__}"]
