# Quick start: `make run` (set up and serve), `make test` (set up and test).
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin

.PHONY: setup run client test lint bench eval openapi clean

# One stamp per set of extras: `make run` installs only what serving needs, `make test`
# and `make bench` add theirs to the same .venv (pip keeps what is already there).
# pip's own output goes to .venv/pip.log, shown only when it fails.
$(VENV)/.installed-%: pyproject.toml
	@test -x $(BIN)/python || { echo "setup: creating $(VENV) with $(PYTHON)"; $(PYTHON) -m venv $(VENV); }
	@echo "setup: installing skelprune with the extras [$(subst +,$(comma),$*)] into $(VENV) (log: $(VENV)/pip.log)"
	@$(BIN)/python -m pip install --disable-pip-version-check --upgrade pip > $(VENV)/pip.log 2>&1 \
		&& $(BIN)/python -m pip install --disable-pip-version-check -e '.[$(subst +,$(comma),$*)]' >> $(VENV)/pip.log 2>&1 \
		|| { tail -n 30 $(VENV)/pip.log; echo "setup: pip failed; the whole log is $(VENV)/pip.log"; exit 1; }
	@touch $@

comma := ,
# `make run` adds the graph extra: the README's first example calls to_networkx()
SERVE := $(VENV)/.installed-service+graph
TESTS := $(VENV)/.installed-service+test+geo+parallel+napari
BENCH := $(VENV)/.installed-service+test+geo+parallel+napari+bench
# numba's cache is keyed on each source file's time stamp: compile again when one changes
KERNELS := $(VENV)/.compiled

# Compile the numba kernels ahead (loaded in under a second afterwards), not on the
# first request or in every worker.
$(KERNELS): $(SERVE) $(shell find skelprune -name "*.py") service/worker/jobs.py
	@echo "setup: compiling the numba kernels (once; half a minute to a minute)"
	@$(BIN)/python -m service.compile
	@touch $(KERNELS)

setup: $(BENCH) $(KERNELS)

run: $(SERVE) $(KERNELS)
	@echo "serve: python -m service on http://$${SKELPRUNE_HOST:-127.0.0.1}:$${SKELPRUNE_PORT:-8000} (Ctrl-C stops it; the log is JSON lines)"
	@$(BIN)/python -m service

# examples/client.py against a running service (`make run` in another terminal)
CLIENT := $(VENV)/.installed-service+client
client: $(CLIENT)
	@$(BIN)/python examples/client.py http://$${SKELPRUNE_HOST:-127.0.0.1}:$${SKELPRUNE_PORT:-8000}

# the viewer page's browser test drives Debian's Chromium (installed once, with apt)
BROWSER := /usr/bin/chromedriver
$(BROWSER):
	bash scripts/install-browser.sh

# the napari widget's and the QGIS provider's tests (tests/frontends/) need QGIS, Xvfb and
# the libraries Qt loads: Debian's packages, installed once, with apt
FRONTENDS := /usr/bin/qgis_process.bin /usr/bin/Xvfb
$(FRONTENDS):
	bash scripts/install-frontends.sh

test: lint $(KERNELS) $(BROWSER) $(FRONTENDS)
	$(BIN)/python -m pytest -q

# ruff (lint and format) for the Python, mypy for the library's types (its settings and
# gaps: pyproject.toml, docs/typing.md), shellcheck for the shell scripts CI runs
PY_SOURCES := skelprune service tests testkit benchmarks evaluation qgis
lint: $(TESTS)
	$(BIN)/ruff check $(PY_SOURCES)
	$(BIN)/ruff format --check $(PY_SOURCES)
	$(BIN)/python -m mypy
	$(BIN)/shellcheck scripts/*.sh .ci/run

bench: $(BENCH) $(KERNELS)
	$(BIN)/python -m benchmarks

eval: $(BENCH) $(KERNELS)
	$(BIN)/python -m evaluation --out docs

openapi: $(SERVE)
	$(BIN)/python -m service.apidocs.openapi_md > openapi.md

clean:
	rm -rf $(VENV) .pytest_cache .ruff_cache build *.egg-info
