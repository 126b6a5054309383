"""Limbs on blobs, round ends and ground truth at once: which tip rule to trim with.

For the default (tips trimmed under the ``reach`` rule), ``trim=false``, and the other
rules of :data:`skelprune.grid.tips.RULES` (``area``; ``none``: the trade-off alone,
which cuts whole limbs), side by side:

* **limbs**: 300 seeded blobs of :mod:`testkit.limbs` (ellipse, circle, wavy cell,
  small soma with thin neurites, fruit with a stem; 1–5 straight or slightly bent
  limbs of several widths and lengths beyond the body, some close beside another).
  A limb is *kept* when the skeleton reaches into it, beyond the body, by at least half
  its length beyond the body. Reported: the share of limbs kept, the limbs the trim cut
  (kept by ``trim=false``, not by the variant), and the share of shapes with RER > 4 %;
* **round ends**: the drawn lollipop, dumbbell and stick figure at scales 1, 1.5 and 2,
  and 60 seeded lollipops and dumbbells (:func:`testkit.limbs.round_ended`): the share
  of round ends whose nearest endpoint lies within a quarter of the disc's radius of its
  centre;
* **dataset ends**: on every kimia216 shape and every SkelNetOn dev shape, the median
  radius at the skeleton's endpoints and the share of endpoints on the boundary's rim
  (squared radius ≤ 2: a tip left at the boundary);
* **ground truth**: mean F1 of skeleton pixels at 2 px on ``data/skelneton-dev``
  (as :mod:`evaluation.groundtruth` measures it).

``python -m benchmarks limbs`` (a few minutes on one core);
``python -m benchmarks.bench_limbs --figure`` draws ``docs/figures/limbs.png`` instead.
"""

from __future__ import annotations

import io
import sys
import time
from collections import defaultdict
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

import skelprune
from evaluation.groundtruth import TOLERANCES, pixel_scores
from evaluation.stability import load_dataset
from skelprune.grid import tips
from testkit.limbs import BODIES, limb_reach, limb_shapes, round_ended
from testkit.shapes import DRAWN

from .common import DATA, table

FIGURE = Path(__file__).resolve().parents[1] / "docs" / "figures" / "limbs.png"
#: Blobs of the figure: (seed, body) of :func:`testkit.limbs.limb_shape`.
FIGURE_SHAPES = ((56, "circle"), (0, "ellipse"), (24, "fruit"), (100, "ellipse"))

#: name -> (tip rule, options of :func:`skelprune.prune`)
VARIANTS: dict[str, tuple[str, dict[str, Any]]] = {
    "default (both)": ("both", {}),
    "trim=false": ("both", {"trim": False}),
    "reach": ("reach", {}),
    "area": ("area", {}),
    "disk": ("disk", {}),
    "none (trade-off alone)": ("none", {}),
}
SHAPES = 300
#: The drawn shapes' discs: (row, col, radius) at scale 1 (testkit/shapes.py).
DRAWN_DISCS = {
    "lollipop": [(30.4, 104.7, 22.3)],
    "dumbbell": [(35.3, 32.6, 25.2), (38.7, 137.2, 24.6)],
    "stick_figure": [(32.3, 70.6, 22.4)],
}


@contextmanager
def rule(name: str) -> Iterator[None]:
    before = tips.RULE
    tips.RULE = name
    try:
        yield
    finally:
        tips.RULE = before


def _endpoints(res: skelprune.PruneResult) -> np.ndarray:
    out = []
    for comp in res.to_dict(curve=False)["components"]:
        out += [(n["y"], n["x"]) for n in comp["skeleton"]["nodes"] if n["kind"] == "endpoint"]
    return np.asarray(out, float).reshape(-1, 2)


def _limbs(shapes, options) -> dict[str, Any]:
    kept, rer_high, rers = [], 0, []
    per_body: dict[str, list[bool]] = defaultdict(list)
    for s in shapes:
        res = skelprune.prune(s.mask, **options)
        rows, cols, _ = res.skeleton_points()
        rer = res.components[0].rer
        rers.append(rer)
        rer_high += rer > 0.04
        for lb in s.limbs:
            ok = limb_reach(lb, s.body, rows, cols) >= 0.5 * lb.length
            kept.append(ok)
            per_body[s.name.split("-")[0]].append(ok)
    return {
        "kept": np.asarray(kept),
        "rer_high": rer_high,
        "rer": float(np.median(rers)),
        "per_body": per_body,
    }


def _round_ends(options) -> tuple[int, int]:
    cases = []
    for name, draw in DRAWN.items():
        for scale in (1.0, 1.5, 2.0):
            discs = [(y * scale, x * scale, r * scale) for y, x, r in DRAWN_DISCS[name]]
            cases.append((draw(scale), discs))
    cases += [round_ended(seed) for seed in range(60)]
    good = total = 0
    for mask, discs in cases:
        ends = _endpoints(skelprune.prune(mask, **options))
        for cy, cx, r in discs:
            total += 1
            good += bool(len(ends)) and np.hypot(*(ends - (cy, cx)).T).min() < 0.25 * r
    return good, total


