"""``skelprune:centerlines`` (polygon features to map lines, ``skelprune centerlines``)
and ``skelprune:rasterlines`` (a raster mask to lines, ``skelprune prune MASK.tif
--geojson``), each run by the library's command line in its own Python (:mod:`.library`)
on a temporary copy of the input."""

from __future__ import annotations

import json
import os
import tempfile
from typing import Any

from qgis.core import (
    QgsCoordinateTransformContext,
    QgsFeature,
    QgsFeatureSink,
    QgsField,
    QgsFields,
    QgsGeometry,
    QgsProcessing,
    QgsProcessingAlgorithm,
    QgsProcessingException,
    QgsProcessingParameterBand,
    QgsProcessingParameterBoolean,
    QgsProcessingParameterFeatureSink,
    QgsProcessingParameterFeatureSource,
    QgsProcessingParameterNumber,
    QgsProcessingParameterRasterLayer,
    QgsVectorFileWriter,
    QgsVectorLayer,
    QgsWkbTypes,
)
from qgis.PyQt.QtCore import QVariant

from . import library

#: The columns of a mask's lines, from the branch table (the library's docs/tables.md).
RASTER_FIELDS = (
    ("component", QVariant.Int),
    ("branch", QVariant.Int),
    ("source", QVariant.Int),
    ("target", QVariant.Int),
    ("branch_kind", QVariant.String),
    ("length", QVariant.Double),
    ("width_mean", QVariant.Double),
    ("strahler", QVariant.Int),
    ("margin", QVariant.Double),
)


class _Algorithm(QgsProcessingAlgorithm):
    def group(self) -> str:
        return "Skeletons"

    def groupId(self) -> str:
        return "skeletons"

    def createInstance(self) -> QgsProcessingAlgorithm:
        return type(self)()


class CenterlinesAlgorithm(_Algorithm):
    """Map centre lines of polygon features."""

    def name(self) -> str:
        return "centerlines"

    def displayName(self) -> str:
        return "Centre lines of polygons"

    def shortHelpString(self) -> str:
        return (
            "Map centre lines of every polygon feature, each pruned on its own by the "
            "parameter-free Bayesian skeleton pruning (skelprune centerlines): one row per "
            "map line with its feature (row number), part, kind, length and mean width, "
            "then the feature's attributes. Lengths and widths are in the layer's units, "
            "in metres for geographic data (pruned in a local equidistant projection). A "
            "part too small for a line gets its centre in the optional point output; a "
            "feature that fails gets a row without geometry whose error says why."
        )

    def initAlgorithm(self, config: Any = None) -> None:
        self.addParameter(
            QgsProcessingParameterFeatureSource(
                "INPUT", "Polygons", [QgsProcessing.TypeVectorPolygon]
            )
        )
        self.addParameter(
            QgsProcessingParameterBoolean(
                "MAIN_PATH", "One line per connected network: its longest path", False
            )
        )
        self.addParameter(
            QgsProcessingParameterNumber(
                "PIXEL_SIZE",
                "Raster pixel size on the ground (metres for geographic data; "
                "empty: fitted to each polygon)",
                QgsProcessingParameterNumber.Double,
                None,
                True,
                0.0,
            )
        )
        self.addParameter(
            QgsProcessingParameterNumber(
                "PIXELS_PER_WIDTH",
                "Pixels across a polygon's narrowest part (when the pixel size is fitted)",
                QgsProcessingParameterNumber.Double,
                3.0,
                False,
                1.0,
            )
        )
        self.addParameter(
            QgsProcessingParameterFeatureSink(
                "OUTPUT", "Centre lines", QgsProcessing.TypeVectorLine
            )
        )
        self.addParameter(
            QgsProcessingParameterFeatureSink(
                "POINTS",
                "Centres of parts too small for a line",
                QgsProcessing.TypeVectorPoint,
                optional=True,
                createByDefault=False,
            )
        )

    def processAlgorithm(self, parameters: Any, context: Any, feedback: Any) -> dict[str, Any]:
        source = self.parameterAsSource(parameters, "INPUT", context)
        if source is None:
            raise QgsProcessingException("no polygon layer given (INPUT)")
        arguments = ["--no-progress"]
        if self.parameterAsBool(parameters, "MAIN_PATH", context):
            arguments.append("--main-path")
        if parameters.get("PIXEL_SIZE") is not None and str(parameters["PIXEL_SIZE"]) != "NULL":
            size = self.parameterAsDouble(parameters, "PIXEL_SIZE", context)
            arguments += ["--pixel-size", repr(size)]
        per = self.parameterAsDouble(parameters, "PIXELS_PER_WIDTH", context)
        arguments += ["--pixels-per-width", repr(per)]
        with tempfile.TemporaryDirectory(prefix="skelprune-") as work:
            given, answer = os.path.join(work, "in.gpkg"), os.path.join(work, "out.gpkg")
            _write(source, given, context)
            library.run(["centerlines", given, answer, *arguments], feedback, allowed=(0, 1))
            if not os.path.exists(answer):
                raise QgsProcessingException("skelprune centerlines wrote no lines")
            lines = QgsVectorLayer(answer, "lines", "ogr")
            fields = QgsFields()
            for field in lines.fields():
                if field.name() != "fid":
                    fields.append(field)
            crs = source.sourceCrs()
            sink, sink_id = self.parameterAsSink(
                parameters, "OUTPUT", context, fields, QgsWkbTypes.LineString, crs
            )
            points, points_id = self.parameterAsSink(
                parameters, "POINTS", context, fields, QgsWkbTypes.Point, crs
            )
            total = max(lines.featureCount(), 1)
            for i, row in enumerate(lines.getFeatures()):
                out = QgsFeature(fields)
                out.setAttributes([row[field.name()] for field in fields])
                geometry = row.geometry()
                is_point = geometry.type() == QgsWkbTypes.PointGeometry
                if not geometry.isNull():
                    out.setGeometry(geometry)
                if not is_point:  # a line, or a failed feature's row without geometry
                    sink.addFeature(out, QgsFeatureSink.FastInsert)
                elif points is not None:
                    points.addFeature(out, QgsFeatureSink.FastInsert)
                feedback.setProgress(100.0 * (i + 1) / total)
        return {"OUTPUT": sink_id, "POINTS": points_id}


