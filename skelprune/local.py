"""Local scope (``scope="local"``): each branch judged by the trade-off of its neighbourhood.

The paper's trade-off is global: ``α`` and ``ℓ̄`` are taken over the whole component, so
on a large network a 300 px road weighs as little as a one-pixel spur does on a
silhouette, and what is kept depends on how far the image extends. The local scope
prunes windows instead (docs/algorithm.md, "Local scope"):

1. The image is cut into square **cores** of ``window`` pixels (a grid from the top-left
   corner); each core is grown by a **halo** of ``window // 4`` pixels on every side (clipped
   to the image) into its **window**.
2. Each window is pruned alone, with the existing pipeline
   (:func:`skelprune.pipeline.prune_components` with ``scope="global"``) and every other
   option as given.
3. Each pixel of the medial axis is decided once, by the window whose core holds it: it
   is kept if that window's answer (before its tips are cut) keeps it. A branch crossing
   a core border is seen whole by both windows (the halo is longer than the spurs a
   window prunes), so both decide alike.
4. **Stitching**, per component: the cores' axis pixels make its medial axis (thinned
   again within :data:`SEAM` px of a core border; pieces two windows' tie-breaking left
   apart joined by short straight lines). From its graph every end branch of which fewer
   than half the pixels are kept is removed, again and again: only end branches go, so
   the answer is one connected graph, as the global answer is. The tips are then cut as
   ``trim`` says, with ``α`` and ``ℓ̄`` of the stitched skeleton.

The windows' memory follows the window, not the image: one window is pruned at a time (or
one per worker, :func:`prune_local` with ``client``), and what is kept of it is its axis
pixels (three integers and a flag each). The input mask and the stitching over each
component's box are the rest (docs/performance.md, "Large networks").
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import replace
from typing import Any

import numpy as np

from .grid.graph import BranchGraph
from .grid.thinning import thin
from .grid.tips import trim_tips
from .io.input import Input
from .options import (
    LOCAL_HALO_FRACTION,
    LOCAL_WINDOW_RANGE,
    LOCAL_WINDOW_WIDTHS,
    OutputOptions,
    PruneOptions,
)
from .output.component import ComponentResult, GraphSummary
from .output.document import PruneResult
from .pipeline import prune_component, prune_components
from .pruning.bayesian import PruningSequence
from .pruning.log import RemovalLog
from .pruning.normalisation import Normalisation
from .skeleton import Skeleton, normalisation

__all__ = ["default_window", "mean_width", "prune_local", "prune_window", "windows"]


def mean_width(mask: np.ndarray) -> float:
    """The shape's mean width ``2·A / P``: ``A`` its pixels, ``P`` those with a
    background 4-neighbour (a strip of width ``w`` has two such pixels a column).

    Read in strips of rows, so that it costs a few rows of memory, not the image's.

    >>> m = np.zeros((40, 200), bool); m[10:22, 10:190] = True
    >>> round(mean_width(m), 1)  # 12 px wide; the two ends count as rim too
    11.4
    """
    h = mask.shape[0]
    area = rim = 0
    for top in range(0, h, 1024):
        bot = min(h, top + 1024)
        band = np.pad(mask[max(top - 1, 0) : min(bot + 1, h)], ((0, 0), (1, 1)))
        lo = 1 if top > 0 else 0
        inner = band[lo : lo + bot - top]
        edge = np.zeros_like(inner)
        up = np.pad(band, ((1, 1), (0, 0)))[lo : lo + bot - top]
        down = np.pad(band, ((1, 1), (0, 0)))[lo + 2 : lo + 2 + bot - top]
        edge |= ~up | ~down
        edge[:, 1:] |= ~inner[:, :-1]
        edge[:, :-1] |= ~inner[:, 1:]
        area += int(np.count_nonzero(inner))
        rim += int(np.count_nonzero(inner & edge))
    return 2.0 * area / rim if rim else 0.0


def default_window(mask: np.ndarray) -> int:
    """The window of ``scope="local"`` when none is given: ``LOCAL_WINDOW_WIDTHS`` mean
    widths (:func:`mean_width`), rounded up to a multiple of 64, within
    ``LOCAL_WINDOW_RANGE``.

    >>> m = np.zeros((64, 4000), bool); m[20:33, :] = True
    >>> default_window(m)  # 13 px wide: 64 · 13 = 832
    832
    """
    w = mean_width(mask)
    lo, hi = LOCAL_WINDOW_RANGE
    size = 64 * math.ceil(LOCAL_WINDOW_WIDTHS * w / 64) if w > 0 else lo
    return int(min(max(size, lo), hi))


def windows(shape: tuple[int, int], window: int) -> Iterator[tuple[slice, slice, slice, slice]]:
    """Each window as ``(rows, cols)`` of its extent and ``(rows, cols)`` of its core, both
    in the image.

    >>> [(r.start, r.stop, cr.start, cr.stop) for r, c, cr, cc in windows((10, 2), 4)]
    [(0, 5, 0, 4), (3, 9, 4, 8), (7, 10, 8, 10)]
    """
    halo = max(1, int(window * LOCAL_HALO_FRACTION))
    h, w = shape
    for top in range(0, h, window):
        for left in range(0, w, window):
            core_r = slice(top, min(top + window, h))
            core_c = slice(left, min(left + window, w))
            ext_r = slice(max(top - halo, 0), min(core_r.stop + halo, h))
            ext_c = slice(max(left - halo, 0), min(core_c.stop + halo, w))
            yield ext_r, ext_c, core_r, core_c


def prune_window(
    sub: np.ndarray, offset: tuple[int, int], core: tuple[int, int, int, int], options: PruneOptions
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """One window pruned alone: the medial-axis pixels of its core (image rows, columns),
    their squared radii and whether its answer keeps each.

    What a worker runs; pure, so that windows may run anywhere in any order.
    """
    top, bottom, left, right = core
    empty = np.zeros(0, np.int64)
    if not sub.any():
        return empty, empty, empty, np.zeros(0, bool)
    res = prune_components(Input(sub), replace(options, scope="global", window=None).resolved())
    rows, cols, r2, kept = [], [], [], []
    for comp in res.components:
        s = comp.skeleton
        r, c = s.image_coordinates(s.rows, s.cols)
        # the vote is on the window's branches before their tips were cut: a short kept
        # branch cut back to less than half its pixels is kept all the same, its tip cut
        # again once stitched
        chosen = s if comp.trim is None else comp.sequence.skeleton_at(comp.chosen_step)
        alive = np.zeros(s.rows.size, bool)
        alive[chosen.points()] = True
        r = r + offset[0]
        c = c + offset[1]
        own = (r >= top) & (r < bottom) & (c >= left) & (c < right)
        rows.append(r[own])
        cols.append(c[own])
        r2.append(s.r2[own])
        kept.append(alive[own])
    return np.concatenate(rows), np.concatenate(cols), np.concatenate(r2), np.concatenate(kept)


def _run_windows(
    mask: np.ndarray,
    window: int,
    options: PruneOptions,
    client: Any = None,
    progress: Callable[[int, int], None] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    spans = list(windows(mask.shape, window))
    parts: list[Any] = []
    for k, (er, ec, cr, cc) in enumerate(spans):
        args = (
            np.ascontiguousarray(mask[er, ec]),
            (er.start, ec.start),
            (cr.start, cr.stop, cc.start, cc.stop),
            options,
        )
        if client is None:
            parts.append(prune_window(*args))
            if progress is not None:
                progress(k + 1, len(spans))
        else:
            parts.append(client.submit(prune_window, *args, pure=False))
    if client is not None:
        from dask.distributed import as_completed

        futures = parts
        for done, _ in enumerate(as_completed(futures), 1):
            if progress is not None:
                progress(done, len(spans))
        parts = client.gather(futures)
    rows = np.concatenate([p[0] for p in parts]) if parts else np.zeros(0, np.int64)
    cols = np.concatenate([p[1] for p in parts]) if parts else np.zeros(0, np.int64)
    r2 = np.concatenate([p[2] for p in parts]) if parts else np.zeros(0, np.int64)
    kept = np.concatenate([p[3] for p in parts]) if parts else np.zeros(0, bool)
    return rows, cols, r2, kept


#: Pixels either side of a core border where the stitched answer is thinned again ...
SEAM = 2
#: ... and where the pieces two windows' axes leave apart are looked for.
BRIDGE = 6


def _seam_thinned(
    rows: np.ndarray, cols: np.ndarray, shape: tuple[int, int], origin: tuple[int, int], window: int
) -> np.ndarray:
    """Which kept pixels stay once the seams are thinned: the two windows' axes meet at a
    core border, each tie broken in its own window, and may touch there side by side
    (a 2 × 2 block, a short cycle); within :data:`SEAM` px of a border, pixels that
    thinning (:func:`~skelprune.grid.thinning.thin`, topology-preserving) removes go;
    nowhere else does a pixel change."""
    img = np.zeros(shape, bool)
    img[rows, cols] = True
    drop = np.zeros(shape, bool)
    band = SEAM + 2
    for axis in (0, 1):
        start = (-origin[axis]) % window  # first core border inside the crop
        for b in range(start, shape[axis], window):
            lo, hi = max(b - band, 0), min(b + band, shape[axis])
            part = img[lo:hi] if axis == 0 else img[:, lo:hi]
            if not part.any():
                continue
            gone = part & ~thin(part)
            # only pixels whose whole neighbourhood lies in the band may go
            keep_lo, keep_hi = max(b - SEAM, lo + 1) - lo, min(b + SEAM, hi - 1) - lo
            if axis == 0:
                drop[lo + keep_lo : lo + keep_hi] |= gone[keep_lo:keep_hi]
            else:
                drop[:, lo + keep_lo : lo + keep_hi] |= gone[:, keep_lo:keep_hi]
    return ~drop[rows, cols]


def _pieces(rows: np.ndarray, cols: np.ndarray) -> tuple[int, np.ndarray]:
    """8-connected pieces of a pixel set: their number and each pixel's piece."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    n = rows.size
    width = int(cols.max()) + 2
    flat = rows * width + cols
    order = np.argsort(flat)
    sflat = flat[order]
    src, dst = [], []
    for dr, dc in ((0, 1), (1, -1), (1, 0), (1, 1)):
        q = flat + dr * width + dc
        j = np.minimum(np.searchsorted(sflat, q), n - 1)
        hit = sflat[j] == q
        src.append(np.flatnonzero(hit))
        dst.append(order[j[hit]])
    s, d = np.concatenate(src), np.concatenate(dst)
    graph = coo_matrix((np.ones(s.size, np.int8), (s, d)), shape=(n, n))
    count, label = connected_components(graph, directed=False)
    return int(count), label


