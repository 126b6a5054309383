"""Speed of the full pipeline, one core, medians over shapes of the best of 3.

The default pipeline (coarse DCE stage) beside ``coarse=None`` (the coarse stage must not
cost much time), on the datasets and, because that is what the stage is for, on every
second kimia216 shape with boundary noise N(0, 1) and scaled by 2. In the same run: bare
``skimage.morphology.skeletonize`` plus a distance transform on the same masks, and the
naive from-scratch oracle on a few small shapes.

``python -m benchmarks library --kimia [--before TREE] [--rounds N] [--clock cpu|wall]``:
only the kimia216 ratio, ``prune()`` + ``to_dict()`` against bare ``skeletonize`` + EDT,
each tree timed in a fresh process of its own (the trees alternated, ``N`` rounds, 3 by
default; CPU time by default): the code of this tree, and with ``--before`` that of
another checkout (the code before a change), in the same run. ``--stages`` adds where the
time goes in this tree: each stage of ``prune()`` timed in CPU time inside the pipeline
(wrappers in its namespace; the indented rows one level down, inside the stages), best of 5
passes over the shapes, ms a shape. ``--axis`` adds the compiled medial axis's stages,
called one by one.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from itertools import pairwise
from pathlib import Path

import numpy as np
from scipy import ndimage
from skimage.morphology import skeletonize

import skelprune
from evaluation.stability import PERTURBATIONS, _rng
from skelprune.api import components
from skelprune.pruning.bayesian import pruning_sequence
from skelprune.skeleton import Skeleton

from .common import dataset, table, upscale


def _each(masks, fns, repeat: int = 3) -> list[list[float]]:
    """ms a shape for each of ``fns``: best of ``repeat``, the functions interleaved shape by
    shape, so that a slow spell of a shared machine falls on all of them alike."""
    out: list[list[float]] = [[] for _ in fns]
    for m in masks:
        best = [np.inf] * len(fns)
        for _ in range(repeat):
            for k, fn in enumerate(fns):
                t = time.perf_counter()
                fn(m)
                best[k] = min(best[k], 1000 * (time.perf_counter() - t))
        for k in range(len(fns)):
            out[k].append(best[k])
    return out


def bare(m: np.ndarray) -> None:
    skeletonize(m)
    ndimage.distance_transform_edt(m)


def full(m: np.ndarray) -> None:
    """The default pipeline (coarse DCE stage, then the Bayesian pruning)."""
    skelprune.prune(m).to_dict()


def from_medial_axis(m: np.ndarray) -> None:
    """``coarse=None``: the Bayesian pruning of the full medial axis."""
    skelprune.prune(m, coarse=None).to_dict()


def _sequence_only(crop, naive: bool) -> float:
    from testkit.oracle import naive_sequence

    medial = Skeleton.medial_axis(crop)
    norm = medial.normalisation(9.0)
    graph = medial.working_graph()  # (the fast sequence copies its own)
    t = time.perf_counter()
    if naive:
        naive_sequence(graph, medial.mask, medial.r2, norm.alpha, norm.lbar)
    else:
        pruning_sequence(medial, norm.alpha, norm.lbar)
    return 1000 * (time.perf_counter() - t)


def main(argv: list[str] | None = None) -> None:
    if argv:
        _kimia_main(argv)
        return
    sets = {"kimia216": dataset("kimia216"), "kimia99": dataset("kimia99")}
    sets["512x512"] = [upscale(m, 512) for m in sets["kimia216"][::17]]
    for name in ("gaussian-1", "scale-2"):
        sets[f"kimia216/2, {name}"] = [
            PERTURBATIONS[name].apply(m, _rng(0, i, name))
            for i, m in enumerate(sets["kimia216"][::2])
        ]
    full(sets["kimia216"][0])  # JIT warm-up (cached on disk after the first run)
    from_medial_axis(sets["kimia216"][0])
    rows = []
    for name, masks in sets.items():
        ours, plain, ref = _each(masks, [full, from_medial_axis, bare])
        rows.append(
            [
                name,
                len(masks),
                float(np.median(ours)),
                float(np.median(plain)),
                float(np.median(np.array(ours) / np.array(plain))),
                float(np.median(ref)),
                float(np.median(ours) / np.median(ref)),
            ]
        )
    print(
        table(
            [
                "shapes",
                "n",
                "default ms (median)",
                "coarse=None ms (median)",
                "default/None (median of ratios)",
                "skeletonize+EDT ms (median)",
                "default/bare",
            ],
            rows,
        )
    )
    small = [crop for m in sets["kimia216"][::34] for crop, _ in components(m)]
    speed = []
    for crop in small:
        fast = min(_sequence_only(crop, False) for _ in range(3))
        slow = _sequence_only(crop, True)
        speed.append(slow / fast)
    rows = [
        [
            "pruning sequence, kimia216",
            len(small),
            float(np.median(speed)),
            float(np.min(speed)),
            float(np.max(speed)),
        ]
    ]
    # The fast sequence is incremental, the oracle repaints every disk for every
    # candidate: the ratio grows with the shape. One larger shape each (the oracle
    # needs seconds there, minutes at 512 px).
    for longest in (200, 256):
        crop = components(upscale(sets["kimia216"][34], longest))[0][0]
        fast = min(_sequence_only(crop, False) for _ in range(3))
        ratio = _sequence_only(crop, True) / fast
        rows.append([f"pruning sequence, one shape at {longest} px", 1, ratio, ratio, ratio])
    print()
    print(table(["oracle comparison", "shapes", "naive/fast (median)", "min", "max"], rows))


# One tree's kimia216 ratio, in a fresh process started in that tree: only the public API,
# so that any version of the code runs it. Best of 3 a shape, the pipeline and the bare
# reference interleaved shape by shape; medians over the shapes. The clock is the wall's
# or the process's CPU time: on a machine shared with more jobs than cores, a 4 ms call
# is nearly always interrupted, a 0.8 ms one seldom, and the wall clock's ratio then
# measures the machine's load.
_KIMIA_RUN = """
import json, sys, time
from pathlib import Path
import numpy as np
from PIL import Image
from scipy import ndimage
from skimage.morphology import skeletonize
import skelprune
paths = sorted(Path(sys.argv[1]).glob("*.png"))
masks = [np.asarray(Image.open(p)) > 0 for p in paths]
skelprune.prune(masks[0]).to_dict()  # the kernels loaded
clock = time.process_time if sys.argv[2] == "cpu" else time.perf_counter
ours, bare = [], []
for m in masks:
    a = b = float("inf")
    for _ in range(3):
        t = clock()
        skelprune.prune(m).to_dict()
        a = min(a, clock() - t)
        t = clock()
        skeletonize(m)
        ndimage.distance_transform_edt(m)
        b = min(b, clock() - t)
    ours.append(1000 * a)
    bare.append(1000 * b)