def _dataset_ends(masks, options) -> tuple[float, float]:
    radii = []
    for mask in masks:
        res = skelprune.prune(mask, **options)
        for comp in res.components:
            sk = comp.skeleton
            ends = [sk.graph.free_end_point(b, e) for b, e in sk.graph.free_ends()]
            radii += sk.r2[ends].tolist()
    r2 = np.asarray(radii, float)
    return float(np.median(np.sqrt(r2))), float(np.mean(r2 <= 2))


def _ground_truth(folder, options) -> float:
    from PIL import Image

    i = TOLERANCES.index(2)
    f1 = []
    for path in sorted((folder / "shapes").glob("*.png")):
        mask = np.asarray(Image.open(path).convert("L")) >= 128
        gt = np.asarray(Image.open(folder / "skeletons" / path.name).convert("L")) >= 128
        rows, cols, _ = skelprune.prune(mask, **options).skeleton_points()
        ours = np.zeros(mask.shape, bool)
        ours[rows, cols] = True
        f1.append(pixel_scores(ours, gt)[i, 2])
    return float(np.mean(f1))


def main() -> None:
    t = time.perf_counter()
    shapes = limb_shapes(SHAPES)
    masks = [m for _, m in load_dataset(DATA / "kimia216")]
    masks += [m for _, m in load_dataset(DATA / "skelneton-dev/shapes")]
    runs = {}
    for name, (rule_name, options) in VARIANTS.items():
        with rule(rule_name):
            runs[name] = (
                _limbs(shapes, options),
                _round_ends(options),
                _dataset_ends(masks, options),
                _ground_truth(DATA / "skelneton-dev", options),
            )
    whole = runs["trim=false"][0]["kept"]
    n_limbs = whole.size
    rows = []
    for name, (limbs, (good, total), (end_r, rim), f1) in runs.items():
        kept = limbs["kept"]
        rows.append(
            [
                name,
                f"{100 * kept.mean():.1f} %",
                f"{int((whole & ~kept).sum())} ({100 * (whole & ~kept).sum() / n_limbs:.1f} %)",
                f"{100 * limbs['rer_high'] / len(shapes):.1f} %",
                f"{100 * limbs['rer']:.2f} %",
                f"{good}/{total}",
                f"{end_r:.1f} px / {100 * rim:.0f} %",
                f"{f1:.3f}",
            ]
        )
    print(
        f"{len(shapes)} blobs with {n_limbs} limbs; {len(masks)} dataset shapes; "
        f"SkelNetOn dev ground truth\n"
    )
    print(
        table(
            [
                "variant",
                "limbs kept",
                "limbs cut by the trim",
                "RER > 4 %",
                "median RER (blobs)",
                "round ends at centre",
                "dataset ends: median radius / on the rim",
                "F1 at 2 px",
            ],
            rows,
        )
    )
    print("\nlimbs kept per body\n")
    print(
        table(
            ["variant", *BODIES],
            [
                [
                    name,
                    *(
                        f"{100 * np.mean(runs[name][0]['per_body'][b]):.0f} % "
                        f"of {len(runs[name][0]['per_body'][b])}"
                        for b in BODIES
                    ),
                ]
                for name in runs
            ],
        )
    )
    print(f"\n{time.perf_counter() - t:.0f} s")


def figure() -> None:
    """Blobs with limbs: ``trim=false``, the trade-off alone, the default (columns)."""
    from PIL import Image, ImageDraw

    from testkit.limbs import limb_shape

    columns = (
        ("trim=false", "both", {"trim": False}),
        ("trade-off alone", "none", {}),
        ("default (remnants only)", "both", {}),
    )
    rows = []
    for seed, body in FIGURE_SHAPES:
        mask = limb_shape(seed, body).mask
        tiles = []
        for title, rule_name, options in columns:
            with rule(rule_name):
                png = skelprune.prune(mask, **options).overlay_png(scale=2, legend=True)
            tile = Image.open(io.BytesIO(png)).convert("RGB")
            head = Image.new("RGB", (tile.width, 16), "white")
            ImageDraw.Draw(head).text((4, 2), title, fill="black")
            both = Image.new("RGB", (tile.width, tile.height + 16), "white")
            both.paste(head, (0, 0))
            both.paste(tile, (0, 16))
            tiles.append(both)
        rows.append(tiles)
    width = sum(max(r[i].width for r in rows) + 8 for i in range(len(columns)))
    height = sum(max(t.height for t in r) + 8 for r in rows)
    out = Image.new("RGB", (width, height), "white")
    y = 0
    for r in rows:
        x = 0
        for i, t in enumerate(r):
            out.paste(t, (x, y))
            x += max(rr[i].width for rr in rows) + 8
        y += max(t.height for t in r) + 8
    out.save(FIGURE)
    print(f"wrote {FIGURE}")


if __name__ == "__main__":
    figure() if "--figure" in sys.argv[1:] else main()
