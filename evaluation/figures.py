"""Figures of ``python -m evaluation`` (the paper's Figs. 3, 6–7, 9 and 11).

matplotlib is an optional extra (``bench``): it is imported inside the functions, so that
nothing else in the package (and never the service) needs it. Overlays are the library's
own :meth:`PruneResult.render_overlay` images (shape green, reconstruction error red,
skeleton black, endpoints blue, junctions orange).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .stability import VARIANTS, Variant

__all__ = [
    "curves_figure",
    "methods_figure",
    "montage_figure",
    "overlay",
    "perturbation_figure",
    "rectangles_figure",
]


def _plt() -> Any:
    import matplotlib

    matplotlib.use("Agg")  # files only; no display needed (and none on a server)
    import matplotlib.pyplot as plt

    return plt


def overlay(variant: Variant, mask: np.ndarray) -> tuple[np.ndarray, int]:
    """RGB overlay of one variant's skeleton, in the library's colours, and its endpoints.

    The baseline has no :class:`PruneResult`; its skeleton pixels and distance-transform
    radii are painted with the same colours (endpoints are skeleton pixels of degree 1).
    """
    if variant.kind == "prune":
        from skelprune.api import prune

        res = prune(mask, **variant.kwargs)
        return res.render_overlay(), res.n_endpoints()
    from skelprune.output.render import render_overlay

    from .baseline import skeletonize_cut

    sk = skeletonize_cut(mask, variant.kwargs["min_length"])
    fg = np.asarray(mask) != 0
    on = np.zeros(fg.shape, bool)
    on[sk.rows, sk.cols] = True
    padded = np.pad(on, 1)
    deg = sum(
        np.roll(np.roll(padded, dy, 0), dx, 1) for dy in (-1, 0, 1) for dx in (-1, 0, 1) if dy or dx
    )[1:-1, 1:-1]
    ends = np.argwhere(on & (deg == 1))
    return render_overlay(fg, sk.rows, sk.cols, sk.r2, endpoints=ends), sk.endpoints


def _fit(img: np.ndarray, size: int) -> np.ndarray:
    """Pad to a square and resample to ``size`` × ``size``."""
    from PIL import Image

    h, w = img.shape[:2]
    s = max(h, w)
    sq = np.full((s, s, 3), 255, np.uint8)
    sq[(s - h) // 2 : (s - h) // 2 + h, (s - w) // 2 : (s - w) // 2 + w] = img
    # Box filter when shrinking, so that one-pixel skeleton lines stay visible (grey);
    # nearest when enlarging, so that pixels stay sharp.
    how = Image.Resampling.BOX if s > size else Image.Resampling.NEAREST
    return np.asarray(Image.fromarray(sq).resize((size, size), how))


def _grid(
    axes_images: Sequence[Sequence[np.ndarray]],
    row_labels: Sequence[str],
    col_labels: Sequence[str],
    path: Path,
    cell: float = 1.4,
    dpi: int = 100,
    captions: Sequence[Sequence[str]] | None = None,
) -> None:
    plt = _plt()
    nr, nc = len(axes_images), len(axes_images[0])
    # room under each row for its captions, so they do not run into the next row
    extra = 0.2 * nr if captions is not None else 0.0
    fig, axes = plt.subplots(
        nr, nc, figsize=(cell * nc + 0.6, cell * nr + 0.4 + extra), squeeze=False
    )
    for i, row in enumerate(axes_images):
        for j, img in enumerate(row):
            ax = axes[i][j]
            ax.imshow(img, interpolation="nearest")
            ax.set_xticks([])
            ax.set_yticks([])
            if i == 0:
                ax.set_title(col_labels[j], fontsize=8)
            if j == 0:
                ax.set_ylabel(row_labels[i], fontsize=8)
            if captions is not None:
                ax.set_xlabel(captions[i][j], fontsize=7, labelpad=1)
    fig.tight_layout(pad=0.3)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)


def perturbation_figure(
    shapes: Sequence[tuple[str, np.ndarray]],
    perturbed: Sequence[Sequence[tuple[str, np.ndarray]]],
    variant: Variant,
    path: Path,
) -> None:
    """Figs. 6–7: rows = shapes, columns = clean and each perturbation; endpoint counts."""
    rows, caps = [], []
    for (_name, mask), pert in zip(shapes, perturbed, strict=True):
        cells = [overlay(variant, m) for m in [mask, *(m for _, m in pert)]]
        rows.append([_fit(img, 120) for img, _ in cells])
        caps.append([f"{n} endpoints" for _, n in cells])
    cols = ["clean", *(p for p, _ in perturbed[0])]
    _grid(rows, [n for n, _ in shapes], cols, path, cell=1.3, captions=caps)


def methods_figure(
    shapes: Sequence[tuple[str, np.ndarray]], variants: Sequence[str], path: Path
) -> None:
    """The same shapes under every variant, side by side, with endpoint counts."""
    cells = [[overlay(VARIANTS[v], m) for v in variants] for _, m in shapes]
    _grid(
        [[_fit(img, 140) for img, _ in row] for row in cells],
        [n for n, _ in shapes],
        list(variants),
        path,
        cell=1.5,
        captions=[[f"{n} endpoints" for _, n in row] for row in cells],
    )


def rectangles_figure(
    rects: Sequence[tuple[str, np.ndarray]], variants: Sequence[str], path: Path
) -> None:
    """Fig. 9: one rectangle per noise kind (rows) under each variant (columns)."""
    plt = _plt()
    nr, nc = len(rects), len(variants)
    fig, axes = plt.subplots(nr, nc, figsize=(2.4 * nc, 1.2 * nr + 0.3), squeeze=False)
    for i, (noise, m) in enumerate(rects):
        for j, v in enumerate(variants):
            ax = axes[i][j]
            img, n_end = overlay(VARIANTS[v], m)
            ax.imshow(img, interpolation="nearest")
            ax.set_xticks([])
            ax.set_yticks([])
            ax.set_xlabel(f"{n_end} endpoints", fontsize=7, labelpad=1)
            if i == 0:
                ax.set_title(v, fontsize=8)
            if j == 0:
                ax.set_ylabel(noise, fontsize=8)
    fig.tight_layout(pad=0.3)
    fig.savefig(path, dpi=90)
    plt.close(fig)


def curves_figure(shapes: Sequence[tuple[str, np.ndarray]], path: Path) -> None:
    """Fig. 3: AR, LR and λ over the pruning steps (default settings), chosen step marked."""
    from skelprune.api import prune

    plt = _plt()
    n = len(shapes)
    fig, axes = plt.subplots(
        2, n, figsize=(2.8 * n, 5.0), squeeze=False, gridspec_kw={"height_ratios": [1.0, 1.3]}
    )
    for j, (name, mask) in enumerate(shapes):
        res = prune(mask)
        comp = max(res.components, key=lambda c: c.area)
        seq = comp.sequence
        steps = np.arange(len(seq.lost))
        top, ax = axes[0][j], axes[1][j]
        top.imshow(res.render_overlay(), interpolation="nearest")
        top.set_xticks([])
        top.set_yticks([])
        top.set_title(f"{name}: step {comp.chosen_step} of {len(steps) - 1}", fontsize=8)
        alpha = 0.0 if seq.alpha is None else seq.alpha
        ax.plot(steps, alpha * seq.rer, label="α·AR", color="tab:red")
        ax.plot(steps, seq.ss, label="LR = log(Γ+1)", color="tab:blue")
        ax.plot(steps, seq.objective, label="λ = α·AR + LR", color="black")
        ax.axvline(comp.chosen_step, color="tab:green", linestyle="--", linewidth=1)
        ax.plot(
            [comp.chosen_step],
            [seq.objective[comp.chosen_step]],
            "o",
            color="tab:green",
            label="chosen step",
        )
        ax.set_xlabel("pruning step", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.set_title(f"α = {alpha:.1f}", fontsize=8)
        if j == 0:
            ax.legend(fontsize=7, loc="upper left")
    fig.tight_layout(pad=0.4)
    fig.savefig(path, dpi=90)
    plt.close(fig)


def montage_figure(
    shapes: Sequence[tuple[str, np.ndarray]], path: Path, cell: int = 96, columns: int = 12
) -> None:
    """Fig. 11: every shape's default skeleton overlay, with its RER, in one grid."""
    from skelprune.api import prune

    plt = _plt()
    n = len(shapes)
    nr = max(1, -(-n // columns))
    nc = min(columns, max(n, 1))
    canvas = np.full((nr * (cell + 14), nc * cell, 3), 255, np.uint8)
    labels = []
    for k, (name, mask) in enumerate(shapes):
        res = prune(mask)
        area = sum(c.area for c in res.components)
        rer = sum(c.rer * c.area for c in res.components) / area
        r, c = divmod(k, nc)
        y0 = r * (cell + 14) + 14
        canvas[y0 : y0 + cell, c * cell : (c + 1) * cell] = _fit(res.render_overlay(), cell)
        labels.append((c * cell + cell / 2, y0 - 2, f"{name} ({100 * rer:.2f} %)"))
    dpi = 100
    fig = plt.figure(figsize=(canvas.shape[1] / dpi, canvas.shape[0] / dpi), dpi=dpi)
    ax = fig.add_axes((0, 0, 1, 1))
    ax.imshow(canvas, interpolation="nearest")
    for x, y, text in labels:
        ax.text(x, y, text, fontsize=5.5, ha="center", va="bottom")
    ax.set_axis_off()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
