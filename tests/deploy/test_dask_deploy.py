"""``deploy/dask`` (a Dask cluster on Kubernetes, the Dask operator's DaskCluster, and the
job that runs ``skelprune prune-many`` on it) agrees with the image, the command line and
the budget it runs under: parsed, and checked against the real code."""

from __future__ import annotations

import re

import typer.main
import yaml

from skelprune.cli import app
from skelprune.limits import DATASET_LIMITS
from skelprune.parallel.run import WORKER_OWN_MB
from testkit import REPO

DASK = REPO / "deploy" / "dask"
K8S = REPO / "deploy" / "k8s"
DOCKERFILE = (REPO / "Dockerfile").read_text().replace("\\\n", " ")


def image_env(name: str) -> str:
    """A variable the image's ENV sets (the runtime stage sets each once)."""
    found = re.findall(rf"\b{name}=(\S+)", DOCKERFILE.split("AS runtime", 1)[1])
    assert found, f"the image sets no {name}"
    return found[-1]


def docs() -> dict[str, dict]:
    out = {}
    for path in sorted(DASK.glob("*.yaml")):
        for doc in yaml.safe_load_all(path.read_text()):
            if doc and doc.get("kind") != "Kustomization":
                out[doc["kind"]] = doc
    return out


def project_image() -> str:
    dep = yaml.safe_load((K8S / "deployment.yaml").read_text())
    return dep["spec"]["template"]["spec"]["containers"][0]["image"]


def mib(quantity: str) -> float:
    units = {"Ki": 2**-10, "Mi": 1, "Gi": 2**10, "MiB": 1, "GiB": 2**10}
    for unit, factor in sorted(units.items(), key=lambda u: -len(u[0])):
        if quantity.endswith(unit):
            return float(quantity[: -len(unit)]) * factor
    raise AssertionError(f"unknown unit in {quantity!r}")


def flag(args: list[str], name: str) -> str:
    assert name in args, f"{name} missing from {args}"
    return args[args.index(name) + 1]


def test_kustomization_lists_every_file_and_the_image_is_the_projects() -> None:
    kustomization = yaml.safe_load((DASK / "kustomization.yaml").read_text())
    files = {p.name for p in DASK.glob("*.yaml")} - {"kustomization.yaml"}
    assert set(kustomization["resources"]) == files
    k8s = yaml.safe_load((K8S / "kustomization.yaml").read_text())
    assert kustomization["images"] == k8s["images"]
    cluster = docs()["DaskCluster"]
    assert cluster["apiVersion"] == "kubernetes.dask.org/v1"
    pods = [cluster["spec"]["worker"]["spec"], cluster["spec"]["scheduler"]["spec"]]
    pods.append(docs()["Job"]["spec"]["template"]["spec"])
    for pod in pods:
        for c in pod.get("initContainers", []) + pod["containers"]:
            assert c["image"] == project_image(), c["name"]
        assert pod["securityContext"]["runAsNonRoot"] is True


def test_the_image_holds_dask() -> None:
    assert '".[service,parallel]"' in DOCKERFILE and "e['parallel']" in DOCKERFILE


