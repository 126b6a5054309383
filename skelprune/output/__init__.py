"""Output: the result types (:mod:`.document`), each component's answer as a branch
table (:mod:`.table`) and its views: the document's skeleton parts and the networkx graph
(:mod:`.views`), the GeoJSON (:mod:`.geojson`, lines by :mod:`.lines`) and the overlay
image (:mod:`.render`); the document's types (:mod:`.schema`). The last stage of the
pipeline."""

from .component import ComponentResult, GraphSummary
from .document import PruneResult
from .table import BranchTable

__all__ = ["BranchTable", "ComponentResult", "GraphSummary", "PruneResult"]
