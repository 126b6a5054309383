"""The napari plugin, headless: the widget opens in a viewer, prunes a label image and a
volume in its worker thread, and the layers it adds hold the library's answer.

The viewer draws with OpenGL, which Qt's offscreen platform does not give napari's image
layers: pytest-xvfb runs the tests on a virtual X display (Debian's Xvfb, installed by
``make test``), with Mesa's software rendering."""

from __future__ import annotations

import numpy as np
import pytest

import skelprune
from skelprune.napari._layers import sequence_paths
from skelprune.napari._sample import cells, sample_cells, sample_vessel, vessel
from skelprune.napari._widget import PruneWidget

pytestmark = pytest.mark.timeout(300)


def _prune(qtbot, viewer, widget: PruneWidget) -> None:
    worker = widget.run()
    assert worker is not None, widget.status.text()
    with qtbot.waitSignal(worker.finished, timeout=240_000):
        pass
    qtbot.waitUntil(lambda: widget.result is not None, timeout=10_000)


def _paths(doc: dict, volume: bool) -> list[np.ndarray]:
    out = []
    for comp in doc["components"]:
        for br in comp["skeleton"]["branches"]:
            p = np.array(br["points"])
            p = p[:, [2, 1, 0]] if volume else p[:, [1, 0]]
            out.append(p if len(p) > 1 else np.concatenate([p, p]))
    return out


def test_the_manifest_names_the_widget_and_the_samples() -> None:
    from npe2 import PluginManifest

    manifest = PluginManifest.from_distribution("skelprune")
    assert manifest.name == "skelprune"
    assert [w.display_name for w in manifest.contributions.widgets] == ["Skeleton pruning"]
    assert {s.key for s in manifest.contributions.sample_data} == {"cells", "vessel"}
    data, _, kind = sample_cells()[0]
    assert kind == "labels" and set(np.unique(data)) == {0, 1, 2, 3}
    assert sample_vessel()[0][0].ndim == 3


def test_napari_opens_the_sample_data_and_the_widget(make_napari_viewer, qtbot) -> None:
    viewer = make_napari_viewer()
    viewer.open_sample("skelprune", "cells")
    np.testing.assert_array_equal(viewer.layers["cells"].data, cells())
    _, widget = viewer.window.add_plugin_dock_widget("skelprune", "Skeleton pruning")
    assert isinstance(widget, PruneWidget)
    _prune(qtbot, viewer, widget)  # the sample layer is the selected one
    assert "cells branches" in viewer.layers


def test_the_form_is_made_from_the_option_definitions(make_napari_viewer) -> None:
    from dataclasses import fields

    widget = PruneWidget(make_napari_viewer())
    form = widget.prune_form
    assert list(form.fields) == [f.name for f in fields(skelprune.PruneOptions)]
    beta = skelprune.PruneOptions.__dataclass_fields__["beta"]
    assert form.fields["beta"].text() == "9"
    assert form.fields["beta"].toolTip() == beta.metadata["help"]
    assert form.fields["coarse"].currentText() == "none"  # the definitions' default
    assert "labels" not in widget.read_form.fields
    form.fields["beta"].setText("abc")
    assert widget.run() is None  # nothing selected: refused first
    viewer = widget.viewer
    viewer.add_labels(cells())
    assert widget.run() is None and "beta must be a number" in widget.status.text()
    form.fields["beta"].setText("-1")
    assert widget.run() is None and "beta must be a finite number > 0" in widget.status.text()


