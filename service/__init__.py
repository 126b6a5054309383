"""skelprune REST service: FastAPI app, worker pool, problem+json errors.

Start it with ``python -m service``; build the app in code with
:func:`service.app.create_app`.
"""

from __future__ import annotations

from importlib.metadata import version

__all__ = ["__version__"]

#: The installed distribution's version (written once, in ``skelprune/_version.py``).
#: Read from the package metadata, not by importing skelprune: ``python -m service``
#: binds its port and seeds the numba cache before the library is imported.
__version__ = version("skelprune")
