"""Retrieval evaluation (Table 3): hit counting and a small run end to end."""

from __future__ import annotations

import numpy as np

from evaluation.retrieval import (
    PERTURBATIONS,
    RETRIEVAL_VARIANTS,
    baseline_descriptor,
    hits_at_rank,
    retrieval_markdown,
    run_retrieval,
)
from evaluation.stability import load_dataset
from skelprune.matching import match
from testkit import DATA


def test_hits_at_rank_counts_same_class_at_each_rank():
    classes = ["a", "a", "b", "b"]
    dist = np.array([[0, 1, 2, 3], [1, 0, 0.5, 4], [2, 0.5, 0, 1], [3, 4, 1, 0]], float)
    # ranks (self left out): 0 -> 1(a) 2(b); 1 -> 2(b) 0(a); 2 -> 1(a) 3(b); 3 -> 2(b) 0(a)
    assert hits_at_rank(dist, classes, 2).tolist() == [2, 2]
    assert hits_at_rank(dist, classes, 5).tolist() == [2, 2, 0]


def test_baseline_descriptor_matches_itself():
    mask = load_dataset(DATA / "kimia216", 1)[0][1]
    d = baseline_descriptor(mask)
    assert d.n_endpoints >= 2
    assert match(d, d).distance == 0.0


def test_small_run_writes_every_table():
    shapes = load_dataset(DATA / "kimia216")
    picked = [
        s
        for s in shapes
        if s[0] in {"hammer-1", "hammer-2", "hammer-3", "bone-1", "bone-2", "bone-3"}
    ]
    run = run_retrieval({"kimia216": picked}, workers=1)
    for v in RETRIEVAL_VARIANTS:
        hits = run.clean[("kimia216", v)]
        assert hits.shape == (5,) and hits.min() >= 0 and hits.max() <= 6
    for p in PERTURBATIONS:
        assert run.perturbed[("kimia216", p)].shape == (5,)
    # rank 1 well above chance (2 of the other 5 shapes share a query's class: 2.4 of 6)
    assert run.clean[("kimia216", "default")][0] >= 4
    text = retrieval_markdown(run, "cmd")
    assert "face" in text and "204" in text and "`cmd`" in text
    for name in (*RETRIEVAL_VARIANTS, *PERTURBATIONS):
        assert f"| {name}" in text