print(json.dumps({"ours": float(np.median(ours)), "bare": float(np.median(bare)),
                  "file": skelprune.__file__}))
"""


def _kimia_once(tree: Path, data: Path, clock: str) -> dict[str, float]:
    """The kimia216 medians of the code in ``tree``, from a fresh process, on ``clock``
    (``"cpu"`` or ``"wall"``)."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    out = subprocess.run(
        [sys.executable, "-c", _KIMIA_RUN, str(data), clock],
        cwd=tree,
        env=env,
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    answer: dict[str, float] = json.loads(out.strip().splitlines()[-1])
    return answer


def _kimia_main(argv: list[str]) -> None:
    parser = argparse.ArgumentParser(prog="python -m benchmarks library")
    parser.add_argument("--kimia", action="store_true", help="the kimia216 ratio alone")
    parser.add_argument("--before", type=Path, help="another checkout, timed alike")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--clock", choices=("cpu", "wall"), default="cpu")
    parser.add_argument("--stages", action="store_true", help="this tree's stage profile")
    parser.add_argument("--axis", action="store_true", help="the compiled axis's stages")
    args = parser.parse_args(argv)
    from testkit import DATA, REPO

    if args.axis:
        print(_axis_stages(dataset("kimia216")))
        print()

    data = DATA / "kimia216"
    trees = [("after (this tree)", REPO)]
    if args.before is not None:
        trees.insert(0, ("before (" + str(args.before) + ")", args.before.resolve()))
    runs: dict[str, list[dict[str, float]]] = {label: [] for label, _ in trees}
    for _ in range(args.rounds):
        for label, tree in trees:
            runs[label].append(_kimia_once(tree, data, args.clock))
    rows = []
    for label, _ in trees:
        got = runs[label]
        ratios = [r["ours"] / r["bare"] for r in got]
        rows.append(
            [
                label,
                float(np.median([r["ours"] for r in got])),
                float(np.median([r["bare"] for r in got])),
                ", ".join(f"{x:.2f}" for x in ratios),
                float(np.median(ratios)),
            ]
        )
    print(
        table(
            [
                "code",
                f"kimia216 ms ({args.clock}, median of rounds)",
                "bare ms",
                "kimia216 / bare, each round",
                "median ratio",
            ],
            rows,
        )
    )
    if args.stages:
        print()
        print(_stages(dataset("kimia216")))


