"""Settings that size and stop the server: worker count from the CPU quota, drain bound."""

from __future__ import annotations

import math
import os
from pathlib import Path

import pytest
import yaml

import service.__main__ as entry
from service.settings import Settings, available_cores, cgroup_cpu_limit
from testkit import REPO


def cgroup(tmp_path: Path, files: dict[str, str]) -> Path:
    for name, text in files.items():
        path = tmp_path / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return tmp_path


@pytest.mark.parametrize(
    ("files", "limit"),
    [
        ({"cpu.max": "150000 100000\n"}, 1.5),
        ({"cpu.max": "50000 100000\n"}, 0.5),
        ({"cpu.max": "max 100000\n"}, None),
        ({"cpu.max": "garbage\n"}, None),
        ({"cpu/cpu.cfs_quota_us": "200000\n", "cpu/cpu.cfs_period_us": "100000\n"}, 2.0),
        ({"cpu/cpu.cfs_quota_us": "-1\n", "cpu/cpu.cfs_period_us": "100000\n"}, None),
        ({}, None),
    ],
    ids=["v2-1.5", "v2-0.5", "v2-max", "v2-garbage", "v1-2", "v1-unlimited", "none"],
)
def test_cgroup_cpu_limit(tmp_path: Path, files: dict[str, str], limit: float | None) -> None:
    assert cgroup_cpu_limit(cgroup(tmp_path, files)) == limit


def test_workers_respect_quota_and_affinity(tmp_path: Path) -> None:
    affinity = len(os.sched_getaffinity(0))
    assert available_cores(cgroup(tmp_path / "none", {})) == affinity
    quota = cgroup(tmp_path / "q", {"cpu.max": "50000 100000"})  # half a CPU: one worker
    assert available_cores(quota) == 1
    roomy = cgroup(tmp_path / "r", {"cpu.max": f"{(affinity + 7) * 100000} 100000"})
    assert available_cores(roomy) == affinity  # the affinity is the tighter bound
    if affinity >= 2:
        onehalf = cgroup(tmp_path / "h", {"cpu.max": "150000 100000"})
        assert available_cores(onehalf) == 2  # rounded up


def test_default_worker_count_uses_both(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("SKELPRUNE_WORKERS", raising=False)
    expected = len(os.sched_getaffinity(0))
    limit = cgroup_cpu_limit()
    if limit is not None:
        expected = max(1, min(expected, math.ceil(limit)))
    assert Settings().workers == expected


def test_shutdown_timeout_reaches_uvicorn(monkeypatch: pytest.MonkeyPatch) -> None:
    import types

    import uvicorn

    seen: dict[str, object] = {}

    class FakeServer:
        def __init__(self, config: dict[str, object]) -> None:
            seen.update(config)

        def run(self, sockets: list[object]) -> None:
            seen["sockets"] = sockets

    monkeypatch.setattr(uvicorn, "Config", lambda app, **kw: kw)
    monkeypatch.setattr(uvicorn, "Server", FakeServer)
    import service.app

    app = types.SimpleNamespace(state=types.SimpleNamespace(pool_failure=None))
    monkeypatch.setattr(service.app, "create_app", lambda settings, **kw: app)
    monkeypatch.setattr(entry.signal, "signal", lambda *args: None)  # not in pytest itself
    monkeypatch.setenv("SKELPRUNE_SHUTDOWN_TIMEOUT", "12.5")
    monkeypatch.setenv("SKELPRUNE_LOG_LEVEL", "warning")
    monkeypatch.setenv("SKELPRUNE_HOST", "127.0.0.1")
    monkeypatch.setenv("SKELPRUNE_PORT", "0")
    entry.main()
    assert seen["timeout_graceful_shutdown"] == 12.5
    assert seen["access_log"] is False  # the service writes its own JSON access log
    assert seen["log_config"]["formatters"]["json"]["tracebacks"] is False
    assert Settings.model_fields["shutdown_timeout"].default == 50.0
    (sock,) = seen["sockets"]  # bound before the app was built
    assert sock.getsockname()[0] == "127.0.0.1"
    sock.close()


def _seconds(text: str) -> float:
    text = str(text).strip()
    return float(text[:-1]) if text.endswith("s") else float(text)


def test_deploy_files_bound_the_drain_below_their_grace_periods() -> None:
    """The drain gives up before the orchestrator's SIGKILL, and after the longest job."""
    root = REPO / "deploy"
    compose = yaml.safe_load((root / "compose.yaml").read_text())["services"]["skelprune"]
    env = compose["environment"]
    drain = float(env["SKELPRUNE_SHUTDOWN_TIMEOUT"])
    assert float(env["SKELPRUNE_JOB_TIMEOUT"]) < drain < _seconds(compose["stop_grace_period"])

    deployment = yaml.safe_load((root / "k8s" / "deployment.yaml").read_text())
    pod = deployment["spec"]["template"]["spec"]
    (container,) = pod["containers"]
    values = {e["name"]: e.get("value") for e in container["env"]}
    drain = float(values["SKELPRUNE_SHUTDOWN_TIMEOUT"])
    pre_stop = container["lifecycle"]["preStop"]["exec"]["command"]
    pre_stop_s = float(pre_stop[-1]) if pre_stop[0] == "sleep" else 0.0
    job_timeout = float(
        values.get("SKELPRUNE_JOB_TIMEOUT") or Settings.model_fields["job_timeout"].default
    )
    assert job_timeout < drain < pod["terminationGracePeriodSeconds"] - pre_stop_s


def test_numba_cache_seed_is_copied_once_into_an_empty_cache(tmp_path) -> None:
    from service.worker.numba_seed import seed_numba_cache

    seed = tmp_path / "seed" / "skelprune"
    seed.mkdir(parents=True)
    (seed / "a.nbi").write_bytes(b"index")
    (seed / "a.nbc").write_bytes(b"code")
    target = tmp_path / "cache"
    assert seed_numba_cache(tmp_path / "seed", target) == 2
    assert (target / "skelprune" / "a.nbc").read_bytes() == b"code"
    (target / "skelprune" / "a.nbc").write_bytes(b"newer")
    assert seed_numba_cache(tmp_path / "seed", target) == 0  # not empty: left alone
    assert (target / "skelprune" / "a.nbc").read_bytes() == b"newer"
    assert seed_numba_cache(tmp_path / "missing", tmp_path / "other") == 0
    assert not (tmp_path / "other").exists()


def test_a_bad_setting_is_one_line_naming_the_variable() -> None:
    import os
    import subprocess
    import sys

    env = {**os.environ, "SKELPRUNE_WORKERS": "abc", "SKELPRUNE_PORT": "0"}
    proc = subprocess.run(
        [sys.executable, "-m", "service"], env=env, capture_output=True, text=True, timeout=60
    )
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith("error: SKELPRUNE_WORKERS='abc'") and "integer" in lines[0]
    assert "Traceback" not in proc.stderr
