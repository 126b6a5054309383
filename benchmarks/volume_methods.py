"""The curve skeletons compared by ``python -m benchmarks volumes``, and their scores.

Every method takes a bool volume ``(z, y, x)`` and its ``spacing = (dz, dy, dx)`` and
answers a bool volume of skeleton voxels. Lengths and tolerances are physical, in units
of the finest voxel side (1 here).

- ``medial axis``: :func:`skelprune.grid3d.curve_skeleton`, unpruned;
- ``skelprune (pruned)``: :func:`skelprune.prune` at its default options (the same curve
  skeleton, pruned by the trade-off between length and lost volume);
- ``kimimaro``: TEASAR with its README's parameters (listing 1: ``scale`` 1.5,
  ``const`` 300, somas 750/3500/300/2, ``pdrf`` 100000 and 4, ``max_paths`` 300,
  ``dust_threshold`` 1000, ``fix_branching``, ``fix_borders``), physical ones converted to
  voxel units by the README's 16 nm voxel side: ``const`` 18.75 voxels;
- ``skan N``: ``skimage.morphology.skeletonize`` (3-D), then skan's ``prune_paths`` of
  the end branches (junction to end point) shorter than ``N`` voxels, once.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

__all__ = ["METHODS", "endpoints", "scores"]

_NM = 16.0  # the README's voxel side, to turn its physical parameters into voxels
KIMIMARO = {
    "scale": 1.5,
    "const": 300 / _NM,
    "pdrf_scale": 100000,
    "pdrf_exponent": 4,
    "soma_acceptance_threshold": 3500 / _NM,
    "soma_detection_threshold": 750 / _NM,
    "soma_invalidation_const": 300 / _NM,
    "soma_invalidation_scale": 2,
    "max_paths": 300,
}


def medial_axis(volume: np.ndarray, spacing) -> np.ndarray:
    from skelprune.grid3d import curve_skeleton

    return curve_skeleton(volume, spacing).mask()


def pruned(volume: np.ndarray, spacing, **options) -> np.ndarray:
    """:func:`skelprune.prune` at ``options`` (the library's defaults unless given): the
    curve skeleton pruned, as a voxel mask."""
    import skelprune

    res = skelprune.prune(volume, spacing=tuple(spacing), **options)
    out = np.zeros(volume.shape, dtype=bool)
    for comp in res.components:
        sk = comp.skeleton
        idx = sk.points()
        oz, oy, ox = sk.origin
        out[sk.z[idx] + oz, sk.y[idx] + oy, sk.x[idx] + ox] = True
    return out


def kimimaro_teasar(volume: np.ndarray, spacing) -> np.ndarray:
    import kimimaro

    skels = kimimaro.skeletonize(
        volume.astype(np.uint8),
        teasar_params=KIMIMARO,
        anisotropy=tuple(float(s) for s in spacing),
        dust_threshold=1000,
        fix_branching=True,
        fix_borders=True,
        progress=False,
        parallel=1,
    )
    out = np.zeros(volume.shape, dtype=bool)
    for sk in skels.values():
        idx = np.rint(sk.vertices / np.array(spacing)).astype(np.int64)
        idx = np.clip(idx, 0, np.array(volume.shape) - 1)
        out[idx[:, 0], idx[:, 1], idx[:, 2]] = True
    return out


def _skan(volume: np.ndarray, spacing, shorter: float) -> np.ndarray:
    from skan import Skeleton, summarize
    from skimage.morphology import skeletonize

    thin = skeletonize(volume)
    if not thin.any():
        return thin
    skel = Skeleton(thin, spacing=spacing)
    table = summarize(skel, separator="_")
    ends = table.index[(table["branch_type"] == 1) & (table["branch_distance"] < shorter)]
    if len(ends):
        skel = skel.prune_paths(ends.to_numpy())
    return np.asarray(skel.skeleton_image) > 0


def skan5(volume: np.ndarray, spacing) -> np.ndarray:
    return _skan(volume, spacing, 5.0)


def skan10(volume: np.ndarray, spacing) -> np.ndarray:
    return _skan(volume, spacing, 10.0)


METHODS = {
    "medial axis (unpruned)": medial_axis,
    "skelprune (pruned)": pruned,
    "kimimaro": kimimaro_teasar,
    "skan 5": skan5,
    "skan 10": skan10,
}


def endpoints(mask: np.ndarray) -> np.ndarray:
    """Voxels of ``mask`` with exactly one 26-neighbour in it, as (k, 3) indices."""
    count = ndimage.convolve(mask.astype(np.uint8), np.ones((3, 3, 3), np.uint8), mode="constant")
    return np.argwhere(mask & (count == 2))


def scores(mask: np.ndarray, truth, tolerance: float = 2.0) -> dict[str, float]:
    """F1 of the skeleton voxels at ``tolerance`` against the true centre lines; tips
    found (an end point inside the tip's end ball grown by ``tolerance``), true tips,
    spurs (end points near no true tip) and end points.

    ``truth``: a :class:`testkit.volumes.SweptShape`.
    """
    sp = truth.spacing
    centre = truth.centre_mask()
    near_centre = ndimage.distance_transform_edt(~centre, sampling=sp) <= tolerance
    precision = float(near_centre[mask].mean()) if mask.any() else 0.0
    near_skeleton = ndimage.distance_transform_edt(~mask, sampling=sp) <= tolerance
    recall = float(near_skeleton[centre].mean())
    f1 = 2 * precision * recall / (precision + recall) if precision + recall else 0.0
    ends = endpoints(mask) * np.array(sp)
    tips = np.asarray(truth.tips).reshape(-1, 3)
    reach = np.array([_tip_radius(truth, t) for t in tips]) + tolerance
    if len(ends) and len(tips):
        dist = np.linalg.norm(ends[:, None, :] - tips[None, :, :], axis=2)
        found = int((dist <= reach[None, :]).any(axis=0).sum())
        spurs = int((~(dist <= reach[None, :]).any(axis=1)).sum())
    else:
        found, spurs = 0, len(ends)
    return {
        "f1": f1,
        "precision": precision,
        "recall": recall,
        "tips found": found,
        "true tips": len(tips),
        "spurs": spurs,
        "endpoints": len(ends),
    }


def _tip_radius(truth, tip: np.ndarray) -> float:
    """The ball radius at a tip: the radius of the centre point it ends."""
    best, radius = np.inf, 0.0
    for line, r in zip(truth.lines, truth.radii, strict=True):
        for k in (0, -1):
            d = float(np.linalg.norm(line[k] - tip))
            if d < best:
                best, radius = d, float(r[k])
    return radius
