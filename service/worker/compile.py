"""Compile every numba kernel into numba's cache now (``python -m service.compile``).

``make setup`` and the image build run it, so that neither a first request nor a new
worker waits for the JIT: they load compiled code (under a second) instead of compiling
it (half a minute to a minute on one core). The cache goes to ``NUMBA_CACHE_DIR``, or next to
the library's sources when that is unset; it is valid for the CPU named by
``NUMBA_CPU_NAME`` (``generic``: any x86-64) or, unset, for this host's CPU.
"""

from __future__ import annotations

import os

from service.worker.jobs import warmup


def main() -> None:
    import numba

    where = os.environ.get("NUMBA_CACHE_DIR") or "the library's __pycache__"
    cpu = numba.config.CPU_NAME or "this host's CPU"
    print(f"skelprune: {warmup()} (cache: {where}; target: {cpu})", flush=True)


if __name__ == "__main__":
    main()
