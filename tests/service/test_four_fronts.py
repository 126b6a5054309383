"""The same input and options give the same bytes through the four fronts: the library
(:func:`skelprune.prune` then :func:`skelprune.encode`), the command line, the service
(a real server on 127.0.0.1) and a data-set run (``prune_many`` on a real local Dask
cluster), over a corpus of every kind of input (testkit/corpus.py) and every answer.

One slow test per front, each comparing the whole corpus against the library's bytes.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import httpx
import pytest

import skelprune
from testkit.corpus import Case, cli_flags, library_options, query, write_corpus
from testkit.daskcluster import dask_cluster
from testkit.realserver import running_server

pytestmark = pytest.mark.slow

ACCEPT = {
    "json": "application/json",
    "geojson": "application/geo+json",
    "csv": "text/csv",
    "graphml": "application/graphml+xml",
    "png": "image/png",
    "swc": "text/x-swc",
}
#: Where the command line writes each answer but the one it prints.
CLI_FILES = {"csv": "--csv", "graphml": "--graphml", "png": "--overlay", "swc": "--swc"}


@pytest.fixture(scope="module")
def corpus(tmp_path_factory: pytest.TempPathFactory) -> list[Case]:
    return write_corpus(tmp_path_factory.mktemp("corpus"))


@pytest.fixture(scope="module")
def library(corpus: list[Case]) -> dict[tuple[str, str], bytes]:
    """Every case's every answer through the library: the reference bytes."""
    out = {}
    for case in corpus:
        for answer in case.answers:
            result = skelprune.prune(case.path, answers=(answer,), **library_options(case.options))
            out[case.name, answer] = skelprune.encode(result, answer)
    return out


def test_the_corpus_answers_every_answer_without_a_number_json_cannot_write(
    library: dict[tuple[str, str], bytes],
) -> None:
    def refuse(constant: str) -> None:
        raise AssertionError(f"{constant} in an answer")

    for (name, answer), body in library.items():
        assert body, (name, answer)
        if answer in ("json", "geojson"):
            json.loads(body, parse_constant=refuse)
        elif answer != "png":
            assert b"nan" not in body.lower() and b"inf" not in body.lower(), (name, answer)


def test_the_command_line_gives_the_librarys_bytes(
    corpus: list[Case], library: dict[tuple[str, str], bytes], tmp_path: Path
) -> None:
    cli = [sys.executable, "-m", "skelprune.cli", "prune"]
    for case in corpus:
        files = {a: tmp_path / f"{case.name}.{a}" for a in case.answers if a in CLI_FILES}
        written = [arg for a, p in files.items() for arg in (CLI_FILES[a], str(p))]
        run = subprocess.run(
            [*cli, str(case.path), *cli_flags(case.options), *written],
            capture_output=True,
            timeout=300,
        )
        assert run.returncode == 0, (case.name, run.stderr.decode())
        assert run.stdout == library[case.name, "json"] + b"\n", case.name
        for answer, path in files.items():
            assert path.read_bytes() == library[case.name, answer], (case.name, answer)
        if "geojson" in case.answers:
            run = subprocess.run(
                [*cli, str(case.path), *cli_flags(case.options), "--geojson"],
                capture_output=True,
                timeout=300,
            )
            assert run.stdout == library[case.name, "geojson"] + b"\n", case.name


def test_the_service_gives_the_librarys_bytes(
    corpus: list[Case], library: dict[tuple[str, str], bytes], tmp_path: Path
) -> None:
    with (
        running_server(tmp_path / "server.log") as (_, base),
        httpx.Client(base_url=base, timeout=120) as client,
    ):
        for case in corpus:
            for answer in case.answers:
                resp = client.post(
                    "/v1/prune",
                    params=query(case.options),
                    content=case.path.read_bytes(),
                    headers={"Content-Type": case.media, "Accept": ACCEPT[answer]},
                )
                assert resp.status_code == 200, (case.name, answer, resp.text[:500])
                assert resp.content == library[case.name, answer], (case.name, answer)


def test_a_data_set_run_gives_the_librarys_bytes(
    corpus: list[Case], library: dict[tuple[str, str], bytes], tmp_path: Path
) -> None:
    from skelprune.parallel import prune_many

    with dask_cluster(tmp_path / "cluster", workers=1) as scheduler:
        # a data-set run splits a label image into one document an object (docs/datasets.md)
        for case in [c for c in corpus if not c.options.get("labels")]:
            out = tmp_path / case.name
            outcomes = prune_many(
                [case.path],
                client=scheduler,
                out=out,
                files=("png", "csv"),
                **library_options(case.options),
            )
            assert [o.status for o in outcomes] == ["done"], outcomes[0].problem
            stem = case.path.stem
            assert (out / f"{stem}.json").read_bytes() == library[case.name, "json"] + b"\n"
            assert (out / f"{stem}.png").read_bytes() == library[case.name, "png"]
            assert (out / f"{stem}.csv").read_bytes() == library[case.name, "csv"]
