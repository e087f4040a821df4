# rotorflow: every target installs what it needs first, and does nothing when all is there.
SHELL := bash
.SHELLFLAGS := -eu -o pipefail -c
.DELETE_ON_ERROR:
.DEFAULT_GOAL := help
MAKEFLAGS += --warn-undefined-variables --no-builtin-rules

PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
# pytest processes for `make test` (pytest-xdist; `auto`: one per core)
TEST_WORKERS ?= auto
NUMBA_STAMP := $(VENV)/.numba-cache
CASE ?= examples/default.toml
SWEEP ?= examples/lambda_wrap_sweep.toml
OPTIMISE_CASE ?= examples/optimise_table1_inner_ev2.toml
PYTEST_ARGS ?=

-include mk/*.mk

.PHONY: help venv demo test lint bench case sweep optimise map report clean export

help: ## list the targets
	@grep -hE '^[a-zA-Z_-]+:.*## ' $(MAKEFILE_LIST) | awk -F':.*## ' '{printf "  %-10s %s\n", $$1, $$2}'

$(STAMP): pyproject.toml
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[dev]'
	@touch $@

# numba's cache of the compiled right-hand side and segment loop (~80 s CPU once, kept
# in ~/.cache under a hash of the sources; without it the model runs in numpy)
$(NUMBA_STAMP): $(STAMP) $(wildcard quasi1d/*.py)
	$(PY) -m rotorflow.quasi1d.compiled
	@touch $@

venv: $(NUMBA_STAMP) ## create .venv, install rotorflow with its Python dependencies, fill numba's cache

demo: $(NUMBA_STAMP) ## set up, then run the built-in default case through every stage (cached)
	$(VENV)/bin/rotorflow run examples/default.toml

case: $(NUMBA_STAMP) ## run what a case asks for, skipping what is cached: make case CASE=path/to/case.toml
	$(VENV)/bin/rotorflow run $(CASE)

sweep: $(NUMBA_STAMP) ## run a sweep on a local Dask cluster: make sweep SWEEP=examples/lambda_wrap_sweep.toml
	$(VENV)/bin/rotorflow sweep $(SWEEP)

optimise: $(NUMBA_STAMP) ## multi-objective search of a case's [optimise] section: make optimise CASE=examples/optimise_table1_inner_ev2.toml
	$(VENV)/bin/rotorflow optimise $(if $(filter command line,$(origin CASE)),$(CASE),$(OPTIMISE_CASE))

map: $(NUMBA_STAMP) ## performance map over speed and pressure ([map] section): make map CASE=... (into build/map/<case>)
	$(VENV)/bin/rotorflow map $(CASE)

report: $(STAMP) ## HTML report of a case (build/<case>/report/index.html): make report CASE=...
	$(VENV)/bin/rotorflow run $(CASE) --want report

export: $(STAMP) ## solids and machining files of a case: make export CASE=... (into build/<case>/export)
	$(VENV)/bin/rotorflow export $(CASE) --out build/$(basename $(notdir $(CASE)))/export

test: $(STAMP) openfoam ## set up, then run the tests (all tiers but slow)
	@# numba's cache is filled beside the tests (a fresh clone would otherwise wait ~80 s
	@# for it); tests that need it before it is ready compile it themselves, the others
	@# run in numpy until it is there.  The tests run on TEST_WORKERS processes (xdist),
	@# a test file to a process, so that a file's module fixtures are built once.
	$(MAKE) --no-print-directory $(NUMBA_STAMP) > $(VENV)/numba-cache.log 2>&1 &
	$(PY) -m pytest -m "not slow" -n $(TEST_WORKERS) --dist loadfile --durations=20 $(PYTEST_ARGS)

lint: $(STAMP) ## ruff over the whole tree
	$(VENV)/bin/ruff check .

bench: $(NUMBA_STAMP) ## run-time-vs-error benchmarks into bench/results/
	$(PY) -m bench.run

clean: ## remove build outputs (keeps .venv)
	rm -rf build bench/results .pytest_cache .ruff_cache
