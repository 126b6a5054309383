"""Skeleton matching by path similarity (Bai & Latecki, TPAMI 30(7), 2008; the paper's [16]).

A skeleton is described by the shortest skeleton paths between every pair of its
endpoints, each sampled at :data:`SAMPLES` equidistant points with the radius of the
maximal disk there (:class:`SkeletonDescriptor`, computed once per skeleton). Two paths
differ by their radius sequences and relative lengths (:func:`path_distance`); two
endpoints by the best order-preserving correspondence of the paths leaving them (optimal
subsequence bijection, OSB); two skeletons by the optimal assignment of their endpoints
(:func:`match`). ``docs/matching.md`` states every choice where [16] leaves room.

>>> import numpy as np, skelprune
>>> m = np.zeros((80, 180), bool); m[10:70, 10:170] = True
>>> res = skelprune.match(m, m)
>>> res.distance, len(res.pairs)
(0.0, 4)
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import cv2
import numpy as np
from numba import njit
from scipy.optimize import linear_sum_assignment
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from .api import prune
from .errors import InvalidImageError, SkelpruneError
from .io.frame import IDENTITY, PixelFrame
from .output.document import PruneResult
from .output.table import ENDPOINT, BranchTable

__all__ = [
    "LENGTH_WEIGHT",
    "MAX_ENDPOINTS",
    "SAMPLES",
    "Match",
    "SkeletonDescriptor",
    "UnmatchableShapeError",
    "describe",
    "describe_table",
    "distance_matrix",
    "match",
    "path_distance",
]

#: Sample points per path, ``M`` of [16].
SAMPLES = 50
#: Weight of the length term of the path distance, ``α`` of [16].
LENGTH_WEIGHT = 40.0
#: Most endpoints a matched skeleton may have: the time of a match grows as ``K³N³``
#: with the endpoint counts (22 and 22: about 0.13 s; 40 and 40: several seconds).
MAX_ENDPOINTS = 40


class UnmatchableShapeError(SkelpruneError):
    """The skeleton has fewer than two endpoints (so no endpoint-to-endpoint path), or
    more than :data:`MAX_ENDPOINTS`."""

    kind = "unmatchable-shape"


@dataclass(frozen=True)
class SkeletonDescriptor:
    """The path table of one skeleton, computed once and reused for every comparison.

    Attributes
    ----------
    node_ids : (K,) int64
        Document node ids (``to_dict()["components"][component]["skeleton"]["nodes"]``)
        of the endpoints, in their order along the shape's outer boundary.
    positions : (K, 2) float64
        ``x, y`` of the endpoints, in the input image's pixel frame.
    radii : (K, K, SAMPLES) float64
        ``radii[i, j]``: radii at the equidistant sample points of the shortest skeleton
        path from endpoint ``i`` to endpoint ``j``, over the skeleton's mean radius.
    lengths : (K, K) float64
        Path lengths over the skeleton's total length.
    component : int
        The component described (the largest one).
    frame : PixelFrame
        From the pixel frame to the input's coordinates (a polygon's own units).
    """

    node_ids: np.ndarray
    positions: np.ndarray
    radii: np.ndarray
    lengths: np.ndarray
    component: int = 0
    frame: PixelFrame = IDENTITY

    @property
    def n_endpoints(self) -> int:
        return int(self.node_ids.size)


@dataclass(frozen=True)
class Match:
    """Result of :func:`match`.

    Attributes
    ----------
    distance : float
        Skeleton dissimilarity (0 for the same skeleton; symmetric).
    pairs : list of (int, int)
        Corresponding endpoints as indices into ``a.node_ids`` and ``b.node_ids``.
    mirrored : bool
        Whether the correspondence runs along ``b``'s boundary in the opposite sense (a
        mirror image matches that way).
    a, b : SkeletonDescriptor
    """

    distance: float
    pairs: list[tuple[int, int]]
    mirrored: bool
    a: SkeletonDescriptor
    b: SkeletonDescriptor

    def to_dict(
        self, frame_a: PixelFrame | None = None, frame_b: PixelFrame | None = None
    ) -> dict[str, Any]:
        """Plain JSON types: the distance and, per pair, both endpoints' node ids and
        positions (mapped by each shape's frame, None: its own, so that polygon input
        gets its own units)."""
        frame_a = self.a.frame if frame_a is None else frame_a
        frame_b = self.b.frame if frame_b is None else frame_b

        def end(d: SkeletonDescriptor, k: int, frame: PixelFrame) -> dict[str, Any]:
            x, y = frame.point(float(d.positions[k, 0]), float(d.positions[k, 1]))
            return {"component": d.component, "node": int(d.node_ids[k]), "x": x, "y": y}

        return {
            "distance": float(self.distance),
            "mirrored": self.mirrored,
            "endpoints": [self.a.n_endpoints, self.b.n_endpoints],
            "correspondence": [
                {"a": end(self.a, i, frame_a), "b": end(self.b, j, frame_b)} for i, j in self.pairs
            ],
        }


# -- describing a skeleton ------------------------------------------------------------


def _boundary_order(mask: np.ndarray, origin: tuple[int, int], positions: np.ndarray) -> np.ndarray:
    """Order of endpoints along the outer boundary of the mask's largest shape (each
    endpoint placed at its nearest boundary pixel; ties by position). ``mask[0, 0]`` is
    the image's pixel ``origin`` (row, column); ``positions`` are image ``x, y``."""
    contours, _ = cv2.findContours(
        np.ascontiguousarray(mask, np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE
    )
    ring = max(contours, key=len)[:, 0, :].astype(float)  # (n, 2) x, y
    ring += (origin[1], origin[0])
    d2 = ((positions[:, None, :] - ring[None, :, :]) ** 2).sum(-1)
    at = d2.argmin(1)
    return np.lexsort((positions[:, 1], positions[:, 0], at))


def _sample(line: np.ndarray, samples: int) -> tuple[np.ndarray, float]:
    """Radii at ``samples`` equidistant points along a polyline ``[x, y, r]``, and its
    length (linear interpolation of the radius between the polyline's points)."""
    step = np.hypot(np.diff(line[:, 0]), np.diff(line[:, 1]))
    s = np.concatenate([[0.0], np.cumsum(step)])
    length = float(s[-1])
    return np.interp(np.linspace(0.0, length, samples), s, line[:, 2]), length


def describe_table(
    table: BranchTable,
    length: float,
    mask: np.ndarray,
    origin: tuple[int, int] = (0, 0),
    component: int = 0,
    samples: int = SAMPLES,
) -> SkeletonDescriptor:
    """The path table of a skeleton's branch table (in image pixel coordinates), whose
    total length is ``length``, and of the shape it came from: ``mask``, whose pixel
    ``[0, 0]`` is the image's pixel ``origin`` (row, column).

    Raises
    ------
    UnmatchableShapeError
        When the skeleton has fewer than two endpoints or more than :data:`MAX_ENDPOINTS`.
    """
    ends = np.flatnonzero(table.node_kind == ENDPOINT).tolist()
    if len(ends) < 2:
        raise UnmatchableShapeError(
            f"the skeleton has {len(ends)} endpoint{'s' * (len(ends) != 1)}: path "
            "similarity matching needs at least two (a shape whose skeleton is a single "
            "point or only cycles cannot be matched this way)"
        )
    if len(ends) > MAX_ENDPOINTS:
        raise UnmatchableShapeError(
            f"the skeleton has {len(ends)} endpoints, more than the {MAX_ENDPOINTS} path "
            "similarity matching takes (its time grows as the sixth power of the endpoint "
            "count); prune with the default options or with min_margin"
        )
    # the node graph: one edge per branch (the shortest of parallel ones), no loops
    best: dict[tuple[int, int], tuple[float, np.ndarray]] = {}
    lines = table.lines()
    for u, v, line in zip(table.source.tolist(), table.target.tolist(), lines, strict=True):
        if u == v:
            continue
        _r, along = _sample(line, 2)
        key = (min(u, v), max(u, v))
        if key not in best or along < best[key][0]:
            best[key] = (along, line if u < v else line[::-1])
    n = table.n_nodes
    keys = list(best)
    w = np.array([best[k][0] for k in keys] + [best[k][0] for k in keys])
    # an edge of length 0 would vanish from a sparse matrix
    w = np.maximum(w, 1e-9)
    iu = [k[0] for k in keys] + [k[1] for k in keys]
    iv = [k[1] for k in keys] + [k[0] for k in keys]
    graph = coo_matrix((w, (iu, iv)), shape=(n, n)).tocsr()
    dist, pred = dijkstra(graph, indices=ends, return_predecessors=True)

    at = table.node_point[ends]
    positions = np.column_stack([table.x[at], table.y[at]]).astype(float)
    order = _boundary_order(mask, origin, positions)
    ends = [ends[k] for k in order]
    dist, pred, positions = dist[order], pred[order], positions[order]
    k = len(ends)
    radii = np.zeros((k, k, samples))
    lengths = np.zeros((k, k))
    for i in range(k):
        for j in range(i + 1, k):
            if not np.isfinite(dist[i, ends[j]]):
                raise UnmatchableShapeError("the skeleton's endpoints are not connected")
            hops = [ends[j]]
            while hops[-1] != ends[i]:
                hops.append(int(pred[i, hops[-1]]))
            hops.reverse()
            parts = []
            for u, v in itertools.pairwise(hops):
                line = best[(min(u, v), max(u, v))][1]
                parts.append(line if u < v else line[::-1])
            r, along = _sample(np.concatenate(parts), samples)
            radii[i, j], radii[j, i] = r, r[::-1]
            lengths[i, j] = lengths[j, i] = along
    mean_radius = float(table.radius[table.pixels()].mean())
    return SkeletonDescriptor(
        node_ids=np.array(ends, np.int64),
        positions=positions,
        radii=radii / mean_radius if mean_radius > 0 else radii,
        lengths=lengths / length if length > 0 else lengths,
        component=component,
    )


def describe(shape: PruneResult | SkeletonDescriptor | Any) -> SkeletonDescriptor:
    """The path table of a pruning result (its largest component) or of a mask (pruned
    with the default options first).

    Raises
    ------
    UnmatchableShapeError
        When that skeleton has fewer than two endpoints or more than
        :data:`MAX_ENDPOINTS`.
    EmptyMaskError
        For a mask with no foreground pixel.
    """
    if isinstance(shape, SkeletonDescriptor):
        return shape
    result = shape if isinstance(shape, PruneResult) else prune(shape)
    if not isinstance(result, PruneResult):
        raise InvalidImageError(
            "shape matching takes a silhouette or a polygon; a volume has no descriptor"
        )
    ci = int(np.argmax([c.area for c in result.components]))
    comp = result.components[ci]
    # the component alone, from its own crop, so that the boundary is its own
    sk = comp.skeleton
    crop = sk.orientation.unapply(sk.mask)
    described = describe_table(comp.table, comp.chosen_point()[0], crop, sk.origin, ci)
    return replace(described, frame=result.frame)


# -- comparing ------------------------------------------------------------------------


@njit(cache=True)
def _path_cost(ra: np.ndarray, la: float, rb: np.ndarray, lb: float, weight: float) -> float:
    s = 0.0
    for t in range(ra.size):
        q = ra[t] + rb[t]
        if q > 0.0:
            s += (ra[t] - rb[t]) ** 2 / q
    q = la + lb
    if q > 0.0:
        s += weight * (la - lb) ** 2 / q
    return s


def path_distance(
    ra: np.ndarray, la: float, rb: np.ndarray, lb: float, weight: float = LENGTH_WEIGHT
) -> float:
    """Dissimilarity of two sampled paths (normalised radii ``r``, lengths ``l``):
    ``Σ_t (r_t − r'_t)² / (r_t + r'_t) + α (l − l')² / (l + l')``.

    >>> path_distance(np.ones(3), 0.5, np.ones(3), 0.5)
    0.0
    """
    return float(
        _path_cost(
            np.asarray(ra, float), float(la), np.asarray(rb, float), float(lb), float(weight)
        )
    )


@njit(cache=True)
def _osb(cost: np.ndarray) -> float:
    """Optimal subsequence bijection of two sequences given their pair costs: the
    cheapest order-preserving one-to-one matching of subsequences, a skipped run of
    ``p`` and ``q`` elements costing ``C·sqrt(p² + q²)`` (at the ends too), with the
    jump cost ``C`` = mean + standard deviation of the row and column minima."""
    m, n = cost.shape
    mins = np.empty(m + n)
    for i in range(m):
        mins[i] = cost[i].min()
    for j in range(n):
        mins[m + j] = cost[:, j].min()
    c = mins.mean() + mins.std()
    best = c * math.sqrt(m * m + n * n)
    d = np.empty((m, n))
    for k in range(m):
        for q in range(n):
            v = c * math.sqrt(k * k + q * q)
            for i in range(k):
                for j in range(q):
                    w = d[i, j] + c * math.sqrt((k - i - 1) ** 2 + (q - j - 1) ** 2)
                    if w < v:
                        v = w
            d[k, q] = v + cost[k, q]
            t = d[k, q] + c * math.sqrt((m - 1 - k) ** 2 + (n - 1 - q) ** 2)
            if t < best:
                best = t
    return best


@njit(cache=True)
def _endpoint_costs(
    ra: np.ndarray, la: np.ndarray, rb: np.ndarray, lb: np.ndarray, weight: float, reverse: bool
) -> np.ndarray:
    """``c[i, j]``: OSB of the paths leaving endpoint ``i`` of a (to the others, in
    boundary order from ``i``) against those leaving ``j`` of b (in b's order, or its
    reverse)."""
    ka, kb = la.shape[0], lb.shape[0]
    out = np.empty((ka, kb))
    sub = np.empty((ka - 1, kb - 1))
    for i in range(ka):
        for j in range(kb):
            for a in range(ka - 1):
                x = (i + 1 + a) % ka
                for b in range(kb - 1):
                    y = (j - 1 - b + kb) % kb if reverse else (j + 1 + b) % kb
                    sub[a, b] = _path_cost(ra[i, x], la[i, x], rb[j, y], lb[j, y], weight)
            out[i, j] = _osb(sub)
    return out


def _assign(cost: np.ndarray) -> tuple[float, list[tuple[int, int]]]:
    """Optimal assignment; each endpoint left over (the larger skeleton's surplus) costs
    the mean endpoint cost, as a match to a dummy endpoint."""
    rows, cols = linear_sum_assignment(cost)
    surplus = abs(cost.shape[0] - cost.shape[1])
    total = float(cost[rows, cols].sum()) + surplus * float(cost.mean())
    return total, [(int(i), int(j)) for i, j in zip(rows, cols, strict=True)]


def _match(
    a: SkeletonDescriptor, b: SkeletonDescriptor
) -> tuple[float, list[tuple[int, int]], bool]:
    best: tuple[float, list[tuple[int, int]], bool] | None = None
    for reverse in (False, True):
        cost = _endpoint_costs(a.radii, a.lengths, b.radii, b.lengths, LENGTH_WEIGHT, reverse)
        total, pairs = _assign(cost)
        if best is None or total < best[0]:
            best = (total, pairs, reverse)
    assert best is not None
    return best


def match(
    a: PruneResult | np.ndarray | SkeletonDescriptor,
    b: PruneResult | np.ndarray | SkeletonDescriptor,
) -> Match:
    """Path similarity of two skeletons: their distance and endpoint correspondence.

    Parameters
    ----------
    a, b : PruneResult, mask or SkeletonDescriptor
        Results of :func:`skelprune.prune` (their largest component is matched), masks
        (pruned with the default options), or descriptors from :func:`describe` (reuse
        them to match one shape against many).

    Returns
    -------
    Match

    Raises
    ------
    UnmatchableShapeError
        When a skeleton has fewer than two endpoints or more than :data:`MAX_ENDPOINTS`.

    Examples
    --------
    >>> import skelprune
    >>> m = np.zeros((40, 90), bool); m[5:35, 5:85] = True; m[10:30, 40:50] = False
    >>> t = np.zeros((40, 90), bool); t[8:32, 5:85] = True
    >>> skelprune.match(m, t).distance > 0
    True
    """
    da, db = describe(a), describe(b)
    distance, pairs, mirrored = _match(da, db)
    return Match(distance=distance, pairs=pairs, mirrored=mirrored, a=da, b=db)


def _rows(args: tuple[Sequence[SkeletonDescriptor], Sequence[SkeletonDescriptor]]) -> np.ndarray:
    queries, database = args
    return np.array([[_match(q, d)[0] for d in database] for q in queries]).reshape(
        len(queries), len(database)
    )


def distance_matrix(
    descriptors: Sequence[SkeletonDescriptor],
    queries: Sequence[SkeletonDescriptor] | None = None,
    workers: int = 1,
) -> np.ndarray:
    """Distances of every query (default: every descriptor) to every descriptor.

    Without ``queries`` the matrix is symmetric with a zero diagonal and, in one process,
    each pair is computed once. With ``workers > 1`` the rows are split over that many
    processes (each pair then computed in both orders, which gives the same value).
    """
    if workers > 1:
        from concurrent.futures import ProcessPoolExecutor

        qs = list(descriptors if queries is None else queries)
        parts = [p for p in np.array_split(np.arange(len(qs)), 4 * workers) if p.size]
        with ProcessPoolExecutor(workers) as pool:
            rows = list(pool.map(_rows, [([qs[i] for i in p], descriptors) for p in parts]))
        out = np.vstack(rows) if rows else np.zeros((0, len(descriptors)))
        if queries is None:
            np.fill_diagonal(out, 0.0)
        return out
    if queries is None:
        n = len(descriptors)
        out = np.zeros((n, n))
        for i in range(n):
            for j in range(i + 1, n):
                out[i, j] = out[j, i] = _match(descriptors[i], descriptors[j])[0]
        return out
    return _rows((queries, descriptors))
