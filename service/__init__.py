"""skelprune REST service: FastAPI app, worker pool, problem+json errors.

Start it with ``python -m service``; build the app in code with
:func:`service.app.create_app`.
"""

from __future__ import annotations

__all__ = ["__version__"]

__version__ = "0.1.0"
