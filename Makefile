# `make demo` and `make test` bootstrap .venv themselves: the stamp file is
# rebuilt whenever pyproject.toml changes.
PYTHON ?= python3
VENV := .venv
STAMP := $(VENV)/.installed
BIN := $(VENV)/bin
OUT ?= out

.PHONY: demo test test-fast lint bench clean docs

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test,lint]'
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/springlab demo --output $(OUT)

# random order (pytest-randomly): the header prints the seed, replay an order with ARGS=--randomly-seed=N;
# on every core (pytest-xdist, one worker per core; every test is independent and seeded): JOBS=1 for one process
# one BLAS thread per worker: the workers already fill the cores, and OpenBLAS's own threads on top of them
# oversubscribe (a 200 x 200 eig: 0.09 s alone, 0.75 s with its threads on two busy cores);
# compiled bytecode cached even where the environment turns it off (PYTHONDONTWRITEBYTECODE=1, common in
# containers): the suite starts dozens of interpreters (the workers, commands run as processes, scenario
# scripts, notebook kernels, dask workers), and each compiled springlab's and the tests' sources anew:
# collection 5.8 -> 3.1 s of CPU per worker, the quick loop 181 -> 170 s of CPU (__pycache__ is gitignored)
ARGS ?=
JOBS ?= auto
TEST_ENV := OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 PYTHONDONTWRITEBYTECODE=
test: $(STAMP)
	$(TEST_ENV) $(BIN)/python -m pytest -n $(JOBS) --dist loadgroup $(ARGS)

# the quick loop: everything but the tests marked slow (> ~5 s on one core)
test-fast: $(STAMP)
	$(TEST_ENV) $(BIN)/python -m pytest -n $(JOBS) --dist loadgroup -m "not slow" $(ARGS)

# ruff (lint and format) over the whole tree, mypy over src/ (config in pyproject.toml)
lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/mypy

# every user-facing path against its floor in one run (benchmarks/bench.py, which also runs every older
# bench_*.py): benchmarks/results.md and results.json; then check.py fails if a ratio is over its budget
bench: $(STAMP)
	$(BIN)/python benchmarks/bench.py
	$(BIN)/python benchmarks/check.py

clean:
	rm -rf $(VENV) $(OUT) build dist site

# the documentation site (mkdocs.yml): docs/ as the guide and the API reference generated from the docstrings,
# into site/ (gitignored); --strict turns every warning (a broken link or anchor, an unreadable docstring) into a failure
DOCS_STAMP := $(VENV)/.installed-docs
$(DOCS_STAMP): $(STAMP)
	$(BIN)/python -m pip install --quiet -e '.[docs]'
	touch $(DOCS_STAMP)

docs: $(DOCS_STAMP)
	$(BIN)/mkdocs build --strict
