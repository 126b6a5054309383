# Quick start: `make run` (set up and serve), `make test` (set up and test).
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: setup run test lint bench eval openapi clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[service,test,bench]'
	touch $(STAMP)

setup: $(STAMP)

run: $(STAMP)
	$(BIN)/python -m service

test: lint
	$(BIN)/python -m pytest -q

# ruff for the Python, shellcheck for the shell scripts CI runs
lint: $(STAMP)
	$(BIN)/ruff check skelprune service tests testkit benchmarks
	$(BIN)/shellcheck scripts/*.sh .ci/run

bench: $(STAMP)
	$(BIN)/python -m benchmarks

eval: $(STAMP)
	$(BIN)/skelprune eval --out docs

openapi: $(STAMP)
	$(BIN)/python -m service.openapi_md > openapi.md

clean:
	rm -rf $(VENV) .pytest_cache .ruff_cache build *.egg-info
