"""skelprune REST service: FastAPI app, worker pool, problem+json errors.

Start it with ``python -m service``; build the app in code with
:func:`service.app.create_app`.
"""

from __future__ import annotations

from skelprune import __version__

__all__ = ["__version__"]
