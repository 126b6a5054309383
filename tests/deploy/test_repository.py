"""The repository stands on its own: a clone with nothing beside it has everything its
tests, benchmarks and evaluation read, and its text points at nothing outside it."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

from testkit import DATA, REPO

# Built from parts, so that this file does not match itself.
OUTSIDE = re.compile(
    "|".join(
        (
            r"\.\./" + "shared",  # the folder some checkouts have beside them
            "/" + "work/",  # a development machine's absolute paths
            r"/home/[a-z]",
            "/" + "Users/",
        )
    )
)
TEAM_SPEC = re.compile(r"\b" + "SP" + r"EC\b")


def _tracked_text_files() -> list[Path]:
    out = subprocess.run(
        ["git", "ls-files", "-z"], cwd=REPO, capture_output=True, check=True
    ).stdout.decode()
    paths = [REPO / p for p in out.split("\0") if p]
    text = []
    for path in paths:
        if not path.is_file() or path.suffix in {".png", ".gif", ".jpg"}:
            continue
        data = path.read_bytes()
        if b"\0" not in data[:4096]:
            text.append(path)
    return text


def test_no_tracked_file_points_outside_the_repository() -> None:
    hits = [
        f"{path.relative_to(REPO)}:{n}: {line.strip()[:80]}"
        for path in _tracked_text_files()
        for n, line in enumerate(path.read_text(errors="replace").splitlines(), 1)
        if OUTSIDE.search(line)
    ]
    assert hits == []


def test_code_and_docs_cite_their_own_docs_not_a_team_document() -> None:
    """The algorithm is explained in docs/algorithm.md; nothing cites a document that a
    reader of the repository does not have (the CHANGELOG, being history, may)."""
    hits = [
        f"{path.relative_to(REPO)}:{n}"
        for path in _tracked_text_files()
        if path.name != "CHANGELOG.md" and not path.is_relative_to(REPO / "data")
        for n, line in enumerate(path.read_text(errors="replace").splitlines(), 1)
        if TEAM_SPEC.search(line)
    ]
    assert hits == []
    assert (REPO / "docs" / "algorithm.md").is_file()


def test_the_datasets_live_inside_the_repository() -> None:
    """Unless $SKELPRUNE_DATA says otherwise, the data is the repository's own ``data/``,
    with every dataset the tests, benchmarks and evaluation read."""
    if DATA.resolve().is_relative_to(REPO.resolve()):
        assert DATA.resolve() == (REPO / "data").resolve()
    counts = {
        "kimia216": 204,
        "kimia99": 99,
        "skelneton-dev/shapes": 293,
        "skelneton-dev/skeletons": 293,
        "anchors/masks/kimia216": 168,
        "anchors/masks/skelneton-dev": 168,
    }
    assert {name: len(list((DATA / name).glob("*.png"))) for name in counts} == counts
    assert (DATA / "README.md").is_file()
    assert (DATA / "anchors" / "authors-matlab-kimia216.csv").is_file()
