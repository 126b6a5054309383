"""The Processing provider ``skelprune``."""

from __future__ import annotations

from qgis.core import QgsProcessingProvider

from .algorithms import CenterlinesAlgorithm, RasterlinesAlgorithm


class SkelpruneProvider(QgsProcessingProvider):
    def id(self) -> str:
        return "skelprune"

    def name(self) -> str:
        return "skelprune"

    def longName(self) -> str:
        return "skelprune: parameter-free skeleton pruning"

    def loadAlgorithms(self) -> None:
        self.addAlgorithm(CenterlinesAlgorithm())
        self.addAlgorithm(RasterlinesAlgorithm())
