"""The shell scripts CI runs: the fresh-machine path of the container smoke test.

CI machines that already hold the base image never reach the base-making code, so a trap
there stays hidden until a new machine runs it. These tests run that code on its own.
"""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

from testkit import REPO

SCRIPT = REPO / "scripts" / "container-smoke.sh"


def _function(name: str) -> str:
    """The source of one shell function of the smoke script."""
    text = SCRIPT.read_text()
    match = re.search(rf"^{name}\(\) \{{\n.*?^\}}\n", text, re.S | re.M)
    assert match, f"{name} not found in {SCRIPT}"
    return match.group(0)


def _run_strict(body: str) -> subprocess.CompletedProcess[str]:
    """Run shell code under the script's own strict mode."""
    return subprocess.run(
        ["bash", "-c", "set -euo pipefail\nset -E\n" + body],
        capture_output=True,
        text=True,
        timeout=30,
    )


def test_remove_rootfs_survives_a_tree_with_no_mounts(tmp_path: Path) -> None:
    # The normal case on a new machine: debootstrap finished, nothing is mounted inside.
    rootfs = tmp_path / "rootfs.tmp"
    (rootfs / "usr" / "bin").mkdir(parents=True)
    (rootfs / "usr" / "bin" / "python3").write_text("")
    done = _run_strict(f"{_function('remove_rootfs')}remove_rootfs {rootfs}\necho survived\n")
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "survived"
    assert not rootfs.exists()


def test_remove_rootfs_of_a_missing_tree_is_a_no_op(tmp_path: Path) -> None:
    done = _run_strict(f"{_function('remove_rootfs')}remove_rootfs {tmp_path / 'none'}\necho ok\n")
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "ok"


def test_a_failing_command_says_where_it_stopped(tmp_path: Path) -> None:
    # The script's ERR trap, run as the script sets it up: a silent exit is what it prevents.
    text = SCRIPT.read_text()
    setup = "\n".join(
        line for line in text.splitlines() if line.startswith(("START=", "log()", "trap 'rc=$?"))
    )
    done = _run_strict(setup + "\nfalse\necho unreachable\n")
    assert done.returncode == 1
    assert "unreachable" not in done.stdout
    assert re.search(r"FAIL: line \d+: `false` exited 1", done.stderr), done.stderr


def test_unknown_option_is_a_usage_error() -> None:
    done = subprocess.run(
        ["bash", str(SCRIPT), "--bogus"], capture_output=True, text=True, timeout=30
    )
    # As root the option is parsed before anything is installed; as another user the
    # root check comes after it, so both give the usage line.
    assert done.returncode == 2, done.stderr
    assert "usage:" in done.stderr


def test_make_run_installs_only_the_serving_extras() -> None:
    """``make run`` sets up with the service extra and the graph one (the README's first
    example calls ``to_networkx()``) alone; ``make test`` adds the test, geo, parallel and
    napari ones (dask: ``prune_many``'s tests start a real cluster; napari: the plugin's)."""

    def installs(target: str) -> list[str]:
        """The extras each editable pip install of ``make -n TARGET`` asks for."""
        out = subprocess.run(
            ["make", "-n", "-W", "pyproject.toml", target],
            cwd=REPO,
            capture_output=True,
            text=True,
            timeout=60,
            check=True,
        ).stdout
        return re.findall(r"pip install [^|]*?-e '\.\[([a-z,]+)\]'", out)

    assert installs("run") == ["service,graph"]
    test = installs("test")  # (and the service extra alone, which the kernels' stamp needs)
    assert "service,test,geo,parallel,napari" in test  # their tests run in make test too
    assert not [extras for extras in test if "bench" in extras]
    assert "bench" in installs("bench")[0]
    assert installs("client") == ["service,client"]
