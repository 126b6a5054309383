#!/usr/bin/env bash
# Container smoke test: build the service image from the repo's Dockerfile with buildah,
# run it with podman, prove that it serves a real prune request, and that it stops cleanly
# on SIGTERM. Fails (non-zero exit) when the image does not build, start, serve or stop.
#
# No registry image can be pulled on the CI machines, so the base image is made locally:
# a Debian bookworm minbase root filesystem (debootstrap, through the machine's own apt
# mirror) with python3 and python3-venv, imported into the container storage. It is cached
# under $SKELPRUNE_BASE_CACHE (default /var/tmp/skelprune-base) between runs.
#
# Usage: bash scripts/container-smoke.sh [--base-only | --fresh]
#   --base-only  make (or find) the base image and stop
#   --fresh      the path of a new machine: ignore the cached base tarball and image, make
#                the base from nothing in a temporary cache, then build, serve and stop
#                (about 4 minutes more; run it before a release)
# Environment:
#   SKELPRUNE_BASE_CACHE   where the base root filesystem tarball is cached
#   SKELPRUNE_SMOKE_PNG    the PNG to POST (default: examples/shape.png)
#   SKELPRUNE_SMOKE_KEEP=1 keep the built image afterwards (default: removed)
# Needs root (debootstrap, buildah/podman with chroot isolation and the vfs driver).
set -euo pipefail

REPO=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BASE_CACHE=${SKELPRUNE_BASE_CACHE:-/var/tmp/skelprune-base}
# Bump when the base recipe below changes, so stale caches are rebuilt.
BASE_RECIPE=bookworm-minbase-python3-v1
BASE_IMAGE=localhost/skelprune-base:${BASE_RECIPE}
IMAGE=localhost/skelprune:smoke-$$
CONTAINER=skelprune-smoke-$$
STORE=(--storage-driver=vfs)
PODMAN=(podman "${STORE[@]}" --runtime runc --cgroup-manager=cgroupfs)
BASE_ONLY=0
FRESH=0
case ${1:-} in
    '') ;;
    --base-only) BASE_ONLY=1 ;;
    --fresh) FRESH=1 ;;
    *) printf 'usage: %s [--base-only | --fresh]\n' "$0" >&2; exit 2 ;;
esac

START=$(date +%s)
log() { printf '[container-smoke +%ss] %s\n' "$(($(date +%s) - START))" "$*" >&2; }
die() { log "FAIL: $*"; exit 1; }
# Any command that stops the script under `set -e` says which one and where: a silent
# exit 1 after a long step is the failure this guards against. (-E: functions too.)
set -E
trap 'rc=$?; log "FAIL: line $LINENO: \`$BASH_COMMAND\` exited $rc"; exit "$rc"' ERR

[[ $(id -u) -eq 0 ]] || die "must run as root (debootstrap, buildah --isolation=chroot)"

