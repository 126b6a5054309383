"""The answer for a volume: the document with ``z``, the branch table, networkx, SWC and
the overlay of the three maximum-intensity projections (docs/volumes.md, "Outputs").

Each component's answer is read once into a :class:`~skelprune.output.table.BranchTable`
with a ``z`` column (:func:`~skelprune.output.table.volume_table`), the table an image's
answer is read into; the document's nodes and branches, the CSV rows, the networkx graph,
SWC and the overlay's end marks are views of it. Points are ``[x, y, z, radius]``: ``x``
the array's last axis, ``z`` its first, as voxel indices of the whole volume; radii,
lengths and widths are physical (``spacing``), volumes counted in voxels.
"""

from __future__ import annotations

import io
import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, NoReturn

import numpy as np

from ..errors import InvalidOptionError
from ..grid3d.skeleton import VolumeSkeleton
from ..grid3d.tips import VolumeTrim
from ..io.frame import PixelFrame
from ..options import OutputOptions, PruneOptions
from ..options_where import missing_answer
from ..pruning.bayesian import PruningSequence, target
from ..pruning.margin import Margins
from .finite import finite, finite_number, finite_tree, rows_csv, rows_frame
from .table import ENDPOINT, BranchTable, volume_table
from .views import branch_dicts, node_dicts

__all__ = ["VolumeComponent", "VolumeResult"]


