"""The screenshot of docs/napari.md: the sample cells pruned in the widget.

xvfb-run -s "-screen 0 1600x1000x24" .venv/bin/python tests/frontends/napari_screenshot.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import napari
from qtpy.QtWidgets import QApplication

from skelprune.napari._sample import sample_cells
from skelprune.napari._widget import PruneWidget

OUT = Path(__file__).resolve().parents[2] / "docs" / "figures" / "napari.png"


def main() -> None:
    viewer = napari.Viewer(show=True)
    viewer.window.resize(1500, 900)
    data, meta, _ = sample_cells()[0]
    viewer.add_labels(data, opacity=0.8, **meta)
    widget = PruneWidget(viewer)
    viewer.window.add_dock_widget(widget, name="Skeleton pruning", area="right")
    worker = widget.run()
    if worker is None:
        sys.exit(widget.status.text())
    while widget.result is None or widget.button.isEnabled() is False:
        QApplication.processEvents()
    viewer.layers["cells branches"].edge_width = 2.0
    widget.colour_by.setCurrentText(
        "strahler" if widget.colour_by.findText("strahler") >= 0 else "length"
    )
    viewer.layers.selection.active = viewer.layers["cells branches"]
    viewer.reset_view()
    for _ in range(20):
        QApplication.processEvents()
    viewer.screenshot(str(OUT), canvas_only=False, flash=False)
    print(OUT)
    viewer.close()


if __name__ == "__main__":
    main()
