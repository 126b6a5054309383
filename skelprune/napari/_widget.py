"""The dock widget: prune the selected Labels or Image layer, 2-D or 3-D, in a worker
thread, and add the answer as layers (:mod:`._layers`)."""

from __future__ import annotations

from typing import Any

import numpy as np
from qtpy import QtCore
from qtpy.QtCore import QObject, Qt
from qtpy.QtWidgets import (
    QComboBox,
    QGroupBox,
    QLabel,
    QProgressBar,
    QPushButton,
    QSlider,
    QVBoxLayout,
    QWidget,
)

from ..errors import SkelpruneError
from ..options import PruneOptions, ReadOptions
from ._form import OptionForm
from ._layers import COLOUR_BY, colour_columns, result_layers, sequence_paths, sequence_steps

__all__ = ["PruneWidget"]


class _Progress(QObject):
    """Carries ``prune``'s progress calls from the worker thread to the widget."""

    moved = QtCore.Signal(int, int)  # type: ignore[attr-defined]


class PruneWidget(QWidget):
    """Prune the viewer's selected Labels or Image layer (a 2-D image, or a 3-D volume
    whose voxel size is the layer's ``scale``) with the options of the form."""

    def __init__(self, napari_viewer: Any) -> None:
        super().__init__()
        self.viewer = napari_viewer
        self.worker: Any = None
        self.result: Any = None
        self._sequence: dict[str, Any] | None = None
        self._source: Any = None
        layout = QVBoxLayout(self)
        box = QGroupBox("Pruning")
        self.prune_form = OptionForm(PruneOptions)
        QVBoxLayout(box).addWidget(self.prune_form)
        layout.addWidget(box)
        box = QGroupBox("Reading (2-D layers)")
        # a Labels layer is read as labels, an Image layer by its foreground rule
        self.read_form = OptionForm(ReadOptions, skip=("labels",))
        QVBoxLayout(box).addWidget(self.read_form)
        layout.addWidget(box)
        self.button = QPushButton("Prune the selected layer")
        self.button.clicked.connect(self.run)
        layout.addWidget(self.button)
        self.progress = QProgressBar()
        self.progress.setVisible(False)
        layout.addWidget(self.progress)
        self.status = QLabel("")
        self.status.setWordWrap(True)
        layout.addWidget(self.status)
        layout.addWidget(QLabel("Colour the branches by"))
        self.colour_by = QComboBox()
        self.colour_by.setEnabled(False)
        self.colour_by.currentTextChanged.connect(self._recolour)
        layout.addWidget(self.colour_by)
        self.step_label = QLabel("Pruning sequence (2-D): step")
        layout.addWidget(self.step_label)
        self.step = QSlider(Qt.Orientation.Horizontal)
        self.step.setEnabled(False)
        self.step.valueChanged.connect(self.show_step)
        layout.addWidget(self.step)
        layout.addStretch(1)
        self._moved = _Progress()
        self._moved.moved.connect(self._on_progress)

    def run(self) -> Any:
        """Start pruning the selected layer; returns the worker (None if refused, with
        the reason in the widget)."""
        from napari.layers import Image, Labels
        from napari.qt.threading import thread_worker

        layer = self.viewer.layers.selection.active
        if not isinstance(layer, Labels | Image):
            return self._refuse("select a Labels or Image layer to prune")
        data = np.asarray(layer.data)
        rgb = bool(getattr(layer, "rgb", False))
        ndim = data.ndim - int(rgb)
        scale = tuple(float(s) for s in layer.scale)
        if ndim not in (2, 3):
            return self._refuse(f"{layer.name}: a 2-D image or a 3-D volume, not {ndim}-D")
        try:
            options = PruneOptions(**self.prune_form.values())
            extra: dict[str, Any] = {}
            if ndim == 3:
                extra["spacing"] = scale
            else:
                read = {**self.read_form.values(), "labels": isinstance(layer, Labels)}
                extra["read"] = ReadOptions(**read)
                if scale[-1] != scale[-2]:
                    return self._refuse(
                        f"{layer.name}: pixels must be square to prune, its scale is {scale}"
                    )
                if scale[-1] != 1.0:  # the branch table in the layer's units
                    extra["pixel_size"] = scale[-1]
                extra["progress"] = self._moved.moved.emit
        except SkelpruneError as exc:
            return self._refuse(str(exc))

        @thread_worker  # type: ignore[untyped-decorator]
        def work() -> Any:
            import skelprune

            return skelprune.prune(data, options, **extra)

        self._source = (layer.name, scale[-2:] if rgb else scale)
        self.button.setEnabled(False)
        self.progress.setVisible(True)
        self.progress.setRange(0, 0)  # busy until the first component is done
        self.status.setText(f"pruning {layer.name} ...")
        self.worker = work()
        self.worker.returned.connect(self._show)
        self.worker.errored.connect(self._failed)
        self.worker.finished.connect(self._done)
        self.worker.start()
        return self.worker

    def _refuse(self, reason: str) -> None:
        self.status.setText(f"error: {reason}")
        return None

    def _on_progress(self, done: int, total: int) -> None:
        self.progress.setRange(0, total)
        self.progress.setValue(done)

    def _done(self) -> None:
        self.button.setEnabled(True)
        self.progress.setVisible(False)

    def _failed(self, exc: Exception) -> None:
        self.status.setText(f"error: {exc}")

    def _replace(self, data: Any, kwargs: dict[str, Any], kind: str) -> Any:
        if kwargs["name"] in self.viewer.layers:
            self.viewer.layers.remove(kwargs["name"])
        return getattr(self.viewer, f"add_{kind}")(data, **kwargs)

    def _show(self, result: Any) -> None:
        from ..output.document import PruneResult

        self.result = result
        name, scale = self._source
        for data, kwargs, kind in result_layers(result, name, scale):
            self._replace(data, kwargs, kind)
        branches = self.viewer.layers[f"{name} branches"]
        self.colour_by.blockSignals(True)
        self.colour_by.clear()
        self.colour_by.addItems(colour_columns(branches.features))
        self.colour_by.setCurrentText(COLOUR_BY)
        self.colour_by.blockSignals(False)
        self.colour_by.setEnabled(True)
        n = len(result.components)
        self.status.setText(f"{name}: {n} component{'s' * (n != 1)} pruned")
        if isinstance(result, PruneResult):
            self._sequence = result.to_dict(curve=False, sequence=True)
            last = sequence_steps(self._sequence)
            self.step.blockSignals(True)
            self.step.setRange(0, last)
            self.step.setValue(last)
            self.step.blockSignals(False)
            self.step.setEnabled(True)
            self.show_step(last, shown=False)
        else:
            self._sequence = None
            self.step.setEnabled(False)

    def show_step(self, step: int, shown: bool = True) -> None:
        """Show the skeleton at ``step`` of the pruning sequence (2-D)."""
        if self._sequence is None:
            return
        name, scale = self._source
        paths = sequence_paths(self._sequence, step)
        self.step_label.setText(f"Pruning sequence (2-D): step {step}")
        kwargs = {
            "name": f"{name} sequence",
            "shape_type": "path",
            "edge_color": "tomato",
            "edge_width": 1.0,
            "scale": scale,
            "ndim": 2,
            # drawn over the answer's branches: shown once the slider is moved
            "visible": shown,
        }
        if kwargs["name"] in self.viewer.layers:
            layer = self.viewer.layers[kwargs["name"]]
            layer.data = paths
            layer.shape_type = "path"
            layer.visible = shown
        else:
            self._replace(paths, kwargs, "shapes")

    def _recolour(self, column: str) -> None:
        if not column or self._source is None:
            return
        self.viewer.layers[f"{self._source[0]} branches"].edge_color = column
