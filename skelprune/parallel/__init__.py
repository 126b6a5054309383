"""Whole data sets on dask.distributed: :func:`prune_many`.

The same pruning as :func:`skelprune.prune`, each input on its own, in tasks spread over a
local cluster of worker processes or any dask cluster (an HPC queue, Kubernetes), with
the results written as they finish (one ``NAME.json`` an input, ``problems.jsonl`` for
those that failed) and a run stopped halfway finishing where it stopped. Needs the
``parallel`` extra (``pip install 'skelprune[parallel]'``); dask is imported only when a
run starts. Guide: ``docs/datasets.md``.
"""

from typing import TYPE_CHECKING

from .._lazy import lazy_exports

if TYPE_CHECKING:
    from .items import Labels
    from .run import Outcome, iter_prune_many, prune_many
    from .store import PROBLEMS_FILE
    from .work import document_bytes

_LAZY = {
    "Labels": "items",
    "Outcome": "run",
    "iter_prune_many": "run",
    "prune_many": "run",
    "PROBLEMS_FILE": "store",
    "document_bytes": "work",
}

__getattr__, __dir__ = lazy_exports(__name__, _LAZY, submodules=True)

__all__ = [
    "PROBLEMS_FILE",
    "Labels",
    "Outcome",
    "document_bytes",
    "iter_prune_many",
    "prune_many",
]
