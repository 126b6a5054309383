"""scope="local": windows pruned alone and stitched (skelprune.local, docs/algorithm.md).

The crop property: inside any window, away from its edge, the local answer is the answer
of that window pruned alone, within the tolerance docs/algorithm.md states (at least 99 %
of the skeleton pixels of each within 3 px of the other, 100 px in from the window's
edge); the global scope misses it on the same windows. And the drawn truth: no dead end
or road running off the image that a person keeps is lost.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

import skelprune
from skelprune.errors import InvalidOptionError
from skelprune.options import LOCAL_WINDOW_RANGE, PruneOptions
from testkit.networks import network, truth_counts
from testkit.shapes import dataset, load

CLEAN = {"fill_holes": 64, "min_area": 64}
TOL = 3.0  # px
AGREE = 0.99
MARGIN = 100  # px from a window's edge
WINDOWS = ((0, 0), (500, 900), (1048, 1048), (300, 1048))


def raster(res: skelprune.PruneResult, shape: tuple[int, int]) -> np.ndarray:
    out = np.zeros(shape, bool)
    for comp in res.components:
        r, c, _ = comp.points()
        out[r, c] = True
    return out


def endpoints(res: skelprune.PruneResult) -> tuple[np.ndarray, np.ndarray]:
    rows: list[float] = []
    cols: list[float] = []
    for comp in res.components:
        t = comp.table
        p = t.node_point[np.array(t.kinds()) == "endpoint"]
        rows += t.y[p].tolist()
        cols += t.x[p].tolist()
    return np.array(rows), np.array(cols)


def agreement(a: np.ndarray, b: np.ndarray) -> float:
    """The smaller of: the share of ``a``'s pixels within TOL of ``b``, and the converse."""
    if not a.any() and not b.any():
        return 1.0
    if not a.any() or not b.any():
        return 0.0
    to_b = ndimage.distance_transform_edt(~b)
    to_a = ndimage.distance_transform_edt(~a)
    return float(min((to_b[a] <= TOL).mean(), (to_a[b] <= TOL).mean()))


@pytest.fixture(scope="module", params=["road", "vessel", "crack"])
def net(request: pytest.FixtureRequest) -> object:
    return network(request.param, 2048, seed=2)


def test_options_checked() -> None:
    assert PruneOptions(scope="local", window=256).window == 256
    with pytest.raises(InvalidOptionError, match="scope must be one of global, local"):
        PruneOptions(scope="tiled")
    with pytest.raises(InvalidOptionError, match="window applies to scope='local' only"):
        PruneOptions(window=256)
    with pytest.raises(InvalidOptionError, match="window must be an integer"):
        PruneOptions(scope="local", window=LOCAL_WINDOW_RANGE[0] - 1)


def test_document_records_scope_only_when_local() -> None:
    m = np.zeros((60, 300), bool)
    m[20:32, 5:295] = True
    m[32:50, 150:160] = True
    assert "scope" not in skelprune.prune(m).to_dict()
    doc = skelprune.prune(m, scope="local", window=128).to_dict()
    assert (doc["scope"], doc["window"]) == ("local", 128)
    # a T across three windows: one graph, three ends, one junction
    assert len(doc["components"][0]["skeleton"]["endpoints"]) == 3


def test_crop_property_on_networks(net: object) -> None:
    m = net.mask  # type: ignore[attr-defined]
    local = raster(skelprune.prune(m, scope="local", **CLEAN), m.shape)
    whole = raster(skelprune.prune(m, **CLEAN), m.shape)
    inner = (slice(MARGIN, 1000 - MARGIN), slice(MARGIN, 1000 - MARGIN))
    worst_local, worst_global = 1.0, 1.0
    for r0, c0 in WINDOWS:
        window = (slice(r0, r0 + 1000), slice(c0, c0 + 1000))
        alone = raster(skelprune.prune(m[window], **CLEAN), (1000, 1000))[inner]
        worst_local = min(worst_local, agreement(local[window][inner], alone))
        worst_global = min(worst_global, agreement(whole[window][inner], alone))
    assert worst_local >= AGREE, worst_local
    # the default's noise floor and margin judge a branch by what it alone reaches, so
    # the global scope's answer hardly depends on the image's extent either
    assert worst_global >= 0.98, worst_global


def test_no_kept_road_lost(net: object) -> None:
    m = net.mask  # type: ignore[attr-defined]
    res = skelprune.prune(m, scope="local", **CLEAN)
    r, c = np.nonzero(raster(res, m.shape))
    counts = truth_counts(net, r, c, *endpoints(res))  # type: ignore[arg-type]
    assert counts["border_roads_kept"] == counts["border_roads"], counts
    # thin vessel ends fall apart into specks under ragged edges (the mask has no dead
    # end there to find); roads and cracks keep every one
    if net.kind == "vessel":  # type: ignore[attr-defined]
        assert counts["dead_ends_found"] >= 0.8 * counts["dead_ends"], counts
    else:
        assert counts["dead_ends_found"] == counts["dead_ends"], counts


