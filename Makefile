# Quick start: `make run` (set up and serve), `make test` (set up and test).
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
# numba's cache is keyed on each source file's time stamp: compile again when one changes
KERNELS := $(VENV)/.compiled

.PHONY: setup run test lint bench eval openapi clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[service,test,bench]'
	touch $(STAMP)

# Compile the numba kernels ahead (loaded in under a second afterwards), not on the
# first request or in every worker.
$(KERNELS): $(STAMP) $(shell find skelprune -name "*.py") service/jobs.py
	$(BIN)/python -m service.compile
	touch $(KERNELS)

setup: $(KERNELS)

run: $(KERNELS)
	$(BIN)/python -m service

test: lint $(KERNELS)
	$(BIN)/python -m pytest -q

# ruff (lint and format) for the Python, shellcheck for the shell scripts CI runs
PY_SOURCES := skelprune service tests testkit benchmarks
lint: $(STAMP)
	$(BIN)/ruff check $(PY_SOURCES)
	$(BIN)/ruff format --check $(PY_SOURCES)
	$(BIN)/shellcheck scripts/*.sh .ci/run

bench: $(KERNELS)
	$(BIN)/python -m benchmarks

eval: $(KERNELS)
	$(BIN)/skelprune eval --out docs

openapi: $(STAMP)
	$(BIN)/python -m service.openapi_md > openapi.md

clean:
	rm -rf $(VENV) .pytest_cache .ruff_cache build *.egg-info
