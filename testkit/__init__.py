"""Support shared by the tests and the benchmarks; not part of the shipped package.

- :data:`REPO`: the repository's root;
- :data:`DATA`: the datasets (``$SKELPRUNE_DATA``, else the repository's ``data/``), the
  one place tests and benchmarks take the path from;
- :mod:`.oracle`: the naive from-scratch pruning that the fast code must equal;
- :mod:`.shapes`: synthetic shapes (holes, several components, border contact);
- :mod:`.realserver`: ``python -m service`` started as a user starts it, on 127.0.0.1.
"""

from pathlib import Path

from evaluation.run import default_data_dir

#: The repository's root folder.
REPO = Path(__file__).resolve().parents[1]
DATA = default_data_dir()

__all__ = ["DATA", "REPO"]
