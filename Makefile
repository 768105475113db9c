# `make demo` and `make test` bootstrap .venv themselves: the stamp file is
# rebuilt whenever pyproject.toml changes.
PYTHON ?= python3
VENV := .venv
STAMP := $(VENV)/.installed
BIN := $(VENV)/bin
OUT ?= out

.PHONY: demo test lint bench clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test,lint]'
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/springlab demo --output $(OUT)

# random order (pytest-randomly): the header prints the seed, replay an order with ARGS=--randomly-seed=N;
# a quick loop without the slow tests: make test ARGS='-m "not slow"'
ARGS ?=
test: $(STAMP)
	$(BIN)/python -m pytest $(ARGS)

# ruff (lint and format) over the whole tree, mypy over src/ (config in pyproject.toml)
lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/mypy

bench: $(STAMP)
	for b in benchmarks/bench_*.py; do echo "== $$b"; $(BIN)/python $$b || exit 1; done

clean:
	rm -rf $(VENV) $(OUT) build dist
