"""``python -m service.compile``: compile every numba kernel into numba's cache now
(:mod:`service.worker.compile`; ``make setup`` and the image build run it)."""

from __future__ import annotations

from service.worker.compile import main

if __name__ == "__main__":
    main()