def _line(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """The pixels strictly between ``p`` and ``q`` on a straight 8-connected line."""
    steps = int(np.abs(q - p).max())
    t = np.linspace(0.0, 1.0, steps + 1)[1:-1]
    return np.round(p[None, :] + t[:, None] * (q - p)[None, :]).astype(np.int64).reshape(-1, 2)


def _join(crop: np.ndarray, p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """The pixels strictly between ``p`` and ``q`` on a path inside the shape: the straight
    line where it stays inside (at a seam, nearly always), else the shortest 8-connected
    path through the shape (a ragged or noisy component, whose straight joins cross the
    background, where no disk could be)."""
    line = _line(p, q)
    if crop[line[:, 0], line[:, 1]].all():
        return line
    from collections import deque

    h, w = crop.shape
    start, goal = int(p[0]) * w + int(p[1]), int(q[0]) * w + int(q[1])
    came = np.full(h * w, -1, np.int64)
    came[start] = start
    queue = deque([start])
    flat = crop.ravel()
    while queue:
        at = queue.popleft()
        if at == goal:
            break
        r, c = divmod(at, w)
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                rr, cc = r + dr, c + dc
                if 0 <= rr < h and 0 <= cc < w:
                    nxt = rr * w + cc
                    if flat[nxt] and came[nxt] < 0:
                        came[nxt] = at
                        queue.append(nxt)
    path = []
    at = int(came[goal])
    while at != start:  # one component: the goal is always reached
        path.append(divmod(at, w))
        at = int(came[at])
    return np.asarray(path[::-1], np.int64).reshape(-1, 2)


def _find(parent: list[int], a: int) -> int:
    while parent[a] != a:
        parent[a] = parent[parent[a]]
        a = parent[a]
    return a


def _bridged(
    crop: np.ndarray,
    rows: np.ndarray,
    cols: np.ndarray,
    r2: np.ndarray,
    kept: np.ndarray,
    origin: tuple[int, int] = (0, 0),
    window: int = 0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The axis of one component in one piece: where two windows' axes fail to meet at a
    seam (each broke its ties its own way), pieces are joined by straight 8-connected lines
    (a few pixels), kept, with their own radii: the shortest joins first between the
    pixels near a core border (:data:`BRIDGE` px), each only if its two pieces are still
    apart; should pieces remain, the largest is joined to its nearest other, and so on.
    A join that would cross the background follows the shape instead (:func:`_join`)."""
    from scipy import ndimage
    from scipy.spatial import cKDTree

    while rows.size > 1:
        count, label = _pieces(rows, cols)
        if count == 1:
            break
        pts = np.stack([rows, cols], 1)
        joins: list[tuple[int, int]] = []
        if window:
            off_r = (rows + origin[0]) % window
            off_c = (cols + origin[1]) % window
            near = np.minimum(np.minimum(off_r, window - off_r), np.minimum(off_c, window - off_c))
            seam = np.flatnonzero(near <= BRIDGE)
            if seam.size > 1:
                k = min(12, seam.size)
                dist, idx = cKDTree(pts[seam]).query(pts[seam], k=k)
                dist = np.where(label[seam][idx] != label[seam][:, None], dist, np.inf)
                j = dist.argmin(1)
                best = dist[np.arange(seam.size), j]
                parent = list(range(count))
                for a in np.argsort(best, kind="stable"):
                    if not np.isfinite(best[a]) or best[a] > 2 * BRIDGE:
                        break
                    pa, pb = seam[a], seam[idx[a, j[a]]]
                    la, lb = _find(parent, int(label[pa])), _find(parent, int(label[pb]))
                    if la != lb:
                        parent[la] = lb
                        joins.append((int(pa), int(pb)))
        if not joins:  # far apart, or no window: the largest piece to its nearest other
            mine = label == np.bincount(label).argmax()
            inside, outside = np.flatnonzero(mine), np.flatnonzero(~mine)
            dist, near_i = cKDTree(pts[outside]).query(pts[inside])
            a = int(np.argmin(dist))
            joins = [(int(inside[a]), int(outside[near_i[a]]))]
        lines = [_join(crop, pts[a], pts[b]) for a, b in joins]
        line = np.concatenate(lines) if lines else np.zeros((0, 2), np.int64)
        if line.size == 0:  # the pieces touch already: cannot happen, but stop safely
            break
        pad = int(np.sqrt(r2.max())) + 2 if r2.size else 2  # the patch holds every disk
        radii = np.empty(len(line), np.int64)
        for seg in np.split(np.arange(len(line)), np.cumsum([len(x) for x in lines])[:-1]):
            if seg.size == 0:
                continue
            part = line[seg]
            lo = np.maximum(part.min(0) - pad, 0)
            hi = np.minimum(part.max(0) + pad + 1, crop.shape)
            patch = crop[lo[0] : hi[0], lo[1] : hi[1]]
            d2 = np.rint(ndimage.distance_transform_edt(patch) ** 2).astype(np.int64)
            radii[seg] = d2[part[:, 0] - lo[0], part[:, 1] - lo[1]]
        rows = np.concatenate([rows, line[:, 0]])
        cols = np.concatenate([cols, line[:, 1]])
        r2 = np.concatenate([r2, radii])
        kept = np.concatenate([kept, np.ones(len(line), bool)])
    return rows, cols, r2, kept


def _component_result(
    crop: np.ndarray,
    origin: tuple[int, int],
    rows: np.ndarray,
    cols: np.ndarray,
    r2: np.ndarray,
    kept: np.ndarray,
    options: PruneOptions,
) -> ComponentResult:
    """One component's stitched answer as the document reads it.

    The graph is the component's medial axis (its windows' cores' axis pixels, the seams
    thinned), from which every end branch of which fewer than half the pixels are kept by
    their windows is removed, again and again as removals make new end branches: only
    end branches go, so the answer stays one connected graph. The tips are then cut back
    as ``trim`` says. The answer is the sequence's only step: no greedy sequence runs over
    the whole component.
    """
    r = rows - origin[0]
    c = cols - origin[1]
    keep = _seam_thinned(r, c, crop.shape, origin, options.window or 0)
    r, c, r2, kept = _bridged(
        crop, r[keep], c[keep], r2[keep], kept[keep], origin, options.window or 0
    )
    axis = Skeleton(crop, r, c, r2, BranchGraph(r, c, crop.shape), origin=origin)
    graph = axis.working_graph()
    changed = True
    while changed:
        changed = False
        for b in graph.end_branches():
            if not graph.is_end_branch(b):
                continue  # merged away by an earlier removal of this pass
            points = graph.branches[b].points
            if 2 * int(np.count_nonzero(kept[points])) < len(points):
                graph.remove_end_branch(b)
                changed = True
    answer = axis.with_graph(graph)
    area = answer.area
    lost = area - int(np.count_nonzero(answer.reconstruction() & crop))
    ma_lost = area - int(np.count_nonzero(axis.reconstruction() & crop))
    try:
        norm = normalisation(graph, r2, options.beta)
    except ValueError:  # ends out of the seed's reach: the seams left the axis in pieces
        norm = Normalisation(0, 0.0, None)
    trim = None
    if options.trim and options.method == "bayesian" and norm.alpha is not None:
        trim = trim_tips(answer, lost, norm.alpha, norm.lbar)
    seq = PruningSequence(
        start=answer,
        log=RemovalLog(),
        lost=[lost],
        steps=[graph.total_steps()],
        area=area,
        alpha=norm.alpha,
        lbar=norm.lbar,
        end=graph,
    )
    return ComponentResult(
        skeleton=answer if trim is None else trim.skeleton,
        axis_summary=GraphSummary.of(axis),
        sequence=seq,
        chosen_step=0,
        ma_rer=ma_lost / area,
        trim=trim,
    )


def prune_local(
    shape: Input,
    options: PruneOptions,
    output: OutputOptions | None = None,
    *,
    client: Any = None,
    progress: Callable[[int, int], None] | None = None,
) -> PruneResult:
    """Prune ``shape`` window by window and stitch the answers (the module's docstring).

    ``options.window`` (None: :func:`default_window`) sets the window. ``client``: a
    ``dask.distributed.Client`` to prune the windows on (None: one after the other, here);
    ``progress(done, total)`` is called as windows finish.

    Examples
    --------
    >>> m = np.zeros((60, 300), bool); m[20:32, 5:295] = True; m[32:50, 150:160] = True
    >>> res = prune_local(Input(m), PruneOptions(scope="local", window=128).resolved())
    >>> res.options.window, len(res.components), res.components[0].graph.n_endpoints()
    (128, 1, 3)
    """
    if shape.labels is not None:
        from .errors import InvalidOptionError

        raise InvalidOptionError("scope='local' prunes a mask's components, not a label image")
    mask = shape.mask
    window = options.window or default_window(mask)
    applied = replace(options, window=window)
    if window >= max(mask.shape):
        # one window holds the image: it is pruned alone, as the global scope prunes it
        result = prune_components(
            shape, replace(applied, scope="global", window=None).resolved(), output, progress
        )
        result.options = applied
        return result
    rows, cols, r2, kept = _run_windows(mask, window, applied, client, progress)
    order = np.lexsort((cols, rows))
    rows, cols, r2, kept = rows[order], cols[order], r2[order], kept[order]
    result = PruneResult(
        input=shape, options=applied, output=OutputOptions() if output is None else output
    )
    for crop, origin, _ in shape.components():
        top, left = origin
        lo = np.searchsorted(rows, top)
        hi = np.searchsorted(rows, top + crop.shape[0])
        r, c = rows[lo:hi] - top, cols[lo:hi] - left
        inside = (c >= 0) & (c < crop.shape[1])
        sel = np.flatnonzero(inside)
        sel = sel[crop[r[sel], c[sel]]] + lo
        if sel.size == 0:  # too small to hold an axis pixel of its own windows
            result.components.append(
                prune_component(crop, origin, replace(applied, scope="global"))
            )
            continue
        result.components.append(
            _component_result(crop, origin, rows[sel], cols[sel], r2[sel], kept[sel], applied)
        )
    return result
