"""The output folder of a run: one ``NAME.json`` a document, ``NAME.jsonl`` a table, and
``problems.jsonl``; written so that a run stopped at any moment leaves only whole
results, and the next run skips them.

- A document is written to a temporary file in the same folder, then renamed over its
  name (atomic on one file system): it is there whole, or not at all.
- A table's line is appended in one write and flushed; a line cut short by a stop is
  dropped when the table is opened again.
- ``problems.jsonl`` holds one line a failed input, ``{"input", "kind", "detail"}``; an
  input that failed is tried again by the next run (its old line goes then).
"""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
from pathlib import Path
from typing import IO, Any

__all__ = ["PROBLEMS_FILE", "Store"]

#: The problems file's name under the output folder.
PROBLEMS_FILE = "problems.jsonl"
#: Temporary files of writes in progress (a stopped run's are removed by the next).
_TMP = ".*.tmp"


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _whole_lines(path: Path) -> list[bytes]:
    """The complete lines of a JSON-lines file, the file cut back to them (a stop may
    have left half a line at its end)."""
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        return []
    end = data.rfind(b"\n") + 1
    if end != len(data):
        with open(path, "r+b") as f:
            f.truncate(end)
    return data[:end].splitlines()


class Store:
    """The output folder: what is done already, and where each result goes."""

    def __init__(self, folder: str | os.PathLike[str]) -> None:
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        for stale in self.folder.glob(_TMP):  # a stopped run's half-written documents
            with contextlib.suppress(OSError):
                stale.unlink()
        self._mode = 0o666 & ~_umask()  # what open() would give (mkstemp gives 0600)
        self._tables: dict[str, IO[bytes]] = {}
        self._rows: dict[str, set[int]] = {}
        self._problems: IO[bytes] | None = None

    def document_path(self, name: str, suffix: str = ".json") -> Path:
        return self.folder / f"{name}{suffix}"

    def table_path(self, name: str) -> Path:
        return self.folder / f"{name}.jsonl"

    def has_document(self, name: str, files: tuple[str, ...] = ()) -> bool:
        """Whether ``NAME.json`` is written, and the files asked for beside it."""
        return all(
            self.document_path(name, s).is_file() for s in (".json", *(f".{f}" for f in files))
        )

    def has_row(self, name: str, row: int) -> bool:
        if name not in self._rows:
            rows = set()
            for line in _whole_lines(self.table_path(name)):
                with contextlib.suppress(ValueError, KeyError, TypeError):
                    rows.add(int(json.loads(line)["row"]))
            self._rows[name] = rows
        return row in self._rows[name]

    def write_document(self, name: str, payload: bytes, suffix: str = ".json") -> Path:
        """Write ``NAME.json`` (or ``NAME`` and another ``suffix``) atomically: a
        temporary file, then a rename."""
        path = self.document_path(name, suffix)
        fd, tmp = tempfile.mkstemp(dir=self.folder, prefix=f".{name}.", suffix=".tmp")
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(payload)
            os.chmod(tmp, self._mode)
            os.replace(tmp, path)
        except BaseException:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
            raise
        return path

    def write_row(self, name: str, row: int, payload: bytes) -> Path:
        """Append one line to the table ``NAME.jsonl`` (one write, flushed)."""
        if name not in self._tables:
            self.has_row(name, row)  # cuts back a line left half-written
            self._tables[name] = open(self.table_path(name), "ab")  # noqa: SIM115
        f = self._tables[name]
        f.write(payload)
        f.flush()
        self._rows[name].add(row)
        return self.table_path(name)

    def start_problems(self, retried: set[str]) -> None:
        """Open the problems file, dropping the lines of inputs this run tries again."""
        path = self.folder / PROBLEMS_FILE
        kept = []
        for line in _whole_lines(path):
            try:
                name = json.loads(line)["input"]
            except (ValueError, KeyError, TypeError):
                continue
            if name not in retried:
                kept.append(line + b"\n")
        fd, tmp = tempfile.mkstemp(dir=self.folder, prefix=".problems.", suffix=".tmp")
        with os.fdopen(fd, "wb") as f:
            f.writelines(kept)
        os.chmod(tmp, self._mode)
        os.replace(tmp, path)
        self._problems = open(path, "ab")  # noqa: SIM115

    def write_problem(self, problem: dict[str, Any]) -> None:
        assert self._problems is not None, "start_problems first"
        self._problems.write(json.dumps(problem).encode() + b"\n")
        self._problems.flush()

    def close(self) -> None:
        for f in [*self._tables.values(), self._problems]:
            if f is not None:
                f.close()
        self._tables.clear()
        self._problems = None
