"""Write the documents of a fixed set of volumes to a folder, to compare two trees byte
for byte (the volume side of :mod:`testkit.snapshot`).

``python -m testkit.volume_snapshot OUT [--quick]``: per volume, its JSON document,
branch table (CSV) and SWC, at the default options and at ``trim=False, min_margin=0``:
synthetic trees on an isotropic and a 1:1:3 grid (clean and noisy), random blobs, and
label volumes of touching trees. Run before and after a change that should not move
any output, then ``diff -r BEFORE AFTER``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

import skelprune
from testkit.volumes import random_blobs, random_tree, touching_trees

OPTION_SETS = {"default": {}, "paper": {"trim": False, "min_margin": 0}}


def volumes(quick: bool = False) -> dict[str, tuple[np.ndarray, tuple[float, float, float]]]:
    """The volumes of the snapshot, by name, with their spacing."""
    out: dict[str, tuple[np.ndarray, tuple[float, float, float]]] = {}
    seeds = range(2) if quick else range(4)
    for seed in seeds:
        for grid, sp in {"iso": (1.0, 1.0, 1.0), "z3": (3.0, 1.0, 1.0)}.items():
            tree = random_tree(seed, 64 if quick else 96, sp)
            out[f"tree{seed}-{grid}"] = (tree.volume(), sp)
            out[f"tree{seed}-{grid}-noisy"] = (tree.volume(0.7, seed=seed), sp)
    for seed in range(4 if quick else 12):
        out[f"blobs{seed}"] = (random_blobs(seed), (1.0, 1.0, 1.0))
    labels = touching_trees(12 if quick else 40, 64 if quick else 96, seed=1).labels
    out["labels-iso"] = (labels, (1.0, 1.0, 1.0))
    out["labels-aniso"] = (labels, (1.5, 1.0, 0.7))
    return out


def write_snapshot(out: Path, quick: bool = False) -> int:
    """Write every file below ``out``; return how many were written."""
    out.mkdir(parents=True, exist_ok=True)
    written = 0
    for name, (volume, spacing) in volumes(quick).items():
        for opt_name, opts in OPTION_SETS.items():
            res = skelprune.prune(volume, spacing=spacing, **opts)
            stem = out / f"{name}.{opt_name}"
            Path(f"{stem}.json").write_text(json.dumps(res.to_dict(), sort_keys=True, indent=1))
            Path(f"{stem}.csv").write_text(res.to_csv())
            Path(f"{stem}.swc").write_text(res.to_swc())
            written += 3
    return written


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("out", type=Path)
    p.add_argument("--quick", action="store_true")
    a = p.parse_args()
    print(write_snapshot(a.out, a.quick), "files written to", a.out)


if __name__ == "__main__":
    main()
