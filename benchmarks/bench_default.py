"""Every kind of input users send, against its peers, in one table: the benchmark the
default options are chosen on (:mod:`benchmarks.default_suite`; docs/default.md).

``python -m benchmarks default [--data DIR] [--options JSON] [--only GROUPS] [--quick]``.
"""

from __future__ import annotations

import sys

from .default_suite import main

__all__ = ["main"]

if __name__ == "__main__":
    main(sys.argv[1:])
