"""Results of pruning and their serialisation (docs/graph.md).

``ComponentResult`` holds arrays (skan's "data" side); ``to_dict`` and
``to_geojson`` are the reporting side, producing plain JSON types.
"""

from __future__ import annotations

import base64
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from .._orientation import Orientation
from .._version import ALGORITHM_VERSION, __version__
from ..graph import BranchGraph, step_length
from ..io.foreground import Foreground
from ..io.frame import IDENTITY, PixelFrame
from ..options import OutputOptions, PruneOptions

if TYPE_CHECKING:
    from ..io.input import Input
    from ..io.polygon import PolygonRaster
from ..pruning.bayesian import PruningSequence
from ..pruning.bayesian import objective as target
from ..pruning.margin import Margins
from ..pruning.tips import Trim
from ..reconstruction import reconstruction
from ..skeleton import Skeleton
from .render import auto_scale, encode_png, render_overlay

__all__ = ["ComponentResult", "PruneResult", "branch_line"]


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
    medial_axis: GraphSummary
    sequence: PruningSequence
    chosen_step: int
    ma_rer: float
    margins: Margins = field(default_factory=Margins)
    trim: Trim | None = None

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
                float(seq.ar[k]),
                float(seq.lr[k]),
                float(seq.objective[k]),
            )
        length = float(step_length(t.na, t.nd))
        return (
            length,
            t.lost / seq.area,
            float(np.log(length / seq.lbar + 1.0)),
            target(t.lost, seq.area, t.na, t.nd, seq.alpha, seq.lbar),
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

    def skeleton_table(self) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
        """Nodes and branches of the pruned skeleton, in image pixel coordinates
        (the ``skeleton`` part of the document before any frame is applied)."""
        nodes, branches, _, _ = _graph_table(self.skeleton, self.margins)
        return nodes, branches

    def sequence_table(self) -> dict[str, Any]:
        """The pruning sequence as a viewer needs it (image pixel coordinates).

        ``S(0)``'s nodes and branches (ids of their own), each branch with the step whose
        removal takes its pixels (``removed_at``) and, where a junction dissolved into a
        merge, the step and the branch it became part of (``absorbed_at``,
        ``absorbed_into``); each junction node with the step that dissolved it and the
        branch its pixels joined. Replayed on a copy of the start's graph, so the events
        are exactly those of :attr:`sequence`. ``uncovered`` lists the shape's pixels
        ``S(0)`` misses, so that ``D \\ R(S(k))`` follows from the disks alone, and
        ``coarse_removed`` the medial axis's pixels the coarse stage took before step 0.
        """
        seq = self.sequence
        start = seq.start
        nodes, branches, branch_id, junction_id = _graph_table(start, None)
        for b in branches:  # margins belong to the answer; here: the events
            del b["margin"]
            b.update(removed_at=None, absorbed_at=None, absorbed_into=None)
        for n in nodes:
            if n["kind"] == "junction":
                n.update(removed_at=None, dissolved_at=None, dissolved_into=None)
        # Owners as the sequence goes: a graph branch holds the S(0) branches and
        # junctions merged into it.
        held: dict[int, tuple[list[int], list[int]]] = {
            gb: ([db], []) for gb, db in branch_id.items()
        }
        graph = start.working_graph()
        for step, pick in enumerate(seq.removed, start=1):
            merged = graph.remove_end_branch(pick)
            own_b, own_j = held.pop(pick)
            for db in own_b:
                branches[db]["removed_at"] = step
            for nid in own_j:
                nodes[nid]["removed_at"] = step
            if merged is None:
                continue
            kept, absorbed, jid = merged
            nid = junction_id[jid]
            nodes[nid]["dissolved_at"] = step
            nodes[nid]["dissolved_into"] = branch_id[kept]
            held[kept][1].append(nid)
            if absorbed != kept:
                branches[branch_id[absorbed]]["absorbed_at"] = step
                branches[branch_id[absorbed]]["absorbed_into"] = branch_id[kept]
                more_b, more_j = held.pop(absorbed)
                held[kept][0].extend(more_b)
                held[kept][1].extend(more_j)
        idx = start.points()
        covered = reconstruction(start.shape.shape, start.rows[idx], start.cols[idx], start.r2[idx])
        miss_r, miss_c = np.nonzero(start.shape & ~covered)
        miss_r, miss_c = self.image_coordinates(miss_r, miss_c)
        gone = np.ones(start.rows.size, bool)
        gone[idx] = False
        gone_r, gone_c = self.image_coordinates(start.rows[gone], start.cols[gone])
        return {
            "start": "medial_axis" if not gone.any() else "coarse",
            "nodes": nodes,
            "branches": branches,
            "uncovered": [
                [float(x), float(y)] for y, x in zip(miss_r.tolist(), miss_c.tolist(), strict=True)
            ],
            "coarse_removed": [
                [float(x), float(y), float(r)]
                for y, x, r in zip(
                    gone_r.tolist(),
                    gone_c.tolist(),
                    np.sqrt(start.r2[gone].astype(float)).tolist(),
                    strict=True,
                )
            ],
        }

    def to_dict(
        self, curve: bool = True, frame: PixelFrame = IDENTITY, sequence: bool = False
    ) -> dict[str, Any]:
        nodes, branches = self.skeleton_table()

        def mapped(pts: list[list[float]]) -> list[list[float]]:
            return [[*frame.point(x, y), frame.distance(r)] for x, y, r in pts]

        def map_graph(nodes: list[dict[str, Any]], branches: list[dict[str, Any]]) -> None:
            for n in nodes:
                n["x"], n["y"] = frame.point(n["x"], n["y"])
                n["radius"] = frame.distance(n["radius"])
                n["points"] = mapped(n["points"])
            for b in branches:
                b["length"] = frame.distance(b["length"])
                b["points"] = mapped(b["points"])
                b["off_path"] = mapped(b["off_path"])

        map_graph(nodes, branches)
        ma = self.medial_axis
        seq = self.sequence
        doc: dict[str, Any] = {
            "area": self.area,
            "alpha": None if self.alpha is None else float(self.alpha),
            "rer": self.rer,
            "ss": self.ss,
            "objective": self.objective,
            "medial_axis": {
                "rer": float(self.ma_rer),
                "length": frame.distance(ma.length),
                "endpoints": ma.endpoints,
                "branches": ma.branches,
            },
            "skeleton": {
                "length": frame.distance(self.chosen_point()[0]),
                "nodes": nodes,
                "branches": branches,
                "endpoints": [n["id"] for n in nodes if n["kind"] == "endpoint"],
            },
            "chosen_step": self.chosen_step,
        }
        if curve:
            doc["curve"] = [
                {
                    "step": i,
                    "length": frame.distance(float(L)),
                    "ar": float(a),
                    "lr": float(lr),
                    "objective": float(o),
                }
                for i, (L, a, lr, o) in enumerate(
                    zip(seq.length, seq.ar, seq.lr, seq.objective, strict=True)
                )
            ]
            if self.trim is not None:  # the chosen point is the answer, tips cut
                L, a, lr, o = self.chosen_point()
                doc["curve"][self.chosen_step].update(
                    length=frame.distance(L), ar=a, lr=lr, objective=o
                )
        if sequence:
            table = self.sequence_table()
            map_graph(table["nodes"], table["branches"])
            table["uncovered"] = [list(frame.point(x, y)) for x, y in table["uncovered"]]
            table["coarse_removed"] = mapped(table["coarse_removed"])
            # how to get back to the raster's pixels (the error is painted on them)
            table["frame"] = {
                "x0": frame.x0,
                "y0": frame.y0,
                "pixel_size": frame.pixel_size,
                "flip_y": frame.flip_y,
            }
            doc["sequence"] = table
        return doc


def _graph_table(
    sk: Skeleton, margins: Margins | None
) -> tuple[list[dict[str, Any]], list[dict[str, Any]], dict[int, int], dict[int, int]]:
    """Nodes and branches of a skeleton's graph in image pixel coordinates, with the
    document id of each live graph branch and junction."""
    g, r2 = sk.graph, sk.r2
    rows, cols = sk.image_coordinates(g.rows, g.cols)
    xs = cols.astype(float).tolist()
    ys = rows.astype(float).tolist()
    rs = np.sqrt(r2.astype(float)).tolist()

    def xyr(p: int) -> list[float]:
        return [xs[p], ys[p], rs[p]]

    nodes: list[dict[str, Any]] = []
    junction_node: dict[int, int] = {}
    for j, junc in enumerate(g.junctions):
        if not junc.alive:
            continue
        pts = sorted(junc.points, key=lambda p: (-r2[p], g.rows[p], g.cols[p]))
        x, y, r = xyr(pts[0])
        junction_node[j] = len(nodes)
        nodes.append(
            {
                "id": len(nodes),
                "x": x,
                "y": y,
                "radius": r,
                "kind": "junction",
                "points": [xyr(p) for p in sorted(junc.points)],
            }
        )

    def new_node(p: int, kind: str) -> int:
        x, y, r = xyr(p)
        nodes.append({"id": len(nodes), "x": x, "y": y, "radius": r, "kind": kind, "points": []})
        return len(nodes) - 1

    branches: list[dict[str, Any]] = []
    branch_id: dict[int, int] = {}
    for b, br in enumerate(g.branches):
        if not br.alive:
            continue
        path = br.path()
        if br.loop:
            src = dst = new_node(path[0], "loop")
        else:
            ends = []
            for e, p in ((0, path[0]), (1, path[-1])):
                if br.node[e] is not None:
                    ends.append(junction_node[br.node[e]])
                elif e == 1 and len(path) == 1 and br.node[0] is None:
                    ends.append(ends[0])  # a single point: one node
                else:
                    ends.append(new_node(p, "endpoint"))
            src, dst = ends
        branches.append(
            {
                "id": len(branches),
                "source": src,
                "target": dst,
                "length": float(br.length),
                "points": [xyr(p) for p in path],
                "off_path": [xyr(p) for p in sorted(br.side)],
                "margin": None if margins is None else margins.margin.get(b),
                "removed_at": None if margins is None else margins.removed_at.get(b),
            }
        )
        branch_id[b] = len(branches) - 1
    return nodes, branches, branch_id, junction_node


def branch_line(skeleton: dict[str, Any], branch: dict[str, Any]) -> list[list[float]]:
    """A branch of a document as a polyline ``[x, y, radius]`` from its source node to
    its target node.

    The path's points, with the source node's position before them and the target
    node's after them where the path does not already end there, so that the lines of
    a skeleton meet exactly at its nodes. A loop's line is closed; a single-point
    branch gets two equal positions, as a LineString needs two.
    """
    nodes = skeleton["nodes"]
    line = [list(p) for p in branch["points"]]
    for end, nid in ((0, branch["source"]), (-1, branch["target"])):
        node = nodes[nid]
        if line[end][:2] != [node["x"], node["y"]] or (end == -1 and len(line) == 1):
            line.insert(len(line) if end == -1 else 0, [node["x"], node["y"], node["radius"]])
    return line


@dataclass
class PruneResult:
    """Result of :func:`skelprune.prune`: the components' answers, the input they came
    from and every option that shaped them, so that its outputs need no argument.

    Attributes
    ----------
    input : Input
        The mask, the frame back to the input's coordinates and what was taken as the
        shape (:func:`skelprune.io.read_input`).
    options : PruneOptions
        The pruning's options as applied (:meth:`PruneOptions.resolved`): what the
        document records.
    output : OutputOptions
        What :meth:`to_dict`, :meth:`to_geojson` and :meth:`overlay_png` hold when not
        told otherwise.
    components : list of ComponentResult
    """

    input: Input
    options: PruneOptions = field(default_factory=lambda: PruneOptions().resolved())
    output: OutputOptions = field(default_factory=OutputOptions)
    components: list[ComponentResult] = field(default_factory=list)

    @property
    def mask(self) -> np.ndarray:
        return self.input.mask

    @property
    def frame(self) -> PixelFrame:
        """The result's own frame: the polygon's coordinates, or the image's pixels."""
        return self.input.frame

    @property
    def foreground(self) -> Foreground:
        """What was taken as the shape (:mod:`skelprune.io.foreground`)."""
        return self.input.foreground

    @property
    def raster(self) -> PolygonRaster | None:
        """For polygon input: the polygon, its raster, its options and warnings."""
        return self.input.raster

    @property
    def warnings(self) -> list[dict[str, Any]]:
        """What the raster of a polygon does not hold as it is (empty for images)."""
        return self.input.warnings

    # the pruning's options, as the document names them
    @property
    def method(self) -> str:
        return self.options.method

    @property
    def beta(self) -> float:
        return self.options.beta

    @property
    def coarse(self) -> str | None:
        return self.options.coarse

    @property
    def choice(self) -> str:
        return self.options.choice

    @property
    def trim(self) -> bool:
        return self.options.trim

    @property
    def width(self) -> int:
        return int(self.mask.shape[1])

    def n_endpoints(self) -> int:
        """Endpoints of the pruned skeleton, all components together."""
        return sum(c.graph.n_endpoints() for c in self.components)

    @property
    def height(self) -> int:
        return int(self.mask.shape[0])

    def skeleton_points(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Rows, cols and squared radii of all pruned-skeleton points (image frame)."""
        parts = [c.points() for c in self.components]
        if not parts:
            e = np.zeros(0, np.int64)
            return e, e, e
        return tuple(np.concatenate(a) for a in zip(*parts, strict=True))  # type: ignore[return-value]

    def to_dict(
        self,
        curve: bool | None = None,
        overlay: bool | None = None,
        frame: PixelFrame | None = None,
        sequence: bool | None = None,
    ) -> dict[str, Any]:
        """The output document of docs/graph.md (plain JSON types).

        ``curve``, ``overlay`` and ``sequence`` None: as the result's
        :attr:`output` options say. ``frame`` None: the result's own frame (a polygon's
        coordinates, an image's pixels); :data:`~skelprune.io.frame.IDENTITY` for the
        raster's pixels. The document records every pruning option as applied; a
        polygon's also says how it was rasterised (``raster``, with the raster options)
        and what the raster does not hold as it is (``warnings``).

        Examples
        --------
        >>> import skelprune
        >>> m = np.zeros((20, 40), bool); m[5:15, 5:35] = True
        >>> doc = skelprune.prune(m).to_dict()
        >>> doc["width"], len(doc["components"][0]["skeleton"]["endpoints"])
        (40, 4)
        """
        frame = self.frame if frame is None else frame
        out = self.output
        curve = out.curve if curve is None else curve
        overlay = out.overlay if overlay is None else overlay
        sequence = out.sequence if sequence is None else sequence
        doc: dict[str, Any] = {
            "width": self.width,
            "height": self.height,
            **self._options_block(),
            "foreground": self.foreground.to_dict(),
            "components": [
                c.to_dict(curve=curve, frame=frame, sequence=sequence) for c in self.components
            ],
            "version": {"library": __version__, "algorithm": ALGORITHM_VERSION},
        }
        if self.raster is not None:
            doc["raster"] = self.raster.to_dict()
            doc["warnings"] = self.warnings
        if overlay:
            doc["overlay_png"] = base64.b64encode(self.overlay_png()).decode("ascii")
        return doc

    def _options_block(self) -> dict[str, Any]:
        """Every pruning option as applied, in the document's order."""
        o = self.options
        return {
            "method": o.method,
            "beta": float(o.beta),
            "coarse": o.coarse,
            "choice": o.choice,
            "trim": o.trim,
            "min_margin": o.min_margin,
            "dce_threshold": o.dce_threshold,
        }

    def to_geojson(
        self,
        frame: PixelFrame | None = None,
        simplify: float | None = None,
        cut_ends: bool | None = None,
    ) -> dict[str, Any]:
        """GeoJSON FeatureCollection for maps: branches as LineStrings, nodes as Points.

        ``frame`` as for :meth:`to_dict` (None: the result's own frame). Lines run from
        node to node, simplified within ``simplify`` pixels (0: every pixel of the path,
        as the document has it) without leaving the shape or crossing one another
        (:mod:`skelprune.output.lines`); for a polygon, their inner vertices first move to
        the medial point across the line (sub-pixel, from the exact polygon). ``cut_ends``
        ends a reach cut straight across at the middle of the cut instead of in a fork to
        its corners (both None: as the result's :attr:`output` options say). The
        document's points stay exact: only this map output changes.

        Every feature's properties carry its component's ``rer`` and ``ss``; the
        collection's ``properties`` (a foreign member) the document's options and the
        line options, each
        component's ``area``, ``alpha``, ``rer``, ``ss`` and ``objective``, and for a
        polygon the raster's ``warnings``.
        """
        # imported here: the map lines pull shapely, OpenCV and scipy.spatial, which
        # a prune() that never draws a map should not pay for at startup
        import shapely

        from .lines import boundary_index, cut_end_forks, map_lines, mask_distance, recentre

        frame = self.frame if frame is None else frame
        simplify = self.output.simplify if simplify is None else simplify
        cut_ends = self.output.cut_ends if cut_ends is None else cut_ends
        features: list[dict[str, Any]] = []
        doc = self.to_dict(curve=False, overlay=False, frame=IDENTITY, sequence=False)
        polygon = None
        if self.raster is not None and simplify > 0:
            f = self.raster.frame
            sign = -1.0 if f.flip_y else 1.0
            polygon = shapely.transform(
                self.raster.geometry,
                lambda xy: np.stack(
                    [(xy[:, 0] - f.x0) / f.pixel_size, sign * (xy[:, 1] - f.y0) / f.pixel_size],
                    axis=1,
                ),
            )
        index = None if polygon is None else boundary_index(polygon)
        distance = mask_distance(self.mask)
        summaries = []
        for ci, comp in enumerate(doc["components"]):
            sk = comp["skeleton"]
            nodes, branches = sk["nodes"], sk["branches"]
            # on every feature too: GIS tools show a feature's properties, not the collection's
            numbers = {"rer": comp["rer"], "ss": comp["ss"]}
            summaries.append(
                {
                    "component": ci,
                    "area": comp["area"],
                    "alpha": comp["alpha"],
                    **numbers,
                    "objective": comp["objective"],
                }
            )
            lines: list[Any] = [np.asarray(branch_line(sk, br), float) for br in branches]
            ends_at: dict[tuple[int, str], int] = {}
            moved: dict[int, tuple[float, float]] = {}
            if cut_ends:
                lines, ends_at, moved = cut_end_forks(nodes, branches, lines, self.mask, distance)
            kept = [i for i, ln in enumerate(lines) if ln is not None]
            exact = [lines[i] for i in kept]
            # the exact polygon gives sub-pixel medial positions
            chosen = exact if index is None else recentre(exact, index)
            simple = map_lines(chosen, simplify, self.mask, polygon, exact)
            used: set[int] = set()
            for i, line in zip(kept, simple, strict=True):
                br = branches[i]
                src = ends_at.get((i, "source"), br["source"])
                dst = ends_at.get((i, "target"), br["target"])
                used.update((src, dst))
                features.append(
                    {
                        "type": "Feature",
                        "geometry": {
                            "type": "LineString",
                            "coordinates": [list(frame.point(x, y)) for x, y, _ in line.tolist()],
                        },
                        "properties": {
                            "component": ci,
                            "kind": "branch",
                            "id": br["id"],
                            "source": src,
                            "target": dst,
                            "length": frame.distance(br["length"]),
                            "radii": [frame.distance(r) for r in line[:, 2].tolist()],
                            "margin": br["margin"],
                            "removed_at": br["removed_at"],
                            **numbers,
                        },
                    }
                )
            for nd in nodes:
                if cut_ends and nd["id"] not in used:
                    continue  # a fork's junction and second tip, gone with the fork
                x, y = moved.get(nd["id"], (nd["x"], nd["y"]))
                features.append(
                    {
                        "type": "Feature",
                        "geometry": {"type": "Point", "coordinates": list(frame.point(x, y))},
                        "properties": {
                            "component": ci,
                            "kind": nd["kind"],
                            "id": nd["id"],
                            "radius": 0.0 if nd["id"] in moved else frame.distance(nd["radius"]),
                            **numbers,
                        },
                    }
                )
        # A foreign member of the collection (RFC 7946 §6.1): the document's numbers.
        properties: dict[str, Any] = {
            "width": doc["width"],
            "height": doc["height"],
            **self._options_block(),
            "simplify": simplify,
            "cut_ends": cut_ends,
        }
        properties["components"] = summaries
        if self.raster is not None:
            properties["warnings"] = self.warnings
        return {"type": "FeatureCollection", "properties": properties, "features": features}

    def to_networkx(self, frame: PixelFrame | None = None) -> Any:
        """The skeleton as a ``networkx.MultiGraph`` (needs the optional ``networkx``).

        Nodes are ``(component, node id)`` with the document's node fields (``x``, ``y``,
        ``radius``, ``kind``, ``points``) as attributes; each branch is an edge, keyed by
        its id, with ``length``, ``points`` (its path from ``source`` to ``target``),
        ``off_path`` and ``line`` (:func:`branch_line`). A loop is a self-loop edge.

        Examples
        --------
        >>> import skelprune
        >>> m = np.zeros((20, 40), bool); m[5:15, 5:35] = True
        >>> g = skelprune.prune(m).to_networkx()
        >>> g.number_of_nodes(), g.number_of_edges(), sorted(d for _, d in g.degree())
        (6, 5, [1, 1, 1, 1, 3, 3])
        """
        try:
            import networkx as nx
        except ImportError:  # an optional dependency: say how to get it
            raise ImportError(
                "to_networkx needs networkx: pip install 'skelprune[graph]'"
            ) from None
        g = nx.MultiGraph()
        for ci, comp in enumerate(
            self.to_dict(curve=False, overlay=False, frame=frame, sequence=False)["components"]
        ):
            sk = comp["skeleton"]
            for nd in sk["nodes"]:
                g.add_node(
                    (ci, nd["id"]), component=ci, **{k: v for k, v in nd.items() if k != "id"}
                )
            for br in sk["branches"]:
                g.add_edge(
                    (ci, br["source"]),
                    (ci, br["target"]),
                    key=br["id"],
                    component=ci,
                    length=br["length"],
                    points=br["points"],
                    off_path=br["off_path"],
                    line=branch_line(sk, br),
                )
        return g

    def render_overlay(self, scale: int = 1, legend: bool = False) -> np.ndarray:
        """RGB overlay (:func:`~skelprune.output.render.render_overlay`), ``scale`` times
        the mask's size; ``legend`` adds a strip with the colour key, RER and SS.

        Examples
        --------
        >>> import skelprune
        >>> m = np.zeros((20, 40), bool); m[5:15, 5:35] = True
        >>> skelprune.prune(m).render_overlay().shape
        (20, 40, 3)
        """
        rows, cols, r2 = self.skeleton_points()
        marks: dict[str, list[tuple[int, int]]] = {"endpoint": [], "junction": []}
        for comp in self.components:
            for n in comp.skeleton_table()[0]:
                if n["kind"] in marks:
                    marks[n["kind"]].append((int(n["y"]), int(n["x"])))
        text = None
        if legend:
            text = "   ".join(
                (f"component {i}: " if len(self.components) > 1 else "")
                + f"RER {100 * c.rer:.2f} %, SS {c.ss:.3f}"
                for i, c in enumerate(self.components[:4])
            )
        return render_overlay(
            self.mask,
            rows,
            cols,
            r2,
            np.array(marks["endpoint"], int).reshape(-1, 2),
            np.array(marks["junction"], int).reshape(-1, 2),
            scale=scale,
            legend=text,
        )

    def overlay_png(self, scale: int | None = None, legend: bool | None = None) -> bytes:
        """The overlay as PNG bytes; ``scale`` and ``legend`` None: as the result's
        :attr:`output` options say (``overlay_scale`` None: the smallest integer scale that
        makes the longer side at least 512 px, :func:`~skelprune.output.render.auto_scale`).
        """
        scale = self.output.overlay_scale if scale is None else scale
        legend = self.output.overlay_legend if legend is None else legend
        return encode_png(
            self.render_overlay(auto_scale(self.mask.shape) if scale is None else scale, legend)
        )
