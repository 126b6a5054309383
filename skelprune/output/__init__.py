"""Output: the result types, their document and GeoJSON (:mod:`.document`), and the
overlay image (:mod:`.render`). The last stage of the pipeline."""

from .document import ComponentResult, GraphSummary, PruneResult

__all__ = ["ComponentResult", "GraphSummary", "PruneResult"]
