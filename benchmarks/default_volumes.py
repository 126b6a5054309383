"""Volume rows of ``python -m benchmarks default``: branching tubes and voxelized neurons.

Each shape is a :class:`testkit.volumes.SweptShape` with known centre lines and tips:
random trees (:func:`testkit.volumes.random_tree`, 128 voxels a side) and navis's example
neurons drawn from their radii (:func:`testkit.neurons.example_neurons`). Each is
measured clean and on copies with voxel-rough surfaces (surface noise of standard
deviation :data:`NOISE` voxels), by skelprune at the run's options and its peers
(kimimaro, skan cut at 5 and 10 voxels; :mod:`benchmarks.volume_methods`), all read by
:func:`benchmarks.volume_methods.scores`:

- F1 of the skeleton voxels within 2 voxels of the true centre lines (mean), clean and
  rough; tips found of the true tips, clean and rough; spurs on the rough copies (end
  points near no true tip);
- the end-count change from the clean copy to each rough one, ``|n_rough − n_clean| /
  n_clean``, mean: how steady the answer is under surface noise.

Targets: F1 and tips found at least the best peer's, spurs and the end-count change at
most the best peer's.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .default_suite import Context, Group, Job, Row

__all__ = ["GROUPS", "measure_volume", "volume_rows"]

#: Standard deviation of the surface noise of the rough copies (voxels).
NOISE = 0.7
PEERS = ("kimimaro", "skan 5", "skan 10")
TREES, TREES_QUICK = 6, 2
COPIES, COPIES_QUICK = 2, 1


def skelprune_volume(volume: np.ndarray, spacing: Any, options: dict[str, Any]) -> np.ndarray:
    """:func:`skelprune.prune` of a volume at ``options``: its kept skeleton voxels."""
    from .volume_methods import pruned

    return pruned(volume, spacing, **options)


def measure_volume(
    truth: Any, options: dict[str, Any], copies: int, seed: int, peers: Sequence[str] = PEERS
) -> dict[str, dict[str, list[float]]]:
    """skelprune's and every peer's scores on the clean volume (``clean ...``) and on
    ``copies`` rough ones (``rough ...``), and the end counts on each."""
    from .volume_methods import METHODS, scores

    methods = {
        "skelprune": lambda v, sp: skelprune_volume(v, sp, options),
        **{m: METHODS[m] for m in peers},
    }
    volumes = [("clean", truth.volume())]
    volumes += [("rough", truth.volume(NOISE, seed=1000 * seed + k)) for k in range(copies)]
    out: dict[str, dict[str, list[float]]] = {m: {} for m in methods}
    for surface, volume in volumes:
        for name, method in methods.items():
            got = scores(method(volume, truth.spacing), truth)
            for key, value in got.items():
                out[name].setdefault(f"{surface} {key}", []).append(float(value))
    return out


def volume_rows(dataset: str, results: list[dict[str, dict[str, list[float]]]]) -> list[Row]:
    """The volume rows of one data set from :func:`measure_volume`'s results."""
    methods = list(results[0])
    peers = methods[1:]

    def values(m: str, key: str) -> list[float]:
        return [v for r in results for v in r[m][key]]

    def f1(surface: str) -> dict[str, float]:
        return {m: float(np.mean(values(m, f"{surface} f1"))) for m in methods}

    def tips(surface: str) -> dict[str, float]:
        return {m: float(np.sum(values(m, f"{surface} tips found"))) for m in methods}

    true_tips = {s: int(np.sum(values("skelprune", f"{s} true tips"))) for s in ("clean", "rough")}
    spurs = {m: float(np.sum(values(m, "rough spurs"))) for m in methods}
    change = {}
    for m in methods:
        steps = []
        for r in results:
            clean = r[m]["clean endpoints"][0]
            steps += [abs(n - clean) / max(clean, 1) for n in r[m]["rough endpoints"]]
        change[m] = float(np.mean(steps))

    def row(metric: str, got: dict[str, float], fmt: Any, higher: bool) -> Row:
        best = (max if higher else min)(got[m] for m in peers)
        ok = got["skelprune"] >= best if higher else got["skelprune"] <= best
        return Row(
            f"{dataset} ({len(results)})",
            metric,
            fmt(got["skelprune"]),
            " · ".join(f"{m} {fmt(got[m])}" for m in peers),
            "≥ best peer" if higher else "≤ best peer",
            bool(ok),
            got,
        )

    def of(surface: str) -> Any:
        return lambda v: f"{v:.0f}/{true_tips[surface]}"

    return [
        row("F1 at 2 voxels, clean", f1("clean"), lambda v: f"{v:.3f}", True),
        row(f"F1 at 2 voxels, rough ({NOISE:g})", f1("rough"), lambda v: f"{v:.3f}", True),
        row("tips found, clean", tips("clean"), of("clean"), True),
        row(f"tips found, rough ({NOISE:g})", tips("rough"), of("rough"), True),
        row(f"spurs, rough ({NOISE:g})", spurs, lambda v: f"{v:.0f}", False),
        row("end-count change clean → rough", change, lambda v: f"{100 * v:.1f} %", False),
    ]


def _tree_job(seed: int, copies: int, options: dict[str, Any]) -> Any:
    from testkit.volumes import random_tree

    return measure_volume(random_tree(seed, 128), options, copies, seed)


def _tree_jobs(ctx: Context) -> list[Job]:
    n, copies = (TREES_QUICK, COPIES_QUICK) if ctx.quick else (TREES, COPIES)
    return [(_tree_job, (seed, copies, ctx.options)) for seed in range(n)]


def _tree_rows(ctx: Context, results: list[Any]) -> list[Row]:
    return volume_rows("branching tubes 128³", results)


def _neuron_job(index: int, side: int, copies: int, options: dict[str, Any]) -> Any:
    from testkit.neurons import example_neurons

    _name, truth = example_neurons(side)[index]
    return measure_volume(truth, options, copies, index)


def _neuron_count() -> int:
    import navis

    return len(navis.example_neurons())


def _neuron_jobs(ctx: Context) -> list[Job]:
    side = 160 if ctx.quick else 256
    copies = COPIES_QUICK if ctx.quick else COPIES
    n = 2 if ctx.quick else _neuron_count()
    return [(_neuron_job, (i, side, copies, ctx.options)) for i in range(n)]


def _neuron_rows(ctx: Context, results: list[Any]) -> list[Row]:
    side = 160 if ctx.quick else 256
    return volume_rows(f"navis example neurons ≤ {side}³", results)


def _neurons_available(ctx: Context) -> str | None:
    try:
        import navis  # noqa: F401
    except ImportError:
        return "needs navis (the bench extra)"
    return None


GROUPS = (
    Group("trees", _tree_jobs, _tree_rows),
    Group("neurons", _neuron_jobs, _neuron_rows, _neurons_available),
)