def test_a_label_image_prunes_into_the_librarys_answer(make_napari_viewer, qtbot) -> None:
    viewer = make_napari_viewer()
    labels = cells()
    viewer.add_labels(labels, name="cells", scale=(0.5, 0.5))
    widget = PruneWidget(viewer)
    viewer.window.add_dock_widget(widget)
    widget.prune_form.fields["beta"].setText("6")
    _prune(qtbot, viewer, widget)
    # the progress bar counted the three cells as the worker pruned them
    qtbot.waitUntil(lambda: widget.progress.value() == 3, timeout=10_000)
    assert widget.progress.maximum() == 3 and widget.button.isEnabled()
    expected = skelprune.prune(labels, beta=6.0, labels=True, pixel_size=0.5)
    doc = expected.to_dict()
    branches = viewer.layers["cells branches"]
    assert len(branches.data) == sum(len(c["skeleton"]["branches"]) for c in doc["components"])
    for got, want in zip(branches.data, _paths(doc, False), strict=True):
        np.testing.assert_array_equal(got, want)
    np.testing.assert_array_equal(branches.scale, [0.5, 0.5])
    table = expected.summary()
    assert list(branches.features.columns) == list(table.columns)
    assert branches.features["length"].tolist() == table["length"].tolist()
    assert set(branches.features["label"]) == {1, 2, 3}
    nodes = viewer.layers["cells nodes"]
    want_nodes = [[n["y"], n["x"]] for c in doc["components"] for n in c["skeleton"]["nodes"]]
    np.testing.assert_array_equal(nodes.data, want_nodes)
    radii = [n["radius"] for c in doc["components"] for n in c["skeleton"]["nodes"]]
    np.testing.assert_allclose(nodes.size, np.maximum(2 * np.array(radii), 1.0))
    skeleton = viewer.layers["cells skeleton"]
    np.testing.assert_array_equal(skeleton.data, expected.skeleton_mask())
    # recolouring by another column of the branch table
    widget.colour_by.setCurrentText("width_mean")
    assert "width_mean" in [widget.colour_by.itemText(i) for i in range(widget.colour_by.count())]
    # the sequence slider: step 0 is the starting skeleton, the last step the fewest branches
    seq = expected.to_dict(curve=False, sequence=True)
    layer = viewer.layers["cells sequence"]
    assert widget.step.isEnabled() and widget.step.maximum() > 0
    widget.step.setValue(0)
    assert len(layer.data) == len(sequence_paths(seq, 0))
    start = sum(len(c["sequence"]["branches"]) for c in seq["components"])
    assert len(layer.data) == start
    widget.step.setValue(widget.step.maximum())
    assert len(layer.data) < start


def test_a_volume_prunes_with_the_layers_voxel_size(make_napari_viewer, qtbot) -> None:
    viewer = make_napari_viewer()
    volume = vessel()
    viewer.add_image(volume.astype(np.uint8), name="vessel", scale=(2.0, 1.0, 1.0))
    widget = PruneWidget(viewer)
    _prune(qtbot, viewer, widget)
    expected = skelprune.prune(volume, spacing=(2.0, 1.0, 1.0))
    doc = expected.to_dict()
    assert widget.result.to_dict() == doc
    branches = viewer.layers["vessel branches"]
    for got, want in zip(branches.data, _paths(doc, True), strict=True):
        np.testing.assert_array_equal(got, want)
    assert branches.features["length"].tolist() == expected.summary()["length"].tolist()
    nodes = viewer.layers["vessel nodes"]
    want_nodes = [
        [n["z"], n["y"], n["x"]] for c in doc["components"] for n in c["skeleton"]["nodes"]
    ]
    np.testing.assert_array_equal(nodes.data, want_nodes)
    skeleton = viewer.layers["vessel skeleton"].data
    # every branch voxel of the document is on the skeleton, and nothing outside the volume
    for c in doc["components"]:
        for br in c["skeleton"]["branches"]:
            for x, y, z, _ in br["points"]:
                assert skeleton[int(z), int(y), int(x)] == 1
    assert not (skeleton.astype(bool) & ~volume).any()
    assert not widget.step.isEnabled()  # the sequence slider is for 2-D shapes


def test_a_bad_layer_is_refused_with_the_reason(make_napari_viewer) -> None:
    viewer = make_napari_viewer()
    widget = PruneWidget(viewer)
    viewer.add_points(np.zeros((2, 2)))
    assert widget.run() is None and "select a Labels or Image layer" in widget.status.text()
    viewer.add_labels(cells(), scale=(1.0, 2.0))
    assert widget.run() is None and "pixels must be square" in widget.status.text()
