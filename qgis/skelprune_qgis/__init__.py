"""A QGIS plugin with the skelprune Processing provider (``skelprune:centerlines``,
``skelprune:rasterlines``).

The algorithms run the skelprune library installed in a Python environment of its own,
as its command line (``python -m skelprune.cli``), in a process of its own: QGIS's
process already holds its own GEOS, PROJ and GDAL, whose symbols would shadow the copies
bundled with shapely, pyproj and pyogrio if the library were imported into it. Which
Python that is comes from the environment variable ``SKELPRUNE_PYTHON``, else the QGIS
setting ``skelprune/python`` (docs/qgis.md).
"""

from __future__ import annotations

from typing import Any


class SkelprunePlugin:
    """Registers the provider; in the desktop and in ``qgis_process`` alike."""

    def __init__(self, iface: Any = None) -> None:
        self.iface = iface
        self.provider: Any = None

    def initProcessing(self) -> None:
        from qgis.core import QgsApplication

        from .provider import SkelpruneProvider

        self.provider = SkelpruneProvider()
        QgsApplication.processingRegistry().addProvider(self.provider)

    def initGui(self) -> None:
        self.initProcessing()

    def unload(self) -> None:
        from qgis.core import QgsApplication

        if self.provider is not None:
            QgsApplication.processingRegistry().removeProvider(self.provider)


def classFactory(iface: Any) -> SkelprunePlugin:
    """QGIS's entry point."""
    return SkelprunePlugin(iface)
