"""The default benchmark's measures and harness (benchmarks/default_*.py) on small inputs."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from benchmarks.__main__ import _split
from benchmarks.default_metrics import centre_line_kept, short_end_branches
from benchmarks.default_planar import measure_network, network_rows
from benchmarks.default_silhouettes import agreement, anchor_halves
from benchmarks.default_suite import main, run
from benchmarks.default_volumes import measure_volume, volume_rows
from testkit.neurons import swc_shape
from testkit.volumes import y_tubes


def line_with_spurs() -> np.ndarray:
    """A 50-px line, one 25-px branch, two short spurs (4 and 6 px), all off the border."""
    m = np.zeros((60, 70), bool)
    m[30, 5:60] = True  # the line
    m[5:30, 20] = True  # a long branch (25 px), its end well inside
    m[31:35, 35] = True  # a 4-px spur
    m[31:37, 48] = True  # a 6-px spur
    return m


def test_centre_line_kept_on_hand_made_cases() -> None:
    raw = line_with_spurs()
    assert centre_line_kept(raw, raw) == 1.0
    assert centre_line_kept(raw, np.zeros_like(raw)) == 0.0
    shifted = np.roll(raw, 2, axis=0)  # 2 px off: still within the tolerance
    assert centre_line_kept(raw, shifted) == 1.0
    no_branch = raw.copy()
    no_branch[5:28, 20] = False  # the branch gone but its last 2 px near the line
    kept = centre_line_kept(raw, no_branch)
    assert kept == pytest.approx((raw.sum() - 23 + 2) / raw.sum())


def test_short_end_branches_counts_spurs_not_branches_or_border_ends() -> None:
    m = line_with_spurs()
    assert short_end_branches(m) == 2
    assert short_end_branches(m, shorter=5.0) == 1
    bare = m.copy()
    bare[31:37, :] = False
    assert short_end_branches(bare) == 0
    edge = bare.copy()
    edge[30, 60:70] = True  # the line runs off the image, 5 px beyond a junction:
    edge[31:46, 64] = True  # its end there is where it leaves the image, not a tip
    assert short_end_branches(edge) == 0
    stub = bare.copy()
    stub[31, 40] = stub[32, 41] = True  # two pixels off the line: its staircase
    assert short_end_branches(stub) == 0
    assert short_end_branches(stub, stub=0.0) == 1
    thick = m.copy()
    thick[31, 10:30] = True  # two pixels wide for a while: corners are not spurs
    assert short_end_branches(thick) == 2


def test_measure_network_on_a_drawn_cross_and_its_rows() -> None:
    mask = np.zeros((80, 90), bool)
    mask[36:45, 5:85] = True
    mask[10:70, 40:49] = True
    got = measure_network(mask, {})
    assert set(got) == {"skelprune", "skan 5", "skan 10"}
    for scores in got.values():
        assert scores["kept"] > 0.9
        assert scores["short"] == 0
    rows = network_rows("cross", [got, got])
    assert [r.metric for r in rows] == [
        "centre line kept, min",
        "centre line kept, median",
        "end branches < 10 px a mask, max",
    ]
    assert rows[2].passed is True and rows[2].ours == "0"
    low = {m: {"kept": 0.97, "short": 6} for m in got}
    rows = network_rows("low", [low, got])
    assert [r.passed for r in rows] == [False, False, False]
    assert rows[0].numbers["skelprune"] == pytest.approx(0.97)


def test_anchor_halves_and_agreement() -> None:
    halves = anchor_halves({"k": ["c", "a", "b", "d"], "s": ["x"]})
    assert halves == {
        ("k", "a"): "A",
        ("k", "b"): "B",
        ("k", "c"): "A",
        ("k", "d"): "B",
        ("s", "x"): "A",
    }
    counts = {
        ("k", "a", "clean"): 4,
        ("k", "a", "noise"): 4,
        ("k", "b", "clean"): 4,
        ("k", "b", "noise"): 5,
        ("k", "c", "clean"): 4,
        ("k", "c", "noise"): None,  # a failed run disagrees
    }
    shapes = [("k", "a"), ("k", "b"), ("k", "c")]
    assert agreement(counts, shapes, "noise", 0) == pytest.approx(1 / 3)
    assert agreement(counts, shapes, "noise", 1) == pytest.approx(2 / 3)


def test_volume_rows_compare_with_the_best_peer() -> None:
    def method(f1: float, tips: int, spurs: int, ends: list[int]) -> dict[str, list[float]]:
        return {
            "clean f1": [f1],
            "rough f1": [f1],
            "clean tips found": [tips],
            "rough tips found": [tips],
            "clean true tips": [5],
            "rough true tips": [5],
            "rough spurs": [spurs],
            "clean endpoints": [ends[0]],
            "rough endpoints": ends[1:],
        }

    result = {
        "skelprune": method(0.95, 5, 1, [5, 6]),
        "kimimaro": method(0.9, 5, 3, [5, 5]),
        "skan 5": method(0.96, 4, 0, [5, 9]),
        "skan 10": method(0.8, 3, 2, [5, 7]),
    }
    rows = {r.metric: r for r in volume_rows("toy", [result])}
    assert rows["F1 at 2 voxels, clean"].passed is False  # skan 5 is better
    assert rows["tips found, clean"].passed is True and rows["tips found, clean"].ours == "5/5"
    assert rows["spurs, rough (0.7)"].passed is False  # skan 5 has none
    change = rows["end-count change clean → rough"]
    assert change.numbers["skelprune"] == pytest.approx(0.2) and change.passed is False


@pytest.mark.slow
def test_measure_volume_on_three_tubes() -> None:
    truth = y_tubes()
    got = measure_volume(truth, {}, copies=1, seed=0, peers=("skan 5", "skan 10"))
    assert set(got) == {"skelprune", "skan 5", "skan 10"}
    assert got["skelprune"]["clean true tips"] == [3.0]
    assert got["skelprune"]["clean tips found"] == [3.0]
    assert got["skelprune"]["clean f1"][0] > 0.9
    assert len(got["skan 10"]["rough endpoints"]) == 1


def test_swc_shape_drops_twigs_inside_their_parent() -> None:
    ids = np.arange(1, 7)
    parents = np.array([-1, 1, 2, 2, 1, 5])
    xyz = np.array([[0, 0, 0], [50, 0, 0], [80, 25, 0], [80, -25, 0], [0, 3, 2], [0, 40, 0]], float)
    radii = np.array([4.0, 3, 2, 2, 2, 2])
    shape = swc_shape(ids, parents, xyz, radii, side=64)
    # node 5 is a 3.6-unit twig off the root: no tip; 3, 4 and 6 are
    assert len(shape.tips) == 3
    assert max(shape.shape) <= 64
    volume = shape.volume()
    assert volume.any() and shape.centre_mask()[volume].any()


def test_run_leaves_out_rows_without_data_and_refuses_bad_input() -> None:
    notes: list[str] = []
    assert run({}, None, quick=True, only=["vessels", "cracks"], notes=notes) == []
    assert len(notes) == 2 and all("--data" in n for n in notes)
    with pytest.raises(ValueError, match="unknown group"):
        run({}, None, only=["nonsense"])
    with pytest.raises(ValueError, match="beta"):
        run({"beta": -1}, None, only=["vessels"])
    with pytest.raises(ValueError, match="options"):
        run({"no_such_option": 1}, None, only=["vessels"])


def test_command_line_errors_name_the_problem(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    for argv, words in (
        (["--options", "{not json"], "not JSON"),
        (["--options", "[1]"], "JSON object"),
        (["--options", '{"coarse": "sometimes"}'], "coarse"),
        (["--data", str(tmp_path / "absent")], "not a folder"),
        (["--only", "vessels,bogus"], "bogus"),
    ):
        with pytest.raises(SystemExit) as e:
            main(argv)
        assert e.value.code == 2
        assert words in capsys.readouterr().err


def test_benchmark_arguments_follow_their_name() -> None:
    known = ["default", "limbs", "networks"]
    assert _split(["default", "--only", "networks", "--quick"], known) == [
        ("default", ["--only", "networks", "--quick"])
    ]
    assert _split(["limbs", "networks"], known) == [("limbs", []), ("networks", [])]
    with pytest.raises(ValueError):
        _split(["--quick"], known)
