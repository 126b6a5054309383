# Quick start: `make run` (set up and serve), `make test` (set up and test).
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin

.PHONY: setup run test lint bench eval openapi clean

# One stamp per set of extras: `make run` installs only what serving needs, `make test`
# and `make bench` add theirs to the same .venv (pip keeps what is already there).
$(VENV)/.installed-%: pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[$(subst +,$(comma),$*)]'
	touch $@

comma := ,
SERVE := $(VENV)/.installed-service
TESTS := $(VENV)/.installed-service+test
BENCH := $(VENV)/.installed-service+test+bench
# numba's cache is keyed on each source file's time stamp: compile again when one changes
KERNELS := $(VENV)/.compiled

# Compile the numba kernels ahead (loaded in under a second afterwards), not on the
# first request or in every worker.
$(KERNELS): $(SERVE) $(shell find skelprune -name "*.py") service/jobs.py
	$(BIN)/python -m service.compile
	touch $(KERNELS)

setup: $(BENCH) $(KERNELS)

run: $(SERVE) $(KERNELS)
	$(BIN)/python -m service

# the viewer page's browser test drives Debian's Chromium (installed once, with apt)
BROWSER := /usr/bin/chromedriver
$(BROWSER):
	bash scripts/install-browser.sh

test: lint $(KERNELS) $(BROWSER)
	$(BIN)/python -m pytest -q

# ruff (lint and format) for the Python, shellcheck for the shell scripts CI runs
PY_SOURCES := skelprune service tests testkit benchmarks
lint: $(TESTS)
	$(BIN)/ruff check $(PY_SOURCES)
	$(BIN)/ruff format --check $(PY_SOURCES)
	$(BIN)/shellcheck scripts/*.sh .ci/run

bench: $(BENCH) $(KERNELS)
	$(BIN)/python -m benchmarks

eval: $(BENCH) $(KERNELS)
	$(BIN)/skelprune eval --out docs

openapi: $(SERVE)
	$(BIN)/python -m service.openapi_md > openapi.md

clean:
	rm -rf $(VENV) .pytest_cache .ruff_cache build *.egg-info
