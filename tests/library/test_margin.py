"""Branch margins (skelprune.pruning.margin) and the min_margin option."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from fastapi.testclient import TestClient

import skelprune
from service.app import create_app
from service.settings import Settings
from skelprune.api import components
from skelprune.errors import InvalidOptionError
from skelprune.grid._orientation import oriented
from skelprune.grid.reconstruction import reconstruction
from skelprune.options import DEFAULT_MIN_MARGIN
from skelprune.pruning.choice import choose_step
from testkit.oracle import objective
from testkit.shapes import blobs, dataset, load, rectangle_with_holes, two_components

CLI = [sys.executable, "-m", "skelprune.cli"]


def shapes() -> list[np.ndarray]:
    masks = [load(p) for p in dataset("kimia216")[::8]] + [load(p) for p in dataset("kimia99")[::8]]
    return (
        masks + [rectangle_with_holes(), two_components()] + [blobs(s, 72, 5, 3) for s in range(6)]
    )


def naive_lambda(comp, crop: np.ndarray, graph) -> float:
    """λ of a graph's skeleton, reconstruction repainted from scratch."""
    pts = graph.alive_points()
    rec = reconstruction(crop.shape, graph.rows[pts], graph.cols[pts], comp.r2[pts])
    lost = int((crop & ~rec).sum())
    seq = comp.sequence
    return objective(lost, seq.area, *graph.total_steps(), seq.alpha, seq.lbar)


@pytest.mark.parametrize("trim", [True, False])
@pytest.mark.parametrize("coarse", ["dce", None])
def test_margins_follow_their_definition(coarse: str | None, trim: bool) -> None:
    """End branch: λ(Ŝ − E) − λ(Ŝ), with Ŝ − E repainted from scratch; inner branch: λ at
    the step that first removes its points, minus λ(Ŝ); never removed: None."""
    checked = {"end": 0, "inner": 0, "never": 0}
    for mask in shapes():
        res = skelprune.prune(mask, coarse=coarse, trim=trim)
        doc = res.to_dict()
        for comp, cdoc, (crop, _) in zip(
            res.components, doc["components"], components(mask), strict=True
        ):
            crop, _ = oriented(crop)
            g, k, lam = comp.graph, comp.chosen_step, comp.sequence.objective
            alive = [b for b, br in enumerate(g.branches) if br.alive]
            base = comp.objective  # λ of the answer, its tips cut
            if comp.alpha is not None:
                assert naive_lambda(comp, crop, g) == pytest.approx(base, abs=1e-12)
                assert base <= lam[k] + 1e-12
            # the sequence continued from Ŝ, as pixel sets
            # (replayed on the untrimmed answer: a merge keeps the longer branch, which a
            # cut tip may change)
            g0 = comp.sequence.skeleton_at(k).graph
            later = [set(g0.alive_points().tolist())]
            h = g0.copy()
            for pick in comp.sequence.removed[k:]:
                h.remove_end_branch(pick)
                later.append(set(h.alive_points().tolist()))
            for b, bdoc in zip(alive, cdoc["skeleton"]["branches"], strict=True):
                pts = set(g.branches[b].points)
                gone = [i for i, s in enumerate(later) if not pts <= s]
                assert bdoc["removed_at"] == (k + gone[0] if gone else None)
                if comp.alpha is None:
                    assert bdoc["margin"] is None
                elif g.is_end_branch(b) and gone:  # (a limb is never removed)
                    h = g.copy()
                    h.remove_end_branch(b)
                    assert bdoc["margin"] == pytest.approx(
                        naive_lambda(comp, crop, h) - base, abs=1e-12
                    )
                    checked["end"] += 1
                elif gone:
                    assert bdoc["margin"] == pytest.approx(lam[k + gone[0]] - base, abs=1e-12)
                    assert bdoc["margin"] > 0
                    checked["inner"] += 1
                else:
                    assert bdoc["margin"] is None
                    checked["never"] += 1
            # the end branch the sequence takes next has the smallest rise it could find
            if comp.alpha is not None and k < len(comp.sequence.removed) and comp.trim is None:
                nxt = alive.index(comp.sequence.removed[k])
                m = cdoc["skeleton"]["branches"][nxt]["margin"]
                assert m == pytest.approx(lam[k + 1] - lam[k], abs=1e-12) and m > 0
    assert min(checked.values()) > 0, checked


def test_end_margins_are_non_negative_but_for_a_dissolved_junctions_path() -> None:
    """≥ 0 but where the greedy's ranking (lengths before a dissolved junction's path is
    added, docs/algorithm.md) took a branch whose removal then added length: documented."""
    margins = []
    for path in dataset("kimia216"):
        res = skelprune.prune(load(path))
        for comp, cdoc in zip(res.components, res.to_dict(curve=False)["components"], strict=True):
            g = comp.graph
            alive = [b for b, br in enumerate(g.branches) if br.alive]
            margins += [
                d["margin"]
                for b, d in zip(alive, cdoc["skeleton"]["branches"], strict=True)
                if g.is_end_branch(b) and d["margin"] is not None  # (None: a limb)
            ]
    margins = np.array(margins)
    assert (margins < 0).mean() < 0.01 and margins.min() > -0.01


