"""The figure of docs/qgis.md: polygons and the lines skelprune:centerlines made of them,
drawn by QGIS's own map renderer. Run with QGIS's Python:

    /usr/bin/python3 tests/frontends/qgis_figure.py POLYGONS LINES OUT.png
"""

from __future__ import annotations

import sys


def main(polygons: str, lines: str, out: str) -> None:
    # QGIS's Python only (not the project's .venv, whose tests import this file)
    from qgis.core import (
        QgsApplication,
        QgsFillSymbol,
        QgsLineSymbol,
        QgsMapRendererParallelJob,
        QgsMapSettings,
        QgsVectorLayer,
    )
    from qgis.PyQt.QtCore import QSize
    from qgis.PyQt.QtGui import QColor

    app = QgsApplication([], False)
    app.initQgis()
    shape = QgsVectorLayer(polygons, "polygons", "ogr")
    answer = QgsVectorLayer(lines, "lines", "ogr")
    shape.renderer().setSymbol(
        QgsFillSymbol.createSimple(
            {"color": "170,205,235", "outline_color": "60,100,140", "outline_width": "0.3"}
        )
    )
    answer.renderer().setSymbol(
        QgsLineSymbol.createSimple({"line_color": "200,30,30", "line_width": "0.8"})
    )
    settings = QgsMapSettings()
    settings.setLayers([answer, shape])
    settings.setDestinationCrs(shape.crs())
    extent = shape.extent()
    extent.grow(extent.width() * 0.03)
    settings.setExtent(extent)
    ratio = extent.height() / extent.width()
    settings.setOutputSize(QSize(1400, max(200, int(1400 * ratio))))
    settings.setBackgroundColor(QColor("white"))
    job = QgsMapRendererParallelJob(settings)
    job.start()
    job.waitForFinished()
    job.renderedImage().save(out, "PNG")
    app.exitQgis()


if __name__ == "__main__":
    main(*sys.argv[1:4])