def test_one_connected_graph_per_component(net: object) -> None:
    res = skelprune.prune(net.mask, scope="local", **CLEAN)  # type: ignore[attr-defined]
    for comp in res.components:
        img = np.zeros(comp.skeleton.mask.shape, bool)
        idx = comp.graph.alive_points()
        img[comp.graph.rows[idx], comp.graph.cols[idx]] = True
        assert ndimage.label(img, np.ones((3, 3)))[1] == 1


@pytest.mark.parametrize("path", dataset("kimia99")[::9], ids=lambda p: p.stem)
def test_silhouettes_fit_one_window(path: object) -> None:
    """A silhouette's default window holds it whole: the local answer is the global one."""
    m = np.kron(load(path), np.ones((4, 4), bool))  # type: ignore[arg-type]
    res = skelprune.prune(m, scope="local")
    assert res.options.window >= max(m.shape)
    assert np.array_equal(raster(res, m.shape), raster(skelprune.prune(m), m.shape))
    assert res.to_dict()["scope"] == "local"


def test_progress_is_reported() -> None:
    m = np.zeros((600, 600), bool)
    m[100:112, 5:595] = m[5:595, 300:312] = True
    m[500:510, 500:510] = True  # a second component
    calls: list[tuple[int, int]] = []
    skelprune.prune(m, progress=lambda d, t: calls.append((d, t)))
    assert calls == [(1, 2), (2, 2)]
    calls.clear()
    skelprune.prune(m, scope="local", window=256, progress=lambda d, t: calls.append((d, t)))
    assert calls == [(k, 9) for k in range(1, 10)]  # a 3 × 3 grid of windows


def test_cli_draws_a_bar_on_a_terminal(monkeypatch: pytest.MonkeyPatch) -> None:
    import io

    from skelprune import cli_files

    class Terminal(io.StringIO):
        def isatty(self) -> bool:
            return True

    err = Terminal()
    monkeypatch.setattr(cli_files.sys, "stderr", err)
    monkeypatch.setattr(cli_files, "PROGRESS_AFTER", 0.0)
    show = cli_files._progress("roads.png")
    for k in range(1, 5):
        show(k, 4)
    assert err.getvalue().endswith("roads.png: [" + "#" * 30 + "] 4/4\n")
    monkeypatch.setattr(cli_files.sys, "stderr", io.StringIO())  # not a terminal: no bar
    assert cli_files._progress("roads.png") is None


def test_overlay_marks_fit_a_large_network() -> None:
    """Marks grow with the picture but never past the shape's median width: on a 2048 px
    network the nodes' discs (13.7 px in radius when they followed the picture alone,
    37 % of their pixels then more than 3 px off the shape) stay on their roads."""
    from skelprune.output.render import COLOURS

    net = network("road", 2048, seed=2)
    res = skelprune.prune(net.mask, **CLEAN)
    img = res.render_overlay()
    junction = np.all(img == COLOURS["junction"], axis=2)
    endpoint = np.all(img == COLOURS["endpoint"], axis=2)
    marked = junction | endpoint
    assert marked.any()
    near = ndimage.binary_dilation(net.mask, iterations=3)
    assert near[marked].mean() > 0.9


def test_prune_many_takes_the_scope() -> None:
    """prune_many's workers run the same pipeline: a batch item with scope="local"
    answers what prune answers."""
    from skelprune.parallel import document_bytes
    from skelprune.parallel.items import expand
    from skelprune.parallel.work import Job, run_batch

    m = np.zeros((300, 300), bool)
    m[100:112, 5:295] = m[5:295, 150:162] = True
    options = PruneOptions(scope="local", window=128)
    done = run_batch(list(enumerate(expand({"t": m}))), Job(options=options))
    assert done[0].answer.payload == document_bytes(skelprune.prune(m, options).to_dict())
    assert (
        b'"scope": "local"' in done[0].answer.payload
        or b'"scope":"local"' in done[0].answer.payload
    )


def test_windows_vote_before_their_tips_are_cut() -> None:
    """Cutting tips moves no end: a short branch a window keeps, cut back to less than
    half its pixels, is still kept once stitched (the vote reads the uncut answer)."""
    m = network("crack", 1024, seed=3).mask
    ends = [
        sum(
            len(c["skeleton"]["endpoints"])
            for c in skelprune.prune(m, scope="local", window=256, trim=trim).to_dict()[
                "components"
            ]
        )
        for trim in (True, False)
    ]
    assert ends[0] == ends[1]


@pytest.mark.parametrize("seed", range(2))
def test_noise_in_windows_keeps_every_axis_point_inside(seed: int) -> None:
    # ragged components cross several windows whose axes meet nowhere near a straight
    # join inside the shape: the joins follow the shape, every point keeps a disk
    mask = np.random.default_rng(seed).random((384, 384)) < 0.5
    res = skelprune.prune(mask, scope="local", window=128)
    assert len(res.components) == ndimage.label(mask, np.ones((3, 3)))[1]
    for comp in res.components:
        rows, cols, r2 = comp.points()
        assert (r2 >= 1).all()
        assert mask[rows, cols].all()
