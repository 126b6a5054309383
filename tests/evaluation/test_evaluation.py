"""Evaluation helpers: the skeletonize + cut baseline, the stability run, the
``python -m evaluation`` command."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from scipy import ndimage

from evaluation.__main__ import main as evaluation_main
from evaluation.baseline import cut_end_branches, skeletonize_cut
from evaluation.perturb import PERTURBATIONS, Perturbation
from evaluation.stability import VARIANTS, load_dataset, measure, run_stability
from skelprune.grid.graph import BranchGraph
from testkit import DATA


def t_shape() -> np.ndarray:
    """A 7-px bar with a long arm (35 px) below and a 3-px bump on top."""
    m = np.zeros((70, 100), bool)
    m[20:27, 5:95] = True  # bar
    m[27:62, 40:47] = True  # long arm
    m[17:20, 70:73] = True  # bump: a short spur in the skeleton
    return m


def test_cut_removes_short_end_branches_and_keeps_long_ones() -> None:
    mask = t_shape()
    full = skeletonize_cut(mask, 0.0)
    cut = skeletonize_cut(mask, 10.0)
    # the bump's spur is in the raw skeleton and gone after the cut
    assert (full.rows < 21).any()
    assert not (cut.rows < 21).any()
    # the long arm survives down to its tip
    assert cut.rows.max() >= 58
    assert cut.endpoints == 3  # two bar ends and the arm
    assert cut.endpoints < full.endpoints
    # every radius is the exact squared distance to the background
    edt = ndimage.distance_transform_edt(np.pad(mask, 1))[1:-1, 1:-1]
    assert np.allclose(np.sqrt(cut.r2), edt[cut.rows, cut.cols])


def test_cut_end_branches_on_a_graph() -> None:
    # a horizontal line with a 2-px spur and a 12-px arm hanging off it
    rows = [10] * 30 + [9, 8] + list(range(11, 23))
    cols = list(range(2, 32)) + [8, 8] + [20] * 12
    g = BranchGraph(np.array(rows), np.array(cols), (30, 40))
    lengths = {b: g.branch_length(b) for b in g.end_branches()}
    removed = cut_end_branches(g, 5.0)
    assert removed and all(lengths[b] < 5.0 for b in removed)
    assert all(g.branch_length(b) >= 5.0 for b in g.end_branches())
    kept = g.alive_points()
    assert 22 in g.rows[kept]  # the arm's tip
    assert 8 not in g.rows[kept]  # the spur's tip


def test_identity_perturbation_agrees_and_shares_are_fractions() -> None:
    shapes = load_dataset(DATA / "kimia216", 3)
    identity = Perturbation("rotate-0", "rotate", 0.0)  # contour round trip: same mask
    variants = ("bayesian", "cut-15")
    run = run_stability(
        {"kimia216": shapes},
        variants,
        (identity, PERTURBATIONS["gaussian-1.5"]),
        rect_seeds=1,
        workers=2,
        progress=False,
    )
    assert len(run.shapes) == 3 * 3 * len(variants)
    for v in variants:
        assert run.agreement("kimia216", v, "rotate-0") == 1.0
        share = run.agreement("kimia216", v, "gaussian-1.5")
        assert 0.0 <= share <= 1.0
        assert run.disagreements("kimia216", v, "rotate-0") == []
        # the loose reading counts every exact agreement, and exactly the
        # disagreements that are off by at most one endpoint on top
        off = [abs(k - k0) for _, k0, k in run.disagreements("kimia216", v, "gaussian-1.5")]
        loose = run.agreement("kimia216", v, "gaussian-1.5", within=1)
        assert round(loose * 3) == round(share * 3) + sum(d <= 1 for d in off)
        assert set(run.meets_targets(v)) == {"agreement", "rectangles", "rer"}
    # the clean rectangle: four endpoints and its skeleton on the exact medial axis
    assert run.rect_share4("none", "bayesian") == 1.0
    assert run.rect_error("none", "bayesian") < 1.0
    assert 0.0 <= run.rect_share4("gaussian-1", "bayesian") <= 1.0
    clean = run.clean("kimia216", "bayesian")
    assert all(0.0 <= r.rer < 0.05 and r.ss is not None and r.ss > 0 for r in clean)


def test_measure_matches_the_document() -> None:
    import skelprune.api as api

    mask = t_shape()
    got = measure(VARIANTS["bayesian"], mask, with_ss=True, with_points=True)
    res = api.prune(mask)
    doc = res.to_dict()["components"][0]
    assert got.endpoints == res.components[0].graph.n_endpoints()
    assert got.rer == doc["rer"] and got.ss == doc["ss"]
    assert got.points is not None and len(got.points) == sum(
        len(b["points"]) + len(b["off_path"]) for b in doc["skeleton"]["branches"]
    ) + sum(len(n["points"]) for n in doc["skeleton"]["nodes"])


def test_eval_command_writes_report_and_figures(tmp_path: Path) -> None:
    code = evaluation_main(
        ["--out", str(tmp_path), "--limit", "2", "--rect-seeds", "1", "--workers", "1"]
    )
    assert code == 0
    text = (tmp_path / "evaluation.md").read_text()
    for heading in ("Table 1", "Table 2", "Stability", "Fig. 3", "Speed", "Fig. 11"):
        assert heading in text
    for v in VARIANTS:
        assert v in text
    assert "python -m evaluation --out docs --limit 2" in text
    stab = (tmp_path / "stability.md").read_text()
    assert "Endpoint agreement" in stab
    assert "Skeleton distance" in stab
    assert "Against the authors' code" in stab and "(4 shapes)" in stab
    margin = (tmp_path / "margin.md").read_text()
    assert "Flips by margin quartile" in margin and "| off (default) |" in margin
    assert margin.count("| rotate-15 |") == 1
    figs = sorted(p.name for p in (tmp_path / "figures").glob("*.png"))
    assert figs == [
        "fig11_kimia216.png",
        "fig3_curves.png",
        "fig6_7_stability.png",
        "fig9_rectangles.png",
        "groundtruth_misses.png",
        "methods.png",
    ]
    assert "SkelNetOn ground truth" in text
    for name in figs:
        with Image.open(tmp_path / "figures" / name) as im:
            assert im.width > 100 and im.height > 50
        assert f"figures/{name}" in text


def test_eval_command_reports_missing_data(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = evaluation_main(
        ["--out", str(tmp_path / "o"), "--data", str(tmp_path), "--workers", "1"]
    )
    assert code == 1
    assert "no PNG masks" in capsys.readouterr().err


def test_anchor_run_reads_the_authors_counts_and_ours() -> None:
    """On the anchor masks, our default reproduces the counts the anchors' CSV recorded
    for it when it was made, and the authors' shares come straight from the CSV."""
    import csv

    from evaluation.anchors import ANCHOR, BATCHES, anchor_table, run_anchors

    folder = DATA / "anchors"
    run = run_anchors(folder, ("bayesian",), workers=1, progress=False, limit=2)
    assert run.methods == (ANCHOR, "bayesian")
    assert run.perturbations == (
        "gaussian-1",
        "uniform-1.2",
        "rotate-15",
        "rotate-30",
        "scale-0.5",
        "scale-1.5",
    )
    assert run.n_shapes() == 4
    rows = {}
    for b in BATCHES:
        with (folder / f"authors-matlab-{b}.csv").open() as f:
            rows.update(
                {
                    (b, r["shape"], r["perturbation"]): int(r["matlab_endpoints"])
                    for r in csv.DictReader(f)
                }
            )
    got = [r for r in run.records if r.method == ANCHOR]
    assert len(got) == 4 * 7
    assert all(rows[(r.batch, r.shape, r.perturbation)] == r.endpoints for r in got)
    shapes = {(r.batch, r.shape) for r in got}
    want = np.mean([rows[(b, s, "rotate-15")] == rows[(b, s, "clean")] for b, s in shapes])
    assert run.agreement(ANCHOR, "rotate-15") == want
    assert 0 <= run.agreement("bayesian", "gaussian-1", 1) <= 1
    assert run.agreement("bayesian", "gaussian-1", 0) <= run.agreement("bayesian", "gaussian-1", 1)
    assert "rotate-30" in anchor_table(run)