# --- tools -------------------------------------------------------------------------------
ensure_tools() {
    local missing=() tool
    declare -A pkg=([buildah]=buildah [podman]=podman [runc]=runc [debootstrap]=debootstrap
                    [curl]=curl [python3]=python3)
    for tool in buildah podman runc debootstrap curl python3; do
        command -v "$tool" >/dev/null 2>&1 || missing+=("${pkg[$tool]}")
    done
    # debootstrap verifies the Release file with the archive keyring
    [[ -f /usr/share/keyrings/debian-archive-keyring.gpg ]] || missing+=(debian-archive-keyring)
    if ((${#missing[@]})); then
        log "installing ${missing[*]}"
        apt-get update -q >/dev/null
        DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends \
            "${missing[@]}" >/dev/null
    fi
}

# The Debian mirror this machine's apt uses (deb822 .sources or one-line sources.list).
debian_mirror() {
    local uri
    uri=$(grep -hsE '^[[:space:]]*URIs:' /etc/apt/sources.list.d/*.sources 2>/dev/null \
          | awk '{print $2}' | grep -vE 'security|updates' | grep -E '/debian/?$' | head -n1 || true)
    if [[ -z $uri ]]; then
        uri=$(grep -hsE '^[[:space:]]*deb[[:space:]]' /etc/apt/sources.list \
                  /etc/apt/sources.list.d/*.list 2>/dev/null \
              | awk '{for (i = 2; i <= NF; i++) if ($i !~ /^\[/) {print $i; break}}' \
              | grep -vE 'security' | grep -E '/debian/?$' | head -n1 || true)
    fi
    echo "${uri:-http://deb.debian.org/debian}"
}

# apt's proxy setting, if any, for debootstrap (which honours http_proxy).
apt_proxy() {
    { apt-config dump 2>/dev/null || true; } \
        | sed -nE 's/^Acquire::http::Proxy "(.+)";$/\1/p' | head -n1 || true
}

# --- base image --------------------------------------------------------------------------
# Remove a (possibly half-made) root filesystem: unmount whatever an interrupted debootstrap
# left mounted inside it (proc, sys, ...) and never cross into another file system.
remove_rootfs() {
    local dir=$1 mnt mounts
    [[ -e $dir ]] || return 0
    # No mount below $dir is the normal case: grep then exits 1, which must not count as a
    # failure (under pipefail it would end the script), so its status is ignored here.
    mounts=$(findmnt -rn -o TARGET 2>/dev/null | grep -F "$dir/" | sort -r || true)
    while read -r mnt; do
        if [[ -n $mnt ]]; then umount -l "$mnt" || true; fi
    done <<<"$mounts"
    rm -rf --one-file-system "${dir:?}"
}

make_base() {
    local tarball=$BASE_CACHE/$BASE_RECIPE.tar
    # one base build at a time (parallel CI jobs on one machine share the cache)
    mkdir -p "$BASE_CACHE"
    exec 9>"$BASE_CACHE/.lock"
    flock -w 900 9 || die "timed out waiting for $BASE_CACHE/.lock"
    if "${PODMAN[@]}" image exists "$BASE_IMAGE"; then
        log "base image $BASE_IMAGE present"
        exec 9>&-
        return
    fi
    if [[ ! -s $tarball ]]; then
        local mirror proxy rootfs
        mirror=$(debian_mirror)
        proxy=$(apt_proxy)
        rootfs=$BASE_CACHE/rootfs.tmp
        remove_rootfs "$rootfs"
        log "debootstrap bookworm (minbase + python3, python3-venv) from $mirror"
        http_proxy=${proxy:-${http_proxy:-}} debootstrap --variant=minbase \
            --include=python3,python3-venv,ca-certificates \
            bookworm "$rootfs" "$mirror" >"$BASE_CACHE/debootstrap.log" 2>&1 \
            || { tail -n 30 "$BASE_CACHE/debootstrap.log" >&2; die "debootstrap failed"; }
        # slim it: no package lists, caches, docs or manuals in the image
        chroot "$rootfs" apt-get clean
        rm -rf "${rootfs:?}"/var/lib/apt/lists/* "${rootfs:?}"/var/cache/apt/*.bin \
               "${rootfs:?}"/usr/share/doc/* "${rootfs:?}"/usr/share/man/* "${rootfs:?}"/usr/share/info/* \
               "${rootfs:?}"/usr/share/locale/* "${rootfs:?}"/var/log/*.log "${rootfs:?}"/tmp/* \
               "${rootfs:?}"/dev/*
        chroot "$rootfs" python3 -c 'import ensurepip, venv' \
            || die "base root filesystem has no working python3 venv"
        tar --numeric-owner -C "$rootfs" -cf "$tarball.tmp" .
        mv "$tarball.tmp" "$tarball"
        remove_rootfs "$rootfs"
    else
        log "using cached base root filesystem $tarball"
    fi
    log "importing $tarball as $BASE_IMAGE"
    "${PODMAN[@]}" import --quiet \
        --change 'ENV PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin' \
        --change 'ENV LANG=C.UTF-8' \
        --change 'CMD ["/usr/bin/python3"]' \
        "$tarball" "$BASE_IMAGE" >/dev/null
    exec 9>&-
}

# --- pip settings passed into the build --------------------------------------------------
# The build reaches PyPI the way this machine does. Local file:// indexes and find-links
# do not exist inside the build, so only http(s) settings are handed on.
pip_setting() {
    local env_name=$1 key=$2 value
    value=${!env_name:-}
    if [[ -z $value ]] && command -v pip >/dev/null 2>&1; then
        value=$(pip config get "global.$key" 2>/dev/null || true)
    fi
    # keep only http(s) URLs
    tr ' ' '\n' <<<"$value" | grep -E '^https?://' | paste -sd' ' || true
}

ensure_tools
if ((FRESH)); then
    BASE_CACHE=$(mktemp -d /var/tmp/skelprune-base-fresh.XXXXXX)
    log "--fresh: removing $BASE_IMAGE, making the base in $BASE_CACHE"
    "${PODMAN[@]}" rmi -f "$BASE_IMAGE" >/dev/null 2>&1 || true
fi
make_base
if ((BASE_ONLY)); then
    log "base image ready: $BASE_IMAGE"
    exit 0
fi

SAMPLE=${SKELPRUNE_SMOKE_PNG:-$REPO/examples/shape.png}
[[ -f $SAMPLE ]] || die "no sample PNG at $SAMPLE"

WORK=$(mktemp -d)
cleanup() {
    local rc=$?
    "${PODMAN[@]}" rm -f -t 5 "$CONTAINER" >/dev/null 2>&1 || true
    if [[ ${SKELPRUNE_SMOKE_KEEP:-0} != 1 ]]; then
        "${PODMAN[@]}" rmi -f "$IMAGE" >/dev/null 2>&1 || true
    fi
    rm -rf "$WORK"
    if ((FRESH)); then rm -rf --one-file-system "${BASE_CACHE:?}"; fi
    if ((rc == 0)); then log "OK"; else log "FAILED (exit $rc)"; fi
    exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# --- build -------------------------------------------------------------------------------
build_args=(--build-arg "BASE_IMAGE=$BASE_IMAGE")
index_url=$(pip_setting PIP_INDEX_URL index-url)
extra_index=$(pip_setting PIP_EXTRA_INDEX_URL extra-index-url)
[[ -n $index_url ]] && build_args+=(--build-arg "PIP_INDEX_URL=$index_url")
[[ -n $extra_index ]] && build_args+=(--build-arg "PIP_EXTRA_INDEX_URL=$extra_index")
secret_args=()
CA_BUNDLE=${SKELPRUNE_CA_BUNDLE:-/etc/ssl/certs/ca-certificates.crt}
[[ -s $CA_BUNDLE ]] && secret_args+=(--secret "id=cacert,src=$CA_BUNDLE")

log "building $IMAGE from $REPO/Dockerfile"
buildah bud --isolation=chroot "${STORE[@]}" --format docker --layers=false \
    "${build_args[@]}" "${secret_args[@]}" \
    -f "$REPO/Dockerfile" -t "$IMAGE" "$REPO" >"$BASE_CACHE/last-build.log" 2>&1 \
    || { tail -n 40 "$BASE_CACHE/last-build.log" >&2; die "image build failed"; }
log "built $IMAGE"

# --- run ---------------------------------------------------------------------------------
PORT=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
log "starting container on port $PORT"
"${PODMAN[@]}" run -d --name "$CONTAINER" \
    --ulimit nofile=1024:1024 --ulimit nproc=1024:1024 \
    --network=host -e "SKELPRUNE_PORT=$PORT" "$IMAGE" >/dev/null 2>"$WORK/run.err" \
    || { cat "$WORK/run.err" >&2; die "podman run failed"; }

show_logs() { "${PODMAN[@]}" logs "$CONTAINER" 2>&1 | tail -n 40 >&2 || true; }

# the port opens at once (/healthz 200, /readyz 503 while the workers warm up); the
# workers load the numba kernels compiled at build time (seeded into /tmp/numba-cache)
started=$(date +%s)
deadline=$((started + 300))
until curl -fsS -m 2 "http://127.0.0.1:$PORT/healthz" >/dev/null 2>&1; do
    state=$("${PODMAN[@]}" inspect -f '{{.State.Status}}' "$CONTAINER" 2>/dev/null || echo gone)
    [[ $state == running ]] || { show_logs; die "container is $state before becoming healthy"; }
    (($(date +%s) < deadline)) || { show_logs; die "no /healthz within 300 s"; }
    sleep 0.2
done
log "/healthz answers, $(($(date +%s) - started)) s after start"
until code=$(curl -sS -m 5 -o "$WORK/readyz.json" -w '%{http_code}' \
                 "http://127.0.0.1:$PORT/readyz" 2>/dev/null) && [[ $code == 200 ]]; do
    [[ $code == 503 ]] || { show_logs; die "/readyz answers ${code:-nothing}, not 200 or 503"; }
    (($(date +%s) < deadline)) || { show_logs; die "/readyz not 200 within 300 s"; }
    sleep 0.2
done
log "/readyz answers 200, $(($(date +%s) - started)) s after start"
# (the logs go to a variable first: grep -q would close the pipe early, and pipefail
# would count podman's SIGPIPE as a failure)
logs=$("${PODMAN[@]}" logs "$CONTAINER" 2>&1 || true)
[[ $logs =~ "numba cache seeded: "[1-9] ]] \
    || { show_logs; die "the server did not seed the numba cache from the image"; }
log "numba cache seeded from the image"
# and the workers loaded it (built for NUMBA_CPU_NAME=generic: valid on any x86-64 host)
if [[ $logs =~ "compiled "[0-9]+" numba kernels" || ! $logs =~ "numba kernels loaded from the cache" ]]; then
    show_logs; die "the workers compiled the kernels instead of loading the image's cache"
fi
log "workers loaded the image's compiled kernels"

# The image's own HEALTHCHECK command must pass too (it is what docker/podman will run).
health=$("${PODMAN[@]}" image inspect --format '{{json .HealthCheck}}' "$IMAGE" 2>/dev/null || true)
[[ $health == *healthz* ]] || die "image has no HEALTHCHECK on /healthz (got: $health)"
"${PODMAN[@]}" healthcheck run "$CONTAINER" >/dev/null 2>&1 \
    || { show_logs; die "the image's HEALTHCHECK command fails in the running container"; }
log "image HEALTHCHECK passes"

user=$("${PODMAN[@]}" exec "$CONTAINER" id -u)
[[ $user != 0 ]] || die "the service runs as root inside the container"

log "POST $(basename "$SAMPLE") to /v1/prune"
code=$(curl -sS -m 120 -o "$WORK/prune.json" -w '%{http_code}' \
    -H 'Content-Type: image/png' --data-binary "@$SAMPLE" \
    "http://127.0.0.1:$PORT/v1/prune") || { show_logs; die "POST /v1/prune failed"; }
[[ $code == 200 ]] || { head -c 2000 "$WORK/prune.json" >&2; show_logs; die "POST /v1/prune: HTTP $code"; }
python3 - "$WORK/prune.json" <<'EOF' || die "unexpected /v1/prune response"
import json
import sys

doc = json.load(open(sys.argv[1]))
comps = doc["components"]
assert isinstance(comps, list) and comps, "no components"
for c in comps:
    sk = c["skeleton"]
    assert sk["endpoints"], "a component without endpoints"
    ids = {n["id"] for n in sk["nodes"]}
    assert set(sk["endpoints"]) <= ids, "endpoints that are not nodes"
    assert sk["branches"], "a component without branches"
    assert 0.0 <= c["rer"] <= 1.0, "rer out of range"
print(f"{len(comps)} component(s), endpoints {[len(c['skeleton']['endpoints']) for c in comps]}",
      file=sys.stderr)
EOF
log "prune response is a skeleton document"

# A volume: a .npy of a bar written without numpy (the host's python3 may not have it).
python3 - "$WORK/bar.npy" <<'EOF' || die "could not write the test volume"
import sys

depth, height, width = 10, 12, 40
header = "{'descr': '|b1', 'fortran_order': False, 'shape': (%d, %d, %d), }" % (
    depth, height, width)
header += " " * (-(10 + len(header) + 1) % 64) + "\n"
voxels = bytearray(depth * height * width)
for z in range(3, 7):
    for y in range(3, 9):
        for x in range(3, 37):
            voxels[(z * height + y) * width + x] = 1
with open(sys.argv[1], "wb") as f:
    f.write(b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header.encode())
    f.write(bytes(voxels))
EOF
log "POST a .npy volume to /v1/prune"
code=$(curl -sS -m 120 -o "$WORK/volume.json" -w '%{http_code}' \
    -H 'Content-Type: application/x-npy' --data-binary "@$WORK/bar.npy" \
    "http://127.0.0.1:$PORT/v1/prune?spacing=2,1,1") || { show_logs; die "POST a volume failed"; }
[[ $code == 200 ]] || { head -c 2000 "$WORK/volume.json" >&2; show_logs; die "POST a volume: HTTP $code"; }
python3 - "$WORK/volume.json" <<'EOF' || die "unexpected volume response"
import json
import sys

doc = json.load(open(sys.argv[1]))
assert doc["dimensions"] == 3 and doc["spacing"] == [2.0, 1.0, 1.0], "not a volume's document"
(comp,) = doc["components"]
assert len(comp["skeleton"]["endpoints"]) == 2, "a bar's skeleton has two ends"
print(f"volume: {len(comp['skeleton']['endpoints'])} endpoints", file=sys.stderr)
EOF
log "volume response is a 3-D skeleton document"

# --- graceful stop -----------------------------------------------------------------------
log "SIGTERM"
# (podman without systemd logs an error about its healthcheck timer here: harmless)
"${PODMAN[@]}" stop -t 30 "$CONTAINER" >/dev/null 2>"$WORK/stop.err" \
    || { cat "$WORK/stop.err" >&2; die "podman stop failed"; }
state=$("${PODMAN[@]}" inspect -f '{{.State.Status}} {{.State.ExitCode}}' "$CONTAINER")
[[ $state == "exited 0" ]] || { show_logs; die "container did not exit cleanly on SIGTERM: $state"; }
log "container exited with code 0 on SIGTERM"
