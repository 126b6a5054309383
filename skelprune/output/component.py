"""One component's answer: the pruned skeleton, its sequence and its numbers (docs/graph.md).

``ComponentResult`` holds the answer and its sequence, and reads the answer once into a
:class:`~skelprune.output.table.BranchTable` (skan's "data" side); its document part,
GeoJSON, networkx graph and overlay marks are views of that table
(:mod:`skelprune.output.views`). :class:`~skelprune.output.document.PruneResult` holds
the components of one input.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import cast

import numpy as np

from ..grid import Orientation
from ..grid.graph import BranchGraph
from ..grid.tips import Trim
from ..io.frame import IDENTITY, PixelFrame
from ..pruning.bayesian import PruningSequence, target
from ..pruning.grid import path_length
from ..pruning.margin import Margins
from ..skeleton import Skeleton
from .schema import BranchDoc, ComponentDoc, NodeDoc, SequenceDoc
from .table import BranchTable, branch_table, frame_distances
from .views import branch_dicts, node_dicts, sequence_dict

__all__ = ["ComponentResult", "GraphSummary"]


@dataclass(frozen=True)
class GraphSummary:
    """Size of a skeleton, kept for the medial axis once pruning has begun."""

    length: float
    endpoints: int
    branches: int

    @classmethod
    def of(cls, skeleton: Skeleton) -> GraphSummary:
        return cls(skeleton.length, skeleton.n_endpoints, skeleton.n_branches)


@dataclass
class ComponentResult:
    """Pruned skeleton of one 8-connected component.

    ``skeleton`` is the answer, ``S(chosen_step)`` of ``sequence`` with its tips cut
    when ``trim`` is set (then ``rer``, ``ss``, ``objective`` and the curve's chosen point
    are the trimmed skeleton's); its pixel coordinates are in the component's padded
    crop seen in its canonical orientation, and :meth:`image_coordinates` maps them to
    the image.
    """

    skeleton: Skeleton
    axis_summary: GraphSummary
    sequence: PruningSequence[Skeleton]
    chosen_step: int
    ma_rer: float
    margins: Margins = field(default_factory=Margins)
    trim: Trim | None = None
    #: The component's label in a label image (None otherwise).
    label: int | None = None

    # the answer's parts, as the reporting below reads them
    @property
    def graph(self) -> BranchGraph:
        return self.skeleton.graph

    @property
    def r2(self) -> np.ndarray:
        return self.skeleton.r2

    @property
    def origin(self) -> tuple[int, int]:
        return self.skeleton.origin

    @property
    def orientation(self) -> Orientation:
        return self.skeleton.orientation

    @property
    def area(self) -> int:
        return self.skeleton.area

    def image_coordinates(
        self, rows: np.ndarray, cols: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Rows and columns of graph points in the image frame."""
        return self.skeleton.image_coordinates(rows, cols)

    @property
    def alpha(self) -> float | None:
        return self.sequence.alpha

    def chosen_point(self) -> tuple[float, float, float, float]:
        """Length, ``AR``, ``LR`` and ``λ`` of the answer (trimmed, if it was)."""
        seq, k, t = self.sequence, self.chosen_step, self.trim
        if t is None or seq.alpha is None:
            return (
                float(seq.length[k]),
                float(seq.rer[k]),
                float(seq.ss[k]),
                float(seq.objective[k]),
            )
        length = path_length(t.steps, t.skeleton.step_weights)
        return (
            length,
            t.lost / seq.area,
            float(np.log(length / seq.lbar + 1.0)),
            target(t.lost, seq.area, length, seq.alpha, seq.lbar),
        )

    @property
    def rer(self) -> float:
        return self.chosen_point()[1]

    @property
    def ss(self) -> float:
        return self.chosen_point()[2]

    @property
    def objective(self) -> float:
        return self.chosen_point()[3]

    def points(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Rows, cols (image frame) and squared radii of the pruned skeleton."""
        idx = self.graph.alive_points()
        rows, cols = self.image_coordinates(self.graph.rows[idx], self.graph.cols[idx])
        return rows, cols, self.r2[idx]

    @cached_property
    def table(self) -> BranchTable:
        """The pruned skeleton's nodes and branches as flat arrays, in image pixel
        coordinates (:mod:`skelprune.output.table`): what every output reads."""
        return branch_table(self.skeleton, self.margins)

    def skeleton_table(self) -> tuple[list[NodeDoc], list[BranchDoc]]:
        """Nodes and branches of the pruned skeleton, in image pixel coordinates
        (the ``skeleton`` part of the document before any frame is applied)."""
        return node_dicts(self.table), branch_dicts(self.table)

    def sequence_table(self, frame: PixelFrame = IDENTITY) -> SequenceDoc:
        """The pruning sequence as a viewer needs it (:func:`~.views.sequence_dict`)."""
        return sequence_dict(self.sequence, self.skeleton, frame)

    def to_dict(
        self, curve: bool = True, frame: PixelFrame = IDENTITY, sequence: bool = False
    ) -> ComponentDoc:
        view = self.table.framed(frame)
        nodes = node_dicts(view)
        ma = self.axis_summary
        seq = self.sequence
        chosen = self.chosen_point()
        # cast: the label's key comes first when there is one, which a TypedDict
        # literal cannot say
        doc = cast(
            ComponentDoc,
            {
                **({} if self.label is None else {"label": self.label}),
                "area": self.area,
                "alpha": None if self.alpha is None else float(self.alpha),
                "rer": chosen[1],
                "ss": chosen[2],
                "objective": chosen[3],
                "medial_axis": {
                    "rer": float(self.ma_rer),
                    "length": frame.distance(ma.length),
                    "endpoints": ma.endpoints,
                    "branches": ma.branches,
                },
                "skeleton": {
                    "length": frame.distance(chosen[0]),
                    "nodes": nodes,
                    "branches": branch_dicts(view),
                    "endpoints": [n["id"] for n in nodes if n["kind"] == "endpoint"],
                },
                "chosen_step": self.chosen_step,
            },
        )
        if curve:
            length = frame_distances(frame, np.asarray(seq.length, np.float64)).tolist()
            doc["curve"] = [
                {"step": i, "length": L, "ar": a, "lr": lr, "objective": o}
                for i, (L, a, lr, o) in enumerate(
                    zip(
                        length,
                        np.asarray(seq.rer, np.float64).tolist(),
                        np.asarray(seq.ss, np.float64).tolist(),
                        np.asarray(seq.objective, np.float64).tolist(),
                        strict=True,
                    )
                )
            ]
            if self.trim is not None:  # the chosen point is the answer, tips cut
                L, a, lr, o = chosen
                point = doc["curve"][self.chosen_step]
                point["length"], point["ar"] = frame.distance(L), a
                point["lr"], point["objective"] = lr, o
        if sequence:
            doc["sequence"] = self.sequence_table(frame)
        return doc