def test_skeleton_distance_is_zero_for_identity_and_positive_under_noise() -> None:
    shapes = load_dataset(DATA / "kimia216", limit=2)
    ident = Perturbation("scale-1", "scale", 1.0)
    noisy = Perturbation("gaussian-1", "gaussian", 1.0)
    run = run_stability(
        {"kimia216": shapes},
        ("bayesian+dce",),
        (ident, noisy),
        rect_seeds=0,
        workers=1,
        progress=False,
    )
    assert run.distance("kimia216", "bayesian+dce", "scale-1") == 0.0
    assert 0 < run.distance("kimia216", "bayesian+dce", "gaussian-1") < 0.1


def test_pixel_scores_against_ground_truth() -> None:
    from evaluation.groundtruth import pixel_scores, run_groundtruth

    line = np.zeros((20, 40), bool)
    line[10, 5:35] = True
    assert pixel_scores(line, line).tolist() == [[1.0, 1.0, 1.0]] * 4
    longer = line.copy()
    longer[10, 35:38] = True  # 3 extra pixels, 1-3 px beyond the truth
    s = pixel_scores(longer, line)
    assert s[0, 1] == 1.0 and s[0, 0] == 30 / 33
    assert s[3, 0] == 1.0  # every extra pixel is within 3 px
    assert np.all(np.diff(s[:, 2]) >= 0)
    assert pixel_scores(np.zeros_like(line), line).tolist() == [[0.0, 0.0, 0.0]] * 4
    run = run_groundtruth(
        DATA / "skelneton-dev", ("bayesian+dce",), workers=1, progress=False, limit=2
    )
    assert len(run.scores) == 2
    m = run.mean("bayesian+dce")
    assert m.shape == (4, 3) and 0.5 < m[2, 2] <= 1.0
