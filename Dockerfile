# skelprune service image.
#
#   docker build -t skelprune .
#   docker run --rm -p 8000:8000 skelprune
#
# Needs BuildKit (Docker >= 23 uses it by default) or buildah for the RUN --mount lines.
# Build arguments:
#   BASE_IMAGE           any Debian-like image with python3 >= 3.11 and its venv module
#   PIP_INDEX_URL, PIP_EXTRA_INDEX_URL   a package mirror, when PyPI is not reachable
# Build secret (optional): --secret id=cacert,src=/path/to/ca-bundle.crt, a CA bundle for
# pip behind a TLS-intercepting proxy. It is used during the build only, never stored.

ARG BASE_IMAGE=python:3.11-slim

# ---------------------------------------------------------------------------------------
# build: a virtual environment with the package, its `service` extra and its `parallel`
# extra (dask: the same image runs the Dask cluster of deploy/dask)
# ---------------------------------------------------------------------------------------
FROM ${BASE_IMAGE} AS build

ARG PIP_INDEX_URL
ARG PIP_EXTRA_INDEX_URL
ENV PIP_DISABLE_PIP_VERSION_CHECK=1 \
    PIP_DEFAULT_TIMEOUT=120 \
    PYTHONDONTWRITEBYTECODE=1

RUN python3 -m venv /opt/venv

# Dependencies first (from pyproject.toml alone), so that a code change does not
# download them again.
WORKDIR /src
COPY pyproject.toml ./
RUN python3 -c "import tomllib; p = tomllib.load(open('pyproject.toml', 'rb'))['project']; e = p['optional-dependencies']; print('\n'.join(p['dependencies'] + e['service'] + e['parallel']))" > /tmp/requirements.txt
RUN --mount=type=secret,id=cacert,required=false \
    --mount=type=cache,target=/root/.cache/pip \
    if [ -s /run/secrets/cacert ]; then \
        export PIP_CERT=/run/secrets/cacert REQUESTS_CA_BUNDLE=/run/secrets/cacert; \
    fi \
    && /opt/venv/bin/pip install -r /tmp/requirements.txt

# Then the package itself (not editable; tests, docs, benchmarks stay out, see .dockerignore).
COPY . ./
RUN --mount=type=secret,id=cacert,required=false \
    --mount=type=cache,target=/root/.cache/pip \
    if [ -s /run/secrets/cacert ]; then \
        export PIP_CERT=/run/secrets/cacert REQUESTS_CA_BUNDLE=/run/secrets/cacert; \
    fi \
    && /opt/venv/bin/pip install ".[service,parallel]" \
    && /opt/venv/bin/pip check \
    && /opt/venv/bin/python -c "import service, skelprune, distributed"


# ---------------------------------------------------------------------------------------
# runtime: the base image, the virtual environment, an unprivileged user
# ---------------------------------------------------------------------------------------
FROM ${BASE_IMAGE} AS runtime

LABEL org.opencontainers.image.title="skelprune" \
      org.opencontainers.image.description="Parameter-free Bayesian skeleton pruning as a REST service" \
      org.opencontainers.image.licenses="MIT"

RUN groupadd --gid 10001 skelprune \
    && useradd --uid 10001 --gid skelprune --no-create-home \
       --home-dir /nonexistent --shell /usr/sbin/nologin skelprune

COPY --from=build /opt/venv /opt/venv

# Compile every numba kernel once, here, into a cache that ships with the image: the
# server copies it into NUMBA_CACHE_DIR at start (SKELPRUNE_NUMBA_CACHE_SEED), so a new
# container loads compiled code instead of compiling for a minute. numba keys the cache
# on each source file's time stamp, which a COPY between stages may change: so it is
# built in this stage, on the files as they are in the image.
# NUMBA_CPU_NAME=generic (here and at run time, below): code for any x86-64 CPU, so the
# cache is valid on whatever host the image runs (numba keys its cache on the CPU too).
RUN NUMBA_CACHE_DIR=/opt/numba-cache NUMBA_NUM_THREADS=1 NUMBA_CPU_NAME=generic \
    /opt/venv/bin/python -m service.compile

# The worker pool gives the parallelism: one BLAS/OpenMP/numba thread per worker process.
# numba compiles with cache=True; its cache goes to a writable place, not the read-only
# site-packages (mount an emptyDir on /tmp with a read-only root filesystem).
ENV PATH=/opt/venv/bin:$PATH \
    PYTHONUNBUFFERED=1 \
    PYTHONDONTWRITEBYTECODE=1 \
    SKELPRUNE_HOST=0.0.0.0 \
    SKELPRUNE_PORT=8000 \
    OMP_NUM_THREADS=1 \
    OPENBLAS_NUM_THREADS=1 \
    MKL_NUM_THREADS=1 \
    NUMBA_NUM_THREADS=1 \
    NUMBA_CACHE_DIR=/tmp/numba-cache \
    NUMBA_CPU_NAME=generic \
    SKELPRUNE_NUMBA_CACHE_SEED=/opt/numba-cache

WORKDIR /tmp
USER 10001:10001
EXPOSE 8000

# No curl in the image: the health check is a python one-liner (exit 1 on any failure).
HEALTHCHECK --interval=30s --timeout=5s --start-period=120s --retries=3 \
    CMD ["python", "-c", "import os, urllib.request as u; u.urlopen('http://127.0.0.1:%s/healthz' % os.environ.get('SKELPRUNE_PORT', '8000'), timeout=4)"]

# SIGTERM: stop accepting, finish the requests in flight, exit 0.
STOPSIGNAL SIGTERM
CMD ["python", "-m", "service"]