def _stages(masks: list[np.ndarray], passes: int = 5) -> str:
    """Each stage of ``prune()`` + ``to_dict()`` in CPU time, ms a shape (best of
    ``passes``): wrappers around the names the pipeline calls them by."""
    import gc

    import skelprune.pipeline as pipeline
    import skelprune.skeleton as skeleton
    from skelprune.output.document import PruneResult
    from skelprune.pruning.bayesian import PruningSequence

    spent: dict[str, float] = {}

    def wrapped(owner: object, name: str, label: str) -> None:
        inner = getattr(owner, name, None)
        if inner is None:  # (a stage the pipeline no longer calls by that name)
            return

        def timed(*a: object, **k: object) -> object:
            t = time.process_time()
            try:
                return inner(*a, **k)
            finally:
                spent[label] = spent.get(label, 0.0) + time.process_time() - t

        setattr(owner, name, timed)

    wrapped(skeleton, "oriented", "medial axis: canonical orientation")
    wrapped(skeleton, "squared_distance", "medial axis: EDT")
    wrapped(skeleton, "oriented_medial_axis", "medial axis: the compiled axis")
    wrapped(skeleton, "BranchGraph", "medial axis: branch graph")
    wrapped(pipeline.Skeleton, "normalisation", "normalisation (α, ℓ̄)")
    wrapped(pipeline, "pruning_sequence", "pruning sequence")
    wrapped(pipeline, "chosen_step", "choice (noise floor)")
    wrapped(PruningSequence, "skeleton_at", "the chosen skeleton (replay)")
    wrapped(pipeline, "trim_tips", "tips' cut")
    wrapped(pipeline, "branch_margins", "margins")
    wrapped(pipeline, "prune_component", "prune_component (all of the above and more)")
    wrapped(PruneResult, "to_dict", "to_dict()")
    # one level down (inside the stages above)
    import skelprune.grid.coverage as coverage
    import skelprune.grid.graph as graph
    import skelprune.grid.limbs as limbs

    wrapped(coverage.Coverage, "__init__", "  sequence: coverage set-up")
    wrapped(coverage.Coverage, "remove_label", "  sequence: coverage removals")
    wrapped(coverage.Coverage, "merge_label", "  sequence: coverage merges")
    wrapped(limbs.LimbGuard, "__init__", "  sequence: limb guard set-up")
    wrapped(limbs.LimbGuard, "is_limb", "  sequence: limb tests")
    wrapped(graph.BranchGraph, "remove_end_branch", "  graph removals (every stage)")
    wrapped(graph.BranchGraph, "copy", "  graph copies (every stage)")
    wrapped(skeleton.Skeleton, "lost_along", "  choice: grown disks' losses (lost_along)")
    skelprune.prune(masks[0]).to_dict()
    gc.freeze()  # (no collection of the warm-up's garbage inside a stage)
    best: dict[str, float] = {}
    for _ in range(passes):
        spent.clear()
        t = time.process_time()
        for m in masks:
            skelprune.prune(m).to_dict()
        spent["total: prune() + to_dict()"] = time.process_time() - t
        for k, v in spent.items():
            best[k] = min(best.get(k, np.inf), v)
    rows = [[k, 1000 * v / len(masks)] for k, v in best.items()]
    return table(["stage (CPU time)", "ms a shape, best of passes"], rows)


