"""Write the documents of every dataset shape to a folder, to compare two trees byte for byte.

``python -m testkit.snapshot OUT [--quick]`` writes one JSON file per shape and option set
(default options, ``coarse=None``, ``method="dce"``), the overlay PNG of a few shapes and the
GeoJSON of ``examples/shape.geojson``. Run it before and after a change that should not
move any output, then ``diff -r BEFORE AFTER`` (fields a change adds on purpose are
expected in the diff; anything else is a regression).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from PIL import Image

import skelprune
from skelprune.io.polygon import polygon_mask
from testkit import DATA, REPO

OPTION_SETS = {"default": {}, "full": {"coarse": None}, "dce": {"method": "dce"}}
DATASETS = ("kimia216", "kimia99", "skelneton-dev/shapes")


def _mask(path: Path) -> np.ndarray:
    return np.asarray(Image.open(path).convert("L")) >= 128


def write_snapshot(out: Path, quick: bool = False, **extra: object) -> int:
    """Write every document below ``out``; return how many files were written.

    ``extra`` options go to every ``prune`` call (``trim=False, min_margin=0``: the
    paper's answers, untrimmed, as the library gave them before either option).
    """
    out.mkdir(parents=True, exist_ok=True)
    written = 0
    for dataset in DATASETS:
        paths = sorted((DATA / dataset).glob("*.png"))
        if quick:
            paths = paths[::10]
        for path in paths:
            mask = _mask(path)
            for label, options in OPTION_SETS.items():
                kw = {**options, **extra}
                if options.get("method") == "dce":  # neither applies to DCE pruning
                    kw.pop("min_margin", None)
                    kw.pop("trim", None)
                doc = skelprune.prune(mask, **kw).to_dict()
                name = f"{dataset.replace('/', '_')}__{path.stem}__{label}.json"
                (out / name).write_text(json.dumps(doc, sort_keys=True))
                written += 1
    for path in sorted(DATA.glob("kimia216/*.png"))[:: 40 if quick else 8]:
        res = skelprune.prune(_mask(path), **extra)
        (out / f"overlay__{path.stem}.png").write_bytes(res.overlay_png())
        written += 1
    polygon = json.loads((REPO / "examples" / "shape.geojson").read_text())
    for side in (64, 256):
        # the raster's mask and frame without the polygon: lines as the pixels give them
        mask, frame = polygon_mask(polygon, longest_side=side)
        geo = skelprune.prune(skelprune.Input(mask, frame), **extra).to_geojson()
        (out / f"examples_shape__{side}.geojson").write_text(json.dumps(geo, sort_keys=True))
        written += 1
    return written


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--quick", action="store_true", help="every tenth shape only")
    parser.add_argument(
        "--no-trim", action="store_true", help="prune with trim=False (the untrimmed answers)"
    )
    parser.add_argument(
        "--argmin", action="store_true", help="prune with min_margin=0 (the paper's argmin)"
    )
    args = parser.parse_args()
    parser_extra = {}
    if args.no_trim:
        parser_extra["trim"] = False
    if args.argmin:
        parser_extra["min_margin"] = 0.0
    extra = parser_extra
    print(f"{write_snapshot(args.out, args.quick, **extra)} documents in {args.out}")


if __name__ == "__main__":
    main()
