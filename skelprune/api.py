"""The one entry point most callers need: :func:`prune`."""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
from scipy import ndimage

from .errors import EmptyMaskError, InvalidOptionError
from .graph import BranchGraph
from .medial_axis import medial_axis, squared_distance
from .pruning import PruningSequence, bayesian_sequence, choose_step, normalisation
from .reconstruction import reconstruction_error
from .result import ComponentResult, PruneResult

__all__ = ["METHODS", "components", "prune"]

METHODS = ("bayesian", "dce")
COARSE = (None, "dce")
EIGHT = np.ones((3, 3), dtype=bool)


def components(mask: np.ndarray) -> list[tuple[np.ndarray, tuple[int, int]]]:
    """8-connected components as padded crops with their origin in the image.

    Each crop has one background pixel all around (so shapes touching the image
    border work) and holds only its own component.
    """
    labels, _n = ndimage.label(mask, structure=EIGHT)
    out = []
    for k, sl in enumerate(ndimage.find_objects(labels), start=1):
        crop = np.pad(labels[sl] == k, 1)
        out.append((crop, (sl[0].start - 1, sl[1].start - 1)))
    return out


def _check_options(beta: float, method: str, coarse: str | None) -> None:
    if not isinstance(beta, (int, float)) or isinstance(beta, bool) or not math.isfinite(beta) \
            or beta <= 0:
        raise InvalidOptionError(f"beta must be a finite number > 0, got {beta!r}")
    if method not in METHODS:
        raise InvalidOptionError(f"method must be one of {METHODS}, got {method!r}")
    if coarse not in COARSE:
        raise InvalidOptionError(f"coarse must be null or 'dce', got {coarse!r}")


def _replay(ma_rows, ma_cols, shape, removed: list[int], upto: int) -> BranchGraph:
    g = BranchGraph(ma_rows, ma_cols, shape)
    for b in removed[:upto]:
        g.remove_end_branch(b)
    return g


def prune_component(crop: np.ndarray, origin: tuple[int, int], beta: float,
                    method: str, coarse: str | None) -> ComponentResult:
    """Medial axis and pruning of one padded component crop."""
    r2img = squared_distance(crop)
    ma = medial_axis(crop, r2img)
    graph = BranchGraph(ma.rows, ma.cols, crop.shape)
    norm = normalisation(graph, ma.r2, beta)
    ma_rer = reconstruction_error(crop, ma.rows, ma.cols, ma.r2)
    if method != "bayesian" or coarse is not None:
        raise InvalidOptionError("DCE pruning is not available yet")
    seq: PruningSequence = bayesian_sequence(graph, crop, ma.r2, norm.alpha, norm.lbar)
    chosen = choose_step(seq.objective)
    final = _replay(ma.rows, ma.cols, crop.shape, seq.removed, chosen)
    return ComponentResult(
        origin=origin, area=int(crop.sum()), r2=ma.r2,
        medial_axis=BranchGraph(ma.rows, ma.cols, crop.shape), graph=final,
        sequence=seq, chosen_step=chosen, ma_rer=ma_rer,
    )


def prune(
    mask: np.ndarray,
    beta: float = 9.0,
    method: Literal["bayesian", "dce"] = "bayesian",
    coarse: Literal["dce"] | None = None,
) -> PruneResult:
    """Pruned skeleton of every 8-connected component of a binary mask.

    Parameters
    ----------
    mask : (H, W) array
        Non-zero pixels are the shape.
    beta : float
        Weight of the reconstruction term, ``α = β·log(length(M)/ℓ̄)``; the paper's 9.
    method : {"bayesian", "dce"}
        Bayesian pruning (the paper) or DCE contour-partition pruning (its ref. [10]).
    coarse : {None, "dce"}
        For ``method="bayesian"``: start from the full medial axis (``None``), or from
        a coarse DCE-pruned skeleton.

    Returns
    -------
    PruneResult

    Raises
    ------
    EmptyMaskError
        When the mask has no foreground pixel.
    InvalidOptionError
        For a bad ``beta``, ``method`` or ``coarse``.

    Examples
    --------
    >>> m = np.zeros((30, 60), bool); m[5:25, 5:55] = True
    >>> res = prune(m)
    >>> comp = res.components[0]
    >>> len(comp.to_dict()["skeleton"]["endpoints"]), comp.rer < 0.05
    (4, True)
    """
    _check_options(beta, method, coarse)
    mask = np.asarray(mask)
    if mask.ndim != 2:
        raise InvalidOptionError(f"mask must be 2-D, got shape {mask.shape}")
    fg = mask != 0
    if not fg.any():
        raise EmptyMaskError("the mask has no foreground pixel")
    result = PruneResult(mask=fg, method=method, beta=float(beta), coarse=coarse)
    for crop, origin in components(fg):
        result.components.append(prune_component(crop, origin, beta, method, coarse))
    return result
