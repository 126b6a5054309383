"""A polygon's raster: the pixel size that fits it, and the check that the raster kept it.

**Pixel size.** Unless told otherwise (``pixel_size`` or ``longest_side``), the pixel comes
from the polygon itself: the narrowest parts must be ``pixels_per_width`` pixels across,
and no coarser than :data:`~skelprune.options.DEFAULT_LONGEST_SIDE` pixels along the
bounding box's longer side, and the raster holds at most ``pixel_budget`` pixels. The
narrowest width is measured twice:

- from the geometry: ``2·area/perimeter`` of every part and every hole (a strip's width,
  half a disk's diameter), so that a part or hole far smaller than the others is seen
  even where a coarse raster would lose it;
- across the boundary: for each point of the evenly resampled boundary the nearest point
  across the polygon, and the 2 % quantile of those widths over the boundary's length
  (:func:`narrowest_width`), so that a neck of an otherwise wide part counts.

**Topology check.** After rasterising, every part of the polygon must be one 8-connected
raster component, no two parts may share one, and the raster must hold as many holes as
the polygon. Each failure is a :class:`RasterWarning` naming the part and a pixel size that
holds it (found by rasterising the part alone at finer sizes).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import shapely
from scipy import ndimage
from scipy.spatial import cKDTree
from shapely.geometry import MultiPolygon, Polygon

from ..errors import SkelpruneError
from ..grid._label import holes

__all__ = [
    "RasterWarning",
    "check_topology",
    "covered_xy",
    "fitted_pixel_size",
    "narrowest_width",
]

EIGHT = np.ones((3, 3), dtype=bool)
#: Quantile of the boundary's local widths taken as the narrowest: below it, single
#: corners and spikes, which any raster rounds off.
WIDTH_QUANTILE = 0.02
#: Boundary samples at most (the sampling step grows for long boundaries) ...
SAMPLES = 40_000
#: ... and the nearest samples looked at for the one across.
NEIGHBOURS = 24
#: Parts for which a holding pixel size is searched (each search rasterises the part a
#: few times); further failing parts are counted in one more warning.
SEARCHED_PARTS = 8
#: Largest raster tried while searching for a holding pixel size.
SEARCH_PIXELS = 1 << 22


def _rings(geom: MultiPolygon) -> list[Polygon]:
    """Every part, and every hole as a polygon of its own."""
    out: list[Polygon] = []
    for part in geom.geoms:
        out.append(part)
        out.extend(Polygon(r) for r in part.interiors)
    return out


def geometric_width(geom: MultiPolygon) -> float:
    """The smallest ``2·area/perimeter`` over the parts and holes of a polygon."""
    widths = [2 * p.area / p.length for p in _rings(geom) if p.length > 0 and p.area > 0]
    return min(widths) if widths else math.inf


def narrowest_width(geom: MultiPolygon, quantile: float = WIDTH_QUANTILE) -> float:
    """The width of a polygon's narrow parts, in its units.

    The boundary is resampled evenly; for each sample, the nearest sample across the
    polygon (its chord runs inside, and the way round along the boundary is more than
    twice the chord: not a neighbour on the same side) gives the local width. Returned:
    the ``quantile`` of those widths over the boundary's length.

    >>> from shapely.geometry import box
    >>> strip = MultiPolygon([box(0, 0, 1000, 20)])
    >>> round(narrowest_width(strip))
    20
    """
    geo = geometric_width(geom)
    rings = np.array([r for part in geom.geoms for r in (part.exterior, *part.interiors)])
    lengths = shapely.length(rings).tolist()
    total = sum(lengths)
    step = max(geo / 8, total / SAMPLES)
    # every ring at once: resampled, its closing position dropped
    coords, which = shapely.get_coordinates(shapely.segmentize(rings, step), return_index=True)
    counts = np.bincount(which, minlength=len(rings))
    last = np.cumsum(counts) - 1
    open_ = np.ones(len(coords), bool)
    open_[last[counts > 0]] = False
    coords, which = coords[open_], which[open_]
    counts = np.maximum(counts - 1, 0)
    kept = counts >= 3
    if not kept.any():
        return geo
    take = kept[which]
    pts, rid = coords[take], which[take]
    pieces = np.split(pts, np.cumsum(counts[kept])[:-1])
    s = np.concatenate(
        [np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(c, axis=0).T))]) for c in pieces]
    )
    length = np.asarray(lengths)[rid]
    tree = cKDTree(pts)
    dist, nb = tree.query(pts, k=min(NEIGHBOURS, len(pts)))
    same = rid[nb] == rid[:, None]
    around = np.abs(s[nb] - s[:, None])
    around = np.minimum(around, length[:, None] - around)
    across = (~same) | (around > 2 * dist)
    across[:, 0] = False  # the point itself
    mid = (pts[:, None, :] + pts[nb]) / 2
    inside = np.zeros_like(across)
    i, j = np.nonzero(across)
    inside[i, j] = covered_xy(geom, mid[i, j, 0], mid[i, j, 1], strict=True)
    width = np.where(across & inside, dist, np.inf).min(axis=1)
    width = width[np.isfinite(width)]
    if width.size == 0:  # every neighbour on the same side: wider than the samples see
        return geo
    return min(float(np.quantile(width, quantile)), geo)


def covered_xy(geom: MultiPolygon, xs: np.ndarray, ys: np.ndarray, strict: bool = False) -> Any:
    """Which points lie in a polygon (``strict``: in its interior; else also on its
    boundary), as ``shapely.intersects_xy`` / ``contains_xy`` answer, in about linear time
    in the parts and points: the points are binned on a grid of about one cell a part, and
    each part tests only the points of the cells its box covers.

    >>> from shapely.geometry import box
    >>> geom = MultiPolygon([box(0, 0, 1, 1), box(2, 0, 3, 1)])
    >>> covered_xy(geom, np.array([0.5, 1.5, 3.0]), np.array([0.5, 0.5, 0.5])).tolist()
    [True, False, True]
    """
    test = shapely.contains_xy if strict else shapely.intersects_xy
    parts = list(geom.geoms)
    if len(parts) <= 1 or len(xs) == 0:
        shapely.prepare(geom)
        return test(geom, xs, ys)
    minx, miny, maxx, maxy = geom.bounds
    n = math.ceil(math.sqrt(len(parts))) + 1  # cells along each side
    cw = max(maxx - minx, 1e-300) / n
    ch = max(maxy - miny, 1e-300) / n
    cx = np.clip(((xs - minx) / cw).astype(np.int64), 0, n - 1)
    cy = np.clip(((ys - miny) / ch).astype(np.int64), 0, n - 1)
    key = cy * n + cx
    order = np.argsort(key, kind="stable")
    key = key[order]
    out = np.zeros(len(xs), dtype=bool)
    bounds = shapely.bounds(parts)
    ix0 = np.clip(((bounds[:, 0] - minx) / cw).astype(np.int64), 0, n - 1)
    ix1 = np.clip(((bounds[:, 2] - minx) / cw).astype(np.int64), 0, n - 1)
    iy0 = np.clip(((bounds[:, 1] - miny) / ch).astype(np.int64), 0, n - 1)
    iy1 = np.clip(((bounds[:, 3] - miny) / ch).astype(np.int64), 0, n - 1)
    # every (part, row of cells) pair at once: the points of its cells' run in the sort
    spans = iy1 - iy0 + 1
    part_of = np.repeat(np.arange(len(parts)), spans)
    row = (np.arange(spans.sum()) - np.repeat(np.cumsum(spans) - spans, spans)) + iy0[part_of]
    lo = np.searchsorted(key, row * n + ix0[part_of], "left")
    hi = np.searchsorted(key, row * n + ix1[part_of], "right")
    runs = hi - lo
    pair_part = np.repeat(part_of, runs)
    pair_point = order[
        np.arange(runs.sum()) - np.repeat(np.cumsum(runs) - runs, runs) + np.repeat(lo, runs)
    ]
    geoms = np.array(parts, dtype=object)
    shapely.prepare(geoms)
    hit = test(geoms[pair_part], xs[pair_point], ys[pair_point])
    out[pair_point[hit]] = True
    return out


def budget_pixel_size(geom: MultiPolygon, budget: int, margin: int) -> float:
    """The smallest pixel size whose raster (margins included) holds at most ``budget``
    pixels."""
    minx, miny, maxx, maxy = geom.bounds
    w, h = maxx - minx, maxy - miny
    m = 2 * margin + 1  # a pixel more for ceil()
    # (w/p + m)(h/p + m) = budget, solved for p
    a, b, c = budget - m * m, -m * (w + h), -w * h
    if a <= 0:
        return math.inf
    return (-b + math.sqrt(b * b - 4 * a * c)) / (2 * a)


def fitted_pixel_size(
    geom: MultiPolygon, pixels_per_width: float, budget: int, longest_side: int, margin: int
) -> float:
    """The pixel size that fits a polygon: ``pixels_per_width`` pixels across its narrowest
    part, no coarser than ``longest_side`` pixels along the bounding box's longer side,
    no finer than ``budget`` pixels allow."""
    minx, miny, maxx, maxy = geom.bounds
    coarsest = max(maxx - minx, maxy - miny) / longest_side
    finest = budget_pixel_size(geom, budget, margin)
    return max(min(coarsest, narrowest_width(geom) / pixels_per_width), finest)


@dataclass(frozen=True)
class RasterWarning:
    """A part of the polygon that the raster does not hold as it is."""

    kind: str  # "vanished" | "split" | "merged" | "holes" | "skipped" | "point" | "crs"
    message: str
    part: int | None = None  # index of the polygon part, where one is meant
    pixel_size: float | None = None  # a pixel size that holds it (None: not found)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def _part_holds(part: Polygon, size: float, margin: int, rasterize: Any) -> bool:
    try:
        mask, _ = rasterize(MultiPolygon([part]), size)
    except SkelpruneError:  # over a limit: not a size to offer
        return False
    n = ndimage.label(mask, EIGHT)[1]
    return n == 1 and holes(mask) == len(part.interiors)


def holding_size(
    part: Polygon, size: float, margin: int, rasterize: Any, max_pixels: int = SEARCH_PIXELS
) -> tuple[float | None, float | None]:
    """The first of ``size/2, size/4, …`` at which a part alone is one raster component
    with its holes (None: none whose raster of the part is within ``max_pixels``), and
    the smallest size tried (None: none was)."""
    minx, miny, maxx, maxy = part.bounds
    tried = None
    for k in range(1, 11):
        s = size / 2**k
        if ((maxx - minx) / s + 2 * margin) * ((maxy - miny) / s + 2 * margin) > max_pixels:
            return None, tried
        tried = s
        if _part_holds(part, s, margin, rasterize):
            return s, tried
    return None, tried


def check_topology(
    geom: MultiPolygon, mask: np.ndarray, frame: Any, margin: int, rasterize: Any
) -> list[RasterWarning]:
    """What the raster of a polygon lost: parts vanished, split or merged, holes closed."""
    labels, n_comp = ndimage.label(mask, EIGHT)
    parts = list(geom.geoms)
    size = frame.pixel_size
    warnings: list[RasterWarning] = []
    # each component belongs to the part holding one of its pixels' centres
    first = []
    for k, sl in enumerate(ndimage.find_objects(labels), start=1):
        r, c = np.unravel_index(int(np.argmax(labels[sl] == k)), labels[sl].shape)
        first.append((sl[0].start + r, sl[1].start + c))
    owner = np.full(n_comp, -1)
    if n_comp:
        rc = np.asarray(first, dtype=float).reshape(-1, 2)
        xs = frame.x0 + rc[:, 1] * size
        ys = frame.y0 - rc[:, 0] * size if frame.flip_y else frame.y0 + rc[:, 0] * size
        tree = shapely.STRtree(parts)
        pts, polys = tree.query(shapely.points(xs, ys), predicate="intersects")
        owner[pts] = polys
    comps_of = np.bincount(owner[owner >= 0], minlength=len(parts))
    failing = [i for i in range(len(parts)) if comps_of[i] != 1]
    for i in failing[:SEARCHED_PARTS]:
        part = parts[i]
        count = int(comps_of[i])
        where = f"part #{i} of {len(parts)}" if len(parts) > 1 else "the polygon"
        fix, tried = holding_size(part, size, margin, rasterize)
        advice = (
            f"; a pixel_size of {fix:.4g} or less holds it"
            if fix is not None
            else f"; none of the sizes tried down to {tried:.4g} holds it"
            if tried is not None
            else "; a finer raster of it is beyond the search's limit"
        )
        if count == 0:
            msg = f"{where} is smaller than the pixel ({size:.4g}) and left no pixel{advice}"
            warnings.append(RasterWarning("vanished", msg, i, fix))
        else:
            msg = f"{where} fell apart into {count} pieces at pixel size {size:.4g}{advice}"
            warnings.append(RasterWarning("split", msg, i, fix))
    if len(failing) > SEARCHED_PARTS:
        more = len(failing) - SEARCHED_PARTS
        warnings.append(
            RasterWarning(
                "vanished",
                f"{more} more polygon part(s) are not one raster piece each at pixel size "
                f"{size:.4g}",
            )
        )
    present = int(np.count_nonzero(comps_of))
    if not warnings and n_comp < present:
        # fewer components than parts present: parts closer than a pixel became one
        warnings.append(
            RasterWarning(
                "merged",
                f"{present - n_comp} polygon part(s) touch another in the raster at pixel "
                f"size {size:.4g} and are pruned together with it",
                None,
                None,
            )
        )
    want = sum(len(p.interiors) for p in parts)
    have = holes(mask)
    if not warnings and have != want:
        fix = None
        minx, miny, maxx, maxy = geom.bounds
        for k in (1, 2):  # a hole a quarter pixel across is as far as it is worth looking
            s = size / 2**k
            if ((maxx - minx) / s + 2 * margin) * ((maxy - miny) / s + 2 * margin) > SEARCH_PIXELS:
                break
            try:
                m, _ = rasterize(geom, s)
            except SkelpruneError:
                break
            if holes(m) == want:
                fix = s
                break
        advice = f"; a pixel_size of {fix:.4g} or less keeps them" if fix else ""
        warnings.append(
            RasterWarning(
                "holes",
                f"the raster has {have} hole(s) where the polygon has {want} at pixel size "
                f"{size:.4g} (a narrow inlet closed into a lake, or a hole or gap narrower "
                f"than a pixel){advice}",
                None,
                fix,
            )
        )
    return warnings
