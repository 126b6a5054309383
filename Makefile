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

setup: $(BENCH)

run: $(SERVE)
	$(BIN)/python -m service

test: lint
	$(BIN)/python -m pytest -q

lint: $(TESTS)
	$(BIN)/ruff check skelprune service tests benchmarks
	$(BIN)/shellcheck scripts/*.sh .ci/run

bench: $(BENCH)
	$(BIN)/python -m benchmarks

eval: $(BENCH)
	$(BIN)/skelprune eval --out docs

openapi: $(SERVE)
	$(BIN)/python -m service.openapi_md > openapi.md

clean:
	rm -rf $(VENV) .pytest_cache .ruff_cache build *.egg-info