def test_workers_are_one_thread_under_the_budget_and_load_the_images_kernels() -> None:
    worker = docs()["DaskCluster"]["spec"]["worker"]
    assert worker["replicas"] >= 1
    pod = worker["spec"]
    [container] = pod["containers"]
    args = container["args"]
    assert args[:2] == ["dask", "worker"]
    assert flag(args, "--nthreads") == "1"
    limits = container["resources"]["limits"]
    assert limits["cpu"] == "1", "one worker process of one thread a CPU"
    # the worker's limit is prune_many's own for a local cluster: the budget + its needs
    limit = mib(flag(args, "--memory-limit"))
    assert limit == DATASET_LIMITS.memory_mb + WORKER_OWN_MB
    assert limit <= mib(limits["memory"]) == mib(container["resources"]["requests"]["memory"])
    assert flag(args, "--local-directory").startswith("/tmp/")
    # a read-only root: /tmp is a volume, shared with the init container that seeds
    # numba's cache from the image (the image's own settings, by name)
    assert container["securityContext"]["readOnlyRootFilesystem"] is True
    mounts = {m["name"]: m["mountPath"] for m in container["volumeMounts"]}
    assert mounts["tmp"] == "/tmp"
    [init] = pod["initContainers"]
    code = init["command"][-1]
    assert "seed_numba_cache" in code
    assert "SKELPRUNE_NUMBA_CACHE_SEED" in code and "NUMBA_CACHE_DIR" in code
    assert image_env("NUMBA_CACHE_DIR").startswith("/tmp/")
    assert image_env("SKELPRUNE_NUMBA_CACHE_SEED").startswith("/opt/")
    assert {m["name"]: m["mountPath"] for m in init["volumeMounts"]}["tmp"] == "/tmp"
    ports = {p["name"]: p["containerPort"] for p in container["ports"]}
    assert str(ports["http-dashboard"]) == flag(args, "--dashboard-address")


def test_the_scheduler_and_its_service_agree() -> None:
    cluster = docs()["DaskCluster"]
    scheduler = cluster["spec"]["scheduler"]
    [container] = scheduler["spec"]["containers"]
    assert container["args"] == ["dask", "scheduler"]
    ports = {p["name"]: p["containerPort"] for p in container["ports"]}
    assert ports == {"tcp-comm": 8786, "http-dashboard": 8787}
    for probe in ("readinessProbe", "livenessProbe"):
        assert container[probe]["httpGet"]["port"] in ports
    service = scheduler["service"]
    assert service["selector"]["dask.org/cluster-name"] == cluster["metadata"]["name"]
    assert {p["targetPort"] for p in service["ports"]} <= set(ports)


def test_the_job_runs_prune_many_on_the_clusters_scheduler_over_the_shared_volume() -> None:
    d = docs()
    cluster, job, claim = d["DaskCluster"], d["Job"], d["PersistentVolumeClaim"]
    pod = job["spec"]["template"]["spec"]
    [container] = pod["containers"]
    args = container["args"]
    assert args[:2] == ["skelprune", "prune-many"]
    # the arguments parse with the real command line, as it would run them
    command = typer.main.get_command(app)
    ctx = command.make_context("skelprune", list(args[1:]), resilient_parsing=False)
    sub = command.get_command(ctx, "prune-many")
    params = sub.make_context("prune-many", list(args[2:])).params
    service = f"{cluster['metadata']['name']}-scheduler"  # what the operator names it
    port = next(p["port"] for p in cluster["spec"]["scheduler"]["service"]["ports"])
    assert params["scheduler"] == f"tcp://{service}:{port}"
    assert params["jobs"] is None
    # the workers read the inputs where the job names them
    data = {v["name"]: v for v in pod["volumes"]}
    worker_pod = cluster["spec"]["worker"]["spec"]
    worker_volumes = {v["name"]: v for v in worker_pod["volumes"]}
    claim_name = claim["metadata"]["name"]
    assert claim["spec"]["accessModes"] == ["ReadWriteMany"]
    for volumes in (data, worker_volumes):
        assert volumes["data"]["persistentVolumeClaim"]["claimName"] == claim_name
    job_mount = {m["name"]: m["mountPath"] for m in container["volumeMounts"]}["data"]
    [worker] = worker_pod["containers"]
    worker_mount = {m["name"]: m["mountPath"] for m in worker["volumeMounts"]}["data"]
    assert job_mount == worker_mount
    for path in params["inputs"]:
        assert path.startswith(job_mount + "/"), path
    assert str(params["out"]).startswith(job_mount + "/")


def test_every_file_says_what_it_is_for_and_the_docs_show_the_command() -> None:
    for path in DASK.glob("*.yaml"):
        assert path.read_text().startswith("#"), f"{path.name} opens with what it is for"
    assert "kubectl apply -k deploy/dask" in (REPO / "docs" / "deploy.md").read_text()