def test_margin_in_geojson_and_none_for_dce() -> None:
    mask = rectangle_with_holes()
    res = skelprune.prune(mask)
    doc = res.to_dict(curve=False)["components"][0]["skeleton"]["branches"]
    gj = [
        f["properties"] for f in res.to_geojson()["features"] if f["properties"]["kind"] == "branch"
    ]
    assert [(p["margin"], p["removed_at"]) for p in gj] == [
        (b["margin"], b["removed_at"]) for b in doc
    ]
    dce = skelprune.prune(mask, method="dce").to_dict()["components"][0]["skeleton"]
    assert all(b["margin"] is None for b in dce["branches"])


def test_min_margin_continues_the_sequence() -> None:
    for mask in shapes()[:12]:
        base = skelprune.prune(mask, min_margin=0.0, choice="argmin")  # the paper's argmin
        assert base.components[0].chosen_step == choose_step(base.components[0].sequence.objective)
        default = skelprune.prune(mask).to_dict()
        assert skelprune.prune(mask, min_margin=DEFAULT_MIN_MARGIN).to_dict() == default
        for m in (0.003, 0.01, 0.1, 1.0):
            res = skelprune.prune(mask, min_margin=m, choice="argmin")
            for c0, c in zip(base.components, res.components, strict=True):
                lam = c.sequence.objective
                assert c.sequence.removed == c0.sequence.removed  # the same sequence
                assert c.chosen_step >= c0.chosen_step
                # every step taken rose λ by less than m; the next one would not
                assert all(lam[i + 1] - lam[i] < m for i in range(c0.chosen_step, c.chosen_step))
                if c.chosen_step < len(c.sequence.removed):
                    assert lam[c.chosen_step + 1] - lam[c.chosen_step] >= m
                assert c.graph.n_endpoints() <= c0.graph.n_endpoints()
    with pytest.raises(InvalidOptionError, match="min_margin must be"):
        skelprune.prune(two_components(), min_margin=-1)
    with pytest.raises(InvalidOptionError, match="min_margin must be"):
        skelprune.prune(two_components(), min_margin=float("nan"))
    with pytest.raises(InvalidOptionError, match="method='bayesian' only"):
        skelprune.prune(two_components(), method="dce", min_margin=0.1)


def test_min_margin_in_cli_and_service(tmp_path) -> None:
    png = dataset("kimia216")[0]
    base = skelprune.prune(load(png), min_margin=0.5).to_dict(curve=False)
    run = subprocess.run(
        [*CLI, "prune", str(png), "--min-margin", "0.5", "--no-curve"],
        capture_output=True,
        text=True,
        timeout=300,
        check=True,
    )
    assert json.loads(run.stdout)["components"] == base["components"]
    bad = subprocess.run(
        [*CLI, "prune", str(png), "--min-margin", "0.5", "--method", "dce"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert bad.returncode == 2 and "bayesian" in bad.stderr and "Traceback" not in bad.stderr
    data = png.read_bytes()
    with TestClient(create_app(Settings(workers=1)), raise_server_exceptions=False) as client:
        resp = client.post(
            "/v1/prune",
            params={"min_margin": "0.5", "curve": "false"},
            content=data,
            headers={"content-type": "image/png"},
        )
        assert resp.status_code == 200, resp.text
        assert resp.json()["components"] == base["components"]
        poly = {"type": "Polygon", "coordinates": [[[0, 0], [40, 0], [40, 20], [0, 20], [0, 0]]]}
        resp = client.post("/v1/prune", json={"geojson": poly, "min_margin": 0.5})
        assert resp.status_code == 200, resp.text
        for kwargs in (
            {"params": {"min_margin": "-1"}},
            {"params": {"min_margin": "x"}},
            {"params": {"min_margin": "0.5", "method": "dce"}},
        ):
            resp = client.post(
                "/v1/prune", content=data, headers={"content-type": "image/png"}, **kwargs
            )
            assert resp.status_code == 422 and "min_margin" in resp.text


def test_flip_matching_finds_every_branch_under_exact_turns() -> None:
    """A turn by 0° or 90° and a mirror-free shift keep every end branch: nothing is lost
    or gained, so the flip table's mapping and matching are right."""
    from evaluation.margin import run_margins
    from evaluation.perturb import Perturbation

    # (twelve shapes: a limb has no margin, so it is not counted)
    sets = {"kimia216": [(p.stem, load(p)) for p in dataset("kimia216")[:12]]}
    perts = (Perturbation("rotate-0", "rotate", 0.0), Perturbation("rotate-90", "rotate", 90.0))
    run = run_margins(sets, perturbations=perts, min_margins=(0.1,), workers=1, progress=False)
    for p in ("rotate-0", "rotate-90"):
        for kind in ("lost", "gained"):
            _, flips, total = run.flips(kind, p)
            assert flips == 0 and total > 10, (p, kind)
        assert run.agreement(None, p) == 1.0 and run.agreement(0.1, p) == 1.0
    assert run.mean_endpoints(0.1) <= run.mean_endpoints(None)


@pytest.mark.parametrize("size", [(60, 160), (90, 240), (120, 320)])
def test_the_default_keeps_a_rectangles_corner_branches(size) -> None:
    """A rectangle keeps its four corner branches. (Below about 60 px across, the paper's
    trade-off from the full medial axis keeps one corner at each end: docs/default.md.)"""
    h, w = size
    mask = np.zeros((h + 10, w + 10), bool)
    mask[5 : 5 + h, 5 : 5 + w] = True
    res = skelprune.prune(mask)
    assert res.n_endpoints() == 4
    assert res.components[0].rer < 0.02