def _axis_stages(masks: list[np.ndarray], passes: int = 7) -> str:
    """The compiled medial axis's stages called one by one on every component, in its
    canonical orientation, CPU time, ms a shape (best of ``passes``), and the fused call."""
    import skelprune.grid.medial_axis as ma
    from skelprune.grid import oriented
    from skelprune.grid._last_cover import drop_redundant_anchors
    from skelprune.grid._maximal_disks import VECTOR_KIND, VECTORS, _anchors, _domination_table

    crops = []
    for m in masks:
        for crop, _ in components(m):
            shape = np.ascontiguousarray(oriented(crop)[0])
            crops.append((shape, ma.squared_distance(shape)))
    best: dict[str, float] = {}
    for _ in range(passes):
        spent: dict[str, float] = {}
        for shape, r2 in crops:
            stamps: list[tuple[str, float]] = [("", time.process_time())]
            need = _domination_table(r2)
            stamps.append(("domination table", time.process_time()))
            anchor = _anchors(r2, need, VECTORS, VECTOR_KIND)
            stamps.append(("anchors (centres of maximal disks)", time.process_time()))
            ar, ac = ma._by_radius(anchor, r2)
            stamps.append(("anchors by radius", time.process_time()))
            drop_redundant_anchors(anchor, r2, ar, ac)
            stamps.append(("redundant anchors", time.process_time()))
            fg = shape.copy()
            ma._ordered_thinning(fg, r2, anchor, ma.SIMPLE)
            stamps.append(("distance-ordered thinning", time.process_time()))
            rows, cols = ma._by_radius(fg, r2)
            stamps.append(("pixels by radius", time.process_time()))
            heights = float(np.sum(2.0 * np.sqrt(r2[rows, cols].astype(float)) + 1.0))
            # (the rule of the code measured: older code capped from heights of 1× the pixels)
            cap = ma._FIRST_CAP if heights > getattr(ma, "_CAPPED_HEIGHTS", 1.0) * r2.size else 0
            stamps.append(("", time.process_time()))  # (numpy here, not the kernel's loop)
            ma._thin(fg, r2, rows, cols, ma.SIMPLE, ma.DEGREE, cap)
            stamps.append(("thinning pass", time.process_time()))
            ma._extend_ends(fg, r2, ma.DEGREE)
            stamps.append(("ends extended", time.process_time()))
            ma._axis_pixels(shape, r2, need, VECTORS, VECTOR_KIND, ma.SIMPLE, ma.DEGREE)
            stamps.append(("all of it, one compiled call", time.process_time()))
            for (_, before), (label, after) in pairwise(stamps):
                if label:
                    spent[label] = spent.get(label, 0.0) + after - before
        for k, v in spent.items():
            best[k] = min(best.get(k, np.inf), v)
    rows_out = [[k, 1000 * v / len(crops)] for k, v in best.items()]
    return table(["compiled medial axis, stage (CPU time)", "ms a shape, best of passes"], rows_out)