def _write(source: Any, path: str, context: Any) -> None:
    """The features of ``source`` into a GeoPackage at ``path``, in their order."""
    options = QgsVectorFileWriter.SaveVectorOptions()
    options.driverName = "GPKG"
    fields = QgsFields()
    for field in source.fields():
        if field.name() != "fid":  # the GeoPackage's own feature id
            fields.append(field)
    transform = context.transformContext() if context else QgsCoordinateTransformContext()
    writer = QgsVectorFileWriter.create(
        path, fields, source.wkbType(), source.sourceCrs(), transform, options
    )
    if writer.hasError():
        raise QgsProcessingException(f"cannot write the features: {writer.errorMessage()}")
    for feature in source.getFeatures():
        copy = QgsFeature(fields)
        copy.setAttributes([feature[field.name()] for field in fields])
        copy.setGeometry(feature.geometry())
        writer.addFeature(copy)
    del writer  # closes the file


class RasterlinesAlgorithm(_Algorithm):
    """Lines of a raster mask (its non-zero, non-nodata pixels), in the raster's CRS."""

    def name(self) -> str:
        return "rasterlines"

    def displayName(self) -> str:
        return "Centre lines of a raster mask"

    def shortHelpString(self) -> str:
        return (
            "The pruned skeleton of a raster mask (a band's non-zero pixels that are not "
            "its nodata value: a segmentation's output) as lines in the raster's CRS, one "
            "per branch, with the branch table's numbers in map units. The raster must be "
            "north-up with square pixels."
        )

    def initAlgorithm(self, config: Any = None) -> None:
        self.addParameter(QgsProcessingParameterRasterLayer("INPUT", "Raster mask"))
        self.addParameter(QgsProcessingParameterBand("BAND", "Band", 1, "INPUT", True))
        self.addParameter(
            QgsProcessingParameterFeatureSink("OUTPUT", "Lines", QgsProcessing.TypeVectorLine)
        )

    def processAlgorithm(self, parameters: Any, context: Any, feedback: Any) -> dict[str, Any]:
        from osgeo import gdal

        layer = self.parameterAsRasterLayer(parameters, "INPUT", context)
        if layer is None:
            raise QgsProcessingException("no raster layer given (INPUT)")
        band = self.parameterAsInt(parameters, "BAND", context) or 1
        with tempfile.TemporaryDirectory(prefix="skelprune-") as work:
            mask = os.path.join(work, "mask.tif")
            # the band alone, as a GeoTIFF the library reads (its nodata and grid kept)
            done = gdal.Translate(mask, layer.source(), format="GTiff", bandList=[band])
            if done is None:
                raise QgsProcessingException(f"{layer.name()}: cannot read band {band}")
            done = None  # closes the file
            text = library.run(["prune", mask, "--geojson"], feedback)
        try:
            lines = json.loads(text)
        except ValueError:
            raise QgsProcessingException("skelprune answered no GeoJSON") from None
        fields = QgsFields()
        for name, kind in RASTER_FIELDS:
            fields.append(QgsField(name, kind))
        sink, sink_id = self.parameterAsSink(
            parameters, "OUTPUT", context, fields, QgsWkbTypes.LineString, layer.crs()
        )
        for feature in lines["features"]:
            if feature["geometry"]["type"] != "LineString":
                continue  # the nodes
            props = {**feature["properties"], "branch": feature["properties"]["id"]}
            out = QgsFeature(fields)
            out.setAttributes([props.get(name) for name, _ in RASTER_FIELDS])
            coords = feature["geometry"]["coordinates"]
            wkt = "LINESTRING (" + ", ".join(f"{x!r} {y!r}" for x, y in coords) + ")"
            out.setGeometry(QgsGeometry.fromWkt(wkt))
            sink.addFeature(out, QgsFeatureSink.FastInsert)
        return {"OUTPUT": sink_id}
