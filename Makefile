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
	$(PY) -m rotorflow.quasi1d.compiled  # numba's cache of the compiled right-hand side and segment loop (~2 min once)
	@touch $@

venv: $(STAMP) ## create .venv and install rotorflow with its Python dependencies

demo: $(STAMP) ## set up, then run the built-in default case through every stage (cached)
	$(VENV)/bin/rotorflow run examples/default.toml

case: $(STAMP) ## run what a case asks for, skipping what is cached: make case CASE=path/to/case.toml
	$(VENV)/bin/rotorflow run $(CASE)

sweep: $(STAMP) ## run a sweep on a local Dask cluster: make sweep SWEEP=examples/lambda_wrap_sweep.toml
	$(VENV)/bin/rotorflow sweep $(SWEEP)

optimise: $(STAMP) ## multi-objective search of a case's [optimise] section: make optimise CASE=examples/optimise_table1_inner_ev2.toml
	$(VENV)/bin/rotorflow optimise $(if $(filter command line,$(origin CASE)),$(CASE),$(OPTIMISE_CASE))

map: $(STAMP) ## performance map over speed and pressure ([map] section): make map CASE=... (into build/map/<case>)
	$(VENV)/bin/rotorflow map $(CASE)

report: $(STAMP) ## HTML report of a case (build/<case>/report/index.html): make report CASE=...
	$(VENV)/bin/rotorflow run $(CASE) --want report

export: $(STAMP) ## solids and machining files of a case: make export CASE=... (into build/<case>/export)
	$(VENV)/bin/rotorflow export $(CASE) --out build/$(basename $(notdir $(CASE)))/export

test: $(STAMP) openfoam ## set up, then run the tests (all tiers but slow)
	$(PY) -m pytest -m "not slow" $(PYTEST_ARGS)

lint: $(STAMP) ## ruff over the whole tree
	$(VENV)/bin/ruff check .

bench: $(STAMP) ## run-time-vs-error benchmarks into bench/results/
	$(PY) -m bench.run

clean: ## remove build outputs (keeps .venv)
	rm -rf build bench/results .pytest_cache .ruff_cache
