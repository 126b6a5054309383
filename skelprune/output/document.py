"""The result of pruning one input and its serialisation (docs/graph.md).

:class:`PruneResult` holds the components' answers (:mod:`.component`), the input they
came from and the options that shaped them; ``to_dict``, ``to_geojson``, ``to_networkx``,
the tables and the overlay are views of the components' branch tables, producing plain
JSON types (:mod:`skelprune.output.schema`).
"""

from __future__ import annotations

import base64
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from .._version import ALGORITHM_VERSION, __version__
from ..errors import InvalidOptionError
from ..io.foreground import Foreground
from ..io.frame import PixelFrame
from ..options import OutputOptions, PruneOptions

if TYPE_CHECKING:
    from ..io.input import Input
    from ..io.polygon import PolygonRaster
from .component import ComponentResult
from .finite import finite_tree
from .render import auto_scale, encode_png, result_overlay
from .views import to_networkx

__all__ = ["PruneResult"]


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
        >>> m = np.zeros((80, 180), bool); m[10:70, 10:170] = True
        >>> doc = skelprune.prune(m).to_dict()
        >>> doc["width"], len(doc["components"][0]["skeleton"]["endpoints"])
        (180, 4)
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
        if self.input.georeference is not None:
            doc["georeference"] = self.input.georeference.to_dict()
        if self.input.hint is not None:
            doc["hint"] = self.input.hint
        if overlay:
            doc["overlay_png"] = base64.b64encode(self.overlay_png()).decode("ascii")
        return finite_tree(doc)

    def _options_block(self) -> dict[str, Any]:
        """Every pruning option as applied, in the document's order."""
        o = self.options
        block: dict[str, Any] = {
            "method": o.method,
            "beta": float(o.beta),
            "coarse": o.coarse,
            "choice": o.choice,
            "trim": o.trim,
            "min_margin": o.min_margin,
            "dce_threshold": o.dce_threshold,
        }
        if o.scope != "global":  # the paper's scope goes unsaid, as documents always had it
            block["scope"] = o.scope
            block["window"] = o.window
        return block

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
        document's points stay exact: only this map output changes. The map lines
        (output option ``lines="map"``) are :func:`skelprune.geo.centerlines`'s, from
        the polygon: refused here.

        Every feature's properties carry its component's ``rer`` and ``ss``; the
        collection's ``properties`` (a foreign member) the document's options and the
        line options, each
        component's ``area``, ``alpha``, ``rer``, ``ss`` and ``objective``, and for a
        polygon the raster's ``warnings``.
        """
        if self.output.lines != "branches":
            raise InvalidOptionError(
                f"lines={self.output.lines!r}: the map lines prune each polygon Feature on "
                "its own, from the polygon: skelprune.geo.centerlines(frame) or "
                "skelprune.geo.geojson_lines(geojson) (docs/gis.md); a result's "
                "to_geojson() gives its branches"
            )
        # imported here: the map lines pull shapely, OpenCV and scipy.spatial, which
        # a prune() that never draws a map should not pay for at startup
        from .geojson import skeleton_geojson

        simplify = self.output.simplify if simplify is None else simplify
        cut_ends = self.output.cut_ends if cut_ends is None else cut_ends
        summaries: list[Any] = [
            {
                "component": ci,
                "area": c.area,
                "alpha": None if c.alpha is None else float(c.alpha),
                "rer": c.rer,
                "ss": c.ss,
                "objective": c.objective,
            }
            for ci, c in enumerate(self.components)
        ]
        # A foreign member of the collection (RFC 7946 §6.1): the document's numbers.
        header = {
            "width": self.width,
            "height": self.height,
            **self._options_block(),
            "simplify": simplify,
            "cut_ends": cut_ends,
        }
        collection = skeleton_geojson(
            [c.table for c in self.components],
            summaries,
            self.mask,
            header,
            self.frame if frame is None else frame,
            simplify,
            cut_ends,
            self.raster,
            crs=self.input.crs,
        )
        from .summary import geojson_numbers

        return finite_tree(
            geojson_numbers(
                self, cast(dict[str, Any], collection), self.frame if frame is None else frame
            )
        )

    def to_networkx(self, frame: PixelFrame | None = None) -> Any:
        """The skeleton as a ``networkx.MultiGraph`` (needs the optional ``networkx``).

        Nodes are ``(component, node id)`` with the document's node fields (``x``, ``y``,
        ``radius``, ``kind``, ``points``) as attributes; each branch is an edge, keyed by
        its id, with ``length``, ``points`` (its path from ``source`` to ``target``),
        ``off_path`` and ``line`` (:meth:`~.table.BranchTable.lines`). A loop is a self-loop edge.

        Examples
        --------
        >>> import skelprune
        >>> m = np.zeros((80, 180), bool); m[10:70, 10:170] = True
        >>> g = skelprune.prune(m).to_networkx()
        >>> g.number_of_nodes(), g.number_of_edges(), sorted(d for _, d in g.degree())
        (6, 5, [1, 1, 1, 1, 3, 3])
        """
        frame = self.frame if frame is None else frame
        labels = [c.label for c in self.components]
        return to_networkx([c.table.framed(frame) for c in self.components], labels)

    def summary(self, level: str | None = None) -> Any:
        """The table people measure (docs/tables.md): one row per branch (``level=
        "branch"``) or per component (``"component"``; None: as the result's output
        option ``table`` says), in the result's unit (pixels, the polygon's units or a
        given ``pixel_size``; the ``unit`` column says which). A
        pandas DataFrame when pandas is installed, else a list of row dicts.

        Examples
        --------
        >>> import skelprune
        >>> m = np.zeros((40, 60), bool); m[5:35, 5:55] = True
        >>> rows = skelprune.prune(m).summary("component")
        >>> int(rows["branches"][0]), int(rows["ends"][0]), rows["unit"][0]
        (5, 4, 'px')
        """
        from .summary import table

        return table(self, self.output.table if level is None else level)

    def to_csv(self, level: str | None = None) -> str:
        """:meth:`summary` as CSV text (empty cells for null; no pandas needed)."""
        from .summary import table_csv

        return table_csv(self, self.output.table if level is None else level)

    def to_graphml(self) -> str:
        """The skeleton as GraphML text: nodes with their position, radius, kind and
        label; one edge per branch with the branch table's numbers."""
        from .summary import graphml

        return graphml(self)

    def skeleton_mask(self) -> np.ndarray:
        """The pruned skeleton as an image of the input's size: boolean, or the labels
        on the skeleton's pixels for a label image. ``skan.Skeleton(result.skeleton_mask())``
        hands it to skan."""
        from .summary import skeleton_mask

        return skeleton_mask(self)

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
        return result_overlay(self, scale, legend)

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
