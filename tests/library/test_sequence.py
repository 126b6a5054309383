"""The document's ``sequence`` (opt-in): every step's skeleton follows from it exactly."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

import skelprune
from skelprune.grid.reconstruction import reconstruction
from skelprune.io.png import read_mask
from testkit import DATA


def _alive(item: dict, k: int) -> bool:
    return item["removed_at"] is None or item["removed_at"] > k


def step_skeleton(seq: dict, k: int) -> tuple[int, int, list[list[float]]]:
    """What a viewer derives for S(k): branch count, endpoint count, pixels [x, y, r]
    (the rules docs/viewer.md states)."""
    branches = [
        b
        for b in seq["branches"]
        if _alive(b, k) and (b["absorbed_at"] is None or b["absorbed_at"] > k)
    ]
    pixels = [p for b in seq["branches"] if _alive(b, k) for p in b["points"] + b["off_path"]]
    pixels += [
        p for n in seq["nodes"] if n["kind"] == "junction" and _alive(n, k) for p in n["points"]
    ]
    ends = {n["id"] for n in seq["nodes"] if n["kind"] == "endpoint"}
    endpoints = sum(
        (b["source"] in ends) + (b["target"] in ends and b["target"] != b["source"])
        for b in seq["branches"]
        if _alive(b, k)
    )
    return len(branches), endpoints, pixels


def error_pixels(seq: dict, k: int, shape: tuple[int, int]) -> int:
    """|D \\ R(S(k))| from the sequence alone: S(0)'s misses plus what S(k)'s disks lose."""

    def cover(pts: list[list[float]]) -> np.ndarray:
        a = np.array(pts, float).reshape(-1, 3)
        return reconstruction(
            shape, a[:, 1].astype(int), a[:, 0].astype(int), np.rint(a[:, 2] ** 2).astype(int)
        )

    start = cover(step_skeleton(seq, 0)[2])  # nothing is removed at step 0
    now = cover(step_skeleton(seq, k)[2])
    return len(seq["uncovered"]) + int((start & ~now).sum())


CASES = [
    ("kimia216/bird-2.png", {"coarse": "dce"}),
    ("kimia216/bird-2.png", {}),
    ("kimia99/hand-1.png", {"coarse": "dce"}),
    ("kimia216/elephant-1.png", {"method": "dce"}),
]


@pytest.mark.parametrize(("name", "options"), CASES)
def test_every_step_follows_from_the_sequence(name: str, options: dict) -> None:
    mask = read_mask(DATA / name)
    res = skelprune.prune(mask, **options)
    comp = res.components[0]
    doc = res.to_dict(sequence=True)["components"][0]
    seq = doc["sequence"]
    n = len(comp.sequence.removed)
    assert len(doc["curve"]) == n + 1
    assert seq["start"] == ("coarse" if options.get("coarse") == "dce" else "medial_axis")
    for k in range(n + 1):
        truth = comp.sequence.skeleton_at(k)
        nb, ne, pixels = step_skeleton(seq, k)
        assert nb == truth.n_branches, k
        assert ne == truth.n_endpoints, k
        assert len(pixels) == truth.n_points, k
        assert error_pixels(seq, k, mask.shape) == comp.sequence.lost[k], k
    # the answer is the chosen step
    nb, _, pixels = step_skeleton(seq, doc["chosen_step"])
    assert nb == len(doc["skeleton"]["branches"])
    answer = {tuple(p) for b in doc["skeleton"]["branches"] for p in b["points"] + b["off_path"]}
    answer |= {tuple(p) for nd in doc["skeleton"]["nodes"] for p in nd["points"]}
    if comp.trim is None:
        assert {tuple(p) for p in pixels} == answer
    else:  # the answer is the chosen step with its tips cut
        untrimmed = comp.sequence.skeleton_at(comp.chosen_step)
        assert answer <= {tuple(p) for p in pixels}
        assert len(pixels) - len(answer) == untrimmed.n_points - comp.skeleton.n_points


def test_coarse_removed_is_the_rest_of_the_medial_axis() -> None:
    mask = read_mask(DATA / "kimia216/bird-2.png")
    res = skelprune.prune(mask, coarse="dce")
    doc = res.to_dict(sequence=True)["components"][0]
    seq = doc["sequence"]
    start = len(step_skeleton(seq, 0)[2])
    full = skelprune.prune(mask, coarse=None).components[0].sequence.start.n_points
    assert seq["coarse_removed"] and start + len(seq["coarse_removed"]) == full


def test_sequence_is_opt_in_and_leaves_the_rest_alone() -> None:
    mask = read_mask(DATA / "kimia216/bird-2.png")
    res = skelprune.prune(mask)
    plain = res.to_dict()
    with_seq = res.to_dict(sequence=True)
    assert "sequence" not in plain["components"][0]
    del with_seq["components"][0]["sequence"]
    assert with_seq == plain


def test_the_command_line_prints_the_sequence_on_request() -> None:
    png = DATA / "kimia216" / "bird-2.png"
    cli = [sys.executable, "-m", "skelprune.cli", "prune", str(png)]
    plain = json.loads(
        subprocess.run(cli, capture_output=True, text=True, timeout=300, check=True).stdout
    )
    with_seq = json.loads(
        subprocess.run(
            [*cli, "--sequence"], capture_output=True, text=True, timeout=300, check=True
        ).stdout
    )
    assert with_seq["components"][0]["sequence"]["start"] == "medial_axis"
    del with_seq["components"][0]["sequence"]
    assert with_seq == plain


@pytest.mark.parametrize("name", ["bird-10", "camel-12", "elephant-2", "key-1"])
def test_the_log_records_what_the_graph_did(name: str) -> None:
    """Each logged step names the points and the merge that removing its branch from a
    fresh copy of the start gives, so that what reads the log needs no graph."""
    mask = read_mask(str(DATA / "kimia216" / f"{name}.png"))
    seq = skelprune.prune(mask, coarse=None).components[0].sequence
    log = seq.log
    assert len(log) == len(seq.removed) > 0 and any(k >= 0 for k in log.kept)
    graph = seq.start.working_graph()
    for i, b in enumerate(log.branch):
        points = list(graph.branches[b].points)
        assert log.points(i).tolist() == points
        assert log.merge(i) == graph.remove_end_branch(b)
    taken = np.concatenate([log.points(i) for i in range(len(log))])
    assert np.intersect1d(taken, graph.alive_points()).size == 0
