"""Fixtures every test folder may use. The datasets' path is ``testkit.DATA`` (a constant,
since test parameters are built from it at collection time)."""

from __future__ import annotations

import os
from collections.abc import Callable
from contextlib import AbstractContextManager
from pathlib import Path

import pytest

from testkit.realserver import Running, running_server

# The service apps a test makes in its own process share pytest's memory (numba's
# kernels, Qt and napari, every test's data), which is not a server's main process: their
# main-memory screen gets room for it. Servers started as users start them
# (testkit.realserver) keep the default.
os.environ.setdefault("SKELPRUNE_MAIN_MEMORY_MB", "65536")


@pytest.fixture
def real_server(tmp_path: Path) -> Callable[..., AbstractContextManager[Running]]:
    """``python -m service`` on 127.0.0.1, started as a user starts it:
    ``with real_server(workers="1") as (proc, base): ...``. Its output goes to
    ``tmp_path / "server.log"``; on leaving the block it is killed, with its workers,
    unless the test stopped it."""

    def start(ready: str = "/readyz", **settings: str) -> AbstractContextManager[Running]:
        return running_server(tmp_path / "server.log", ready=ready, **settings)

    return start