def auto_volume_scale(shape: tuple[int, ...]) -> int:
    """The overlay's default scale: the volume's longer side drawn at least 512 px
    (1 to 16)."""
    return max(1, min(16, -(-512 // max(shape))))


#: The columns of a volume's branch table, in order.
VOLUME_BRANCH_COLUMNS = (
    "component",
    "label",
    "branch",
    "kind",
    "length",
    "voxels",
    "mean_width",
    "min_width",
    "max_width",
    "x0",
    "y0",
    "z0",
    "x1",
    "y1",
    "z1",
    "margin",
    "removed_at",
)


@dataclass
class VolumeComponent:
    """One component's curve skeleton (``axis``), its sequence and the answer."""

    axis: VolumeSkeleton
    skeleton: VolumeSkeleton
    sequence: PruningSequence[VolumeSkeleton]
    chosen_step: int
    margins: Margins
    trim: VolumeTrim | None = None
    label: int | None = None

    @property
    def volume(self) -> int:
        """Voxels of the component."""
        return self.axis.area

    @property
    def rer(self) -> float:
        """Share of the component's voxels the answer's balls miss."""
        return self.lost / self.volume

    @property
    def lost(self) -> int:
        """Voxels of the component the answer's balls miss."""
        return self.sequence.lost[self.chosen_step] if self.trim is None else self.trim.lost

    @property
    def objective(self) -> float:
        """``λ`` of the answer (its tips cut, if they were)."""
        seq = self.sequence
        if self.trim is None or seq.alpha is None:
            return float(seq.objective[self.chosen_step])
        return target(self.lost, seq.area, self.skeleton.length, seq.alpha, seq.lbar)

    @cached_property
    def table(self) -> BranchTable:
        """The answer's nodes and branches as flat arrays with a ``z`` column
        (:func:`~skelprune.output.table.volume_table`): what every output reads."""
        return volume_table(self.skeleton, self.margins)

    def graph_doc(self) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
        """The answer's nodes (junction clusters and free ends) and branches, as the
        document lists them (branch ids: the graph's own)."""
        nodes: list[Any] = node_dicts(self.table)
        branches: list[Any] = branch_dicts(self.table, graph_ids=True)
        return nodes, branches

    def to_dict(self) -> dict[str, Any]:
        seq = self.sequence
        nodes, branches = self.graph_doc()
        ss = float(seq.ss[self.chosen_step])
        if self.trim is not None and seq.lbar > 0:
            ss = math.log(self.skeleton.length / seq.lbar + 1.0)
        return {
            "label": self.label,
            "volume": self.volume,
            "alpha": seq.alpha,
            "lbar": seq.lbar,
            "rer": self.rer,
            "ss": ss,
            "objective": self.objective,
            "chosen_step": self.chosen_step,
            "steps": len(seq.removed),
            "tips_trimmed": self.trim is not None,
            "medial_axis": {
                "rer": seq.lost[0] / self.volume,
                "length": self.axis.length,
                "endpoints": self.axis.n_endpoints,
                "branches": sum(1 for br in self.axis.graph.branches if br.alive),
            },
            "skeleton": {
                "length": self.skeleton.length,
                # as in an image's document: the ids of the end nodes
                "endpoints": [n["id"] for n in nodes if n["kind"] == "endpoint"],
                "nodes": nodes,
                "branches": branches,
            },
        }


@dataclass
class VolumeResult:
    """What :func:`skelprune.prune` answers for a volume.

    Examples
    --------
    >>> import skelprune
    >>> v = np.zeros((12, 14, 40), bool); v[3:9, 4:10, 3:37] = True
    >>> res = skelprune.prune(v, spacing=(2.0, 1.0, 1.0))
    >>> doc = res.to_dict()
    >>> doc["spacing"], len(doc["components"]), doc["components"][0]["skeleton"]["endpoints"]
    ([2.0, 1.0, 1.0], 1, [0, 1])
    >>> res.to_swc().splitlines()[1].split()[1:]   # the root: type, x, y, z, radius, parent
    ['0', '5', '7', '14', '3', '-1']
    """

    shape: tuple[int, int, int]
    spacing: tuple[float, float, float]
    options: PruneOptions
    output: OutputOptions
    volume: np.ndarray
    components: list[VolumeComponent] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """The document: the volume's shape and spacing, the options, and per component
        its numbers, nodes and branches (points ``[x, y, z, radius]``)."""
        opts = self.options
        doc: dict[str, Any] = {
            "dimensions": 3,
            "width": self.shape[2],
            "height": self.shape[1],
            "depth": self.shape[0],
            "spacing": list(self.spacing),
            "method": opts.method,
            "beta": opts.beta,
            "coarse": None,
            "choice": opts.choice,
            "trim": opts.trim,
            "min_margin": opts.min_margin,
            "components": [c.to_dict() for c in self.components],
        }
        return finite_tree(doc)

    def summary(self) -> Any:
        """The branch table: one row per branch of the answer, its length, its width
        (twice the ball radius: mean, least, largest) and its two ends, all in the units
        of ``spacing``; a pandas ``DataFrame`` when pandas is installed, else a list of
        row dicts (as an image's :meth:`~skelprune.output.document.PruneResult.summary`)."""
        return rows_frame(self._branch_rows(), VOLUME_BRANCH_COLUMNS)

    def _branch_rows(self) -> list[dict[str, Any]]:
        dz, dy, dx = self.spacing
        rows = []
        for i, comp in enumerate(self.components):
            t = comp.table
            ends = t.node_kind == ENDPOINT
            off = np.diff(t.off_offsets).tolist()
            margins, steps = t.margins(), t.removal_steps()
            for j, (b, src, dst) in enumerate(
                zip(t.graph_branch.tolist(), t.source.tolist(), t.target.tolist(), strict=True)
            ):
                pts = t.path(j)
                kind = "loop" if src < 0 else "end" if ends[src] or ends[dst] else "inner"
                rows.append(
                    {
                        "component": i,
                        "label": comp.label,
                        "branch": b,
                        "kind": kind,
                        "length": float(t.length[j]),
                        "voxels": len(pts) + off[j],
                        "mean_width": float(2 * pts[:, 3].mean()),
                        "min_width": float(2 * pts[:, 3].min()),
                        "max_width": float(2 * pts[:, 3].max()),
                        "x0": pts[0, 0] * dx,
                        "y0": pts[0, 1] * dy,
                        "z0": pts[0, 2] * dz,
                        "x1": pts[-1, 0] * dx,
                        "y1": pts[-1, 1] * dy,
                        "z1": pts[-1, 2] * dz,
                        "margin": margins[j],
                        "removed_at": steps[j],
                    }
                )
        return [{k: finite(v) for k, v in row.items()} for row in rows]

    @property
    def warnings(self) -> list[dict[str, Any]]:
        """None for a volume (the image result's warnings come from rasterising)."""
        return []

    def to_csv(self) -> str:
        """:meth:`summary` as CSV text (a header row; empty cells for null), with or
        without pandas."""
        return rows_csv(self._branch_rows(), VOLUME_BRANCH_COLUMNS)

    def to_networkx(self) -> Any:
        """The skeleton as a ``networkx.MultiGraph``: nodes ``(component, node id)`` with
        the document's node fields, one edge per branch keyed by its id (a loop: a
        self-loop on a node of its own)."""
        import networkx as nx

        g = nx.MultiGraph()
        for i, comp in enumerate(self.components):
            nodes, branches = comp.graph_doc()
            for node in nodes:
                g.add_node((i, node["id"]), **{k: v for k, v in node.items() if k != "id"})
            for br in branches:
                a, b = br["source"], br["target"]
                if a is None:  # a loop without junction: a node at its first voxel
                    x, y, z, radius = br["points"][0]
                    a = b = f"loop{br['id']}"
                    g.add_node((i, a), x=x, y=y, z=z, radius=radius, kind="loop", points=[])
                attrs = {k: v for k, v in br.items() if k not in ("id", "source", "target")}
                g.add_edge((i, a), (i, b), key=br["id"], **attrs)
        return g

    def to_swc(self) -> str:
        """The skeleton in the SWC format of neuron tools: one line per skeleton voxel,
        ``id type x y z radius parent`` in the units of ``spacing``, type 0 (undefined),
        each component a tree rooted at its voxel of largest radius. SWC holds trees
        only: of a cycle, one step is left out."""
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import breadth_first_order

        dz, dy, dx = self.spacing
        lines = ["# skelprune curve skeleton; units of spacing " + " ".join(map(str, self.spacing))]
        next_id = 1
        for comp in self.components:
            s, t = comp.skeleton, comp.table
            pts = t.pixels()
            cx, cy, cz = t.columns()
            local = np.full(s.z.size, -1, np.int64)
            local[pts] = np.arange(pts.size)
            nbr = s.graph.nbr[pts]
            rows, slots = np.nonzero(nbr >= 0)
            keep = local[nbr[rows, slots]] >= 0
            rows, cols = rows[keep], local[nbr[rows, slots][keep]]
            adj = coo_matrix((np.ones(rows.size), (rows, cols)), shape=(pts.size, pts.size))
            seen = np.zeros(pts.size, bool)
            # roots by decreasing radius (ties: raster order), one per connected piece
            for root in np.lexsort((pts, -s.r2[pts])).tolist():
                if seen[root]:
                    continue
                order, parent = breadth_first_order(adj.tocsr(), root, directed=False)
                ids = {}
                for q in order.tolist():
                    seen[q] = True
                    ids[q] = next_id
                    next_id += 1
                    p = pts[q]
                    up = -1 if parent[q] < 0 else ids[int(parent[q])]
                    # SWC has no null: every number is finite (finite_number)
                    x, y, z = cx[p] * dx, cy[p] * dy, cz[p] * dz
                    numbers = " ".join(map(finite_number, (x, y, z, t.radius[p])))
                    lines.append(f"{ids[q]} 0 {numbers} {up}")
        return "\n".join(lines) + "\n"

    def to_geojson(
        self,
        frame: PixelFrame | None = None,
        simplify: float | None = None,
        cut_ends: bool | None = None,
    ) -> NoReturn:
        """Refused, whatever the arguments (those of an image's
        :meth:`~skelprune.output.document.PruneResult.to_geojson`): GeoJSON holds map
        geometry, and a volume's points are voxel indices in three dimensions, not map
        coordinates. Its answers are the JSON document (:meth:`to_dict`), the overlay
        (:meth:`overlay_png`), the CSV table (:meth:`to_csv`) and SWC (:meth:`to_swc`),
        as :func:`skelprune.encode` says.

        Raises
        ------
        InvalidOptionError
            Always, in the words of :func:`skelprune.encode`'s refusal.
        """
        raise InvalidOptionError(missing_answer("a volume", "volume", "geojson"))

    def render_overlay(self, scale: int = 1) -> np.ndarray:
        """RGB image of the three maximum-intensity projections (along ``z`` top left,
        along ``y`` below it, along ``x`` to its right, as orthogonal views are laid out),
        the volume grey, the curve skeleton's removed voxels orange, the answer red and
        its end points blue (three voxels a side); voxels stretched to their physical
        proportions."""
        from scipy.ndimage import binary_dilation

        dz, dy, dx = self.spacing
        unit = min(self.spacing)
        fz, fy, fx = (max(1, round(d / unit)) * scale for d in (dz, dy, dx))
        axis_m = np.zeros(self.shape, bool)
        kept = np.zeros(self.shape, bool)
        ends = np.zeros(self.shape, bool)
        for comp in self.components:
            for sk, drawn in ((comp.axis, axis_m), (comp.skeleton, kept)):
                idx = sk.points()
                oz, oy, ox = sk.origin
                drawn[sk.z[idx] + oz, sk.y[idx] + oy, sk.x[idx] + ox] = True
            t = comp.table
            at = t.node_point[t.node_kind == ENDPOINT]
            ends[tuple(c[at].astype(np.int64) for c in t.columns()[::-1])] = True

        def view(axis: int, f0: int, f1: int, turn: bool = False) -> np.ndarray:
            def mip(a: np.ndarray) -> np.ndarray:
                m = a.max(axis=axis)
                return m.T if turn else m

            img = np.full((*mip(self.volume).shape, 3), 255, np.uint8)
            img[mip(self.volume)] = (205, 205, 205)
            img[mip(axis_m)] = (245, 160, 60)
            img[mip(kept)] = (210, 20, 20)
            img = np.repeat(np.repeat(img, f0, axis=0), f1, axis=1)
            # end points as blocks of three voxels a side, to be seen at any scale
            big = np.repeat(np.repeat(binary_dilation(mip(ends), np.ones((3, 3))), f0, 0), f1, 1)
            img[big] = (20, 60, 220)
            return img

        top = view(0, fy, fx)  # rows y, columns x
        front = view(1, fz, fx)  # rows z, columns x
        side = view(2, fy, fz, turn=True)  # rows y, columns z
        gap = 4 * scale
        h = top.shape[0] + gap + front.shape[0]
        w = top.shape[1] + gap + side.shape[1]
        out = np.full((h, w, 3), 255, np.uint8)
        out[: top.shape[0], : top.shape[1]] = top
        out[top.shape[0] + gap :, : front.shape[1]] = front
        out[: side.shape[0], top.shape[1] + gap :] = side
        return out

    def overlay_png(self, scale: int | None = None) -> bytes:
        """:meth:`render_overlay` as PNG bytes (``scale``: the output options' or one
        that makes the longer side at least 512 px)."""
        from PIL import Image

        if scale is None:
            scale = self.output.overlay_scale or auto_volume_scale(self.shape)
        buf = io.BytesIO()
        Image.fromarray(self.render_overlay(scale)).save(buf, format="PNG")
        return buf.getvalue()
