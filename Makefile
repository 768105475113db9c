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
ARGS ?=
JOBS ?= auto
test: $(STAMP)
	$(BIN)/python -m pytest -n $(JOBS) --dist loadgroup $(ARGS)

# the quick loop: everything but the tests marked slow (> ~5 s on one core)
test-fast: $(STAMP)
	$(BIN)/python -m pytest -n $(JOBS) --dist loadgroup -m "not slow" $(ARGS)

# ruff (lint and format) over the whole tree, mypy over src/ (config in pyproject.toml)
lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/mypy

bench: $(STAMP)
	for b in benchmarks/bench_*.py; do echo "== $$b"; $(BIN)/python $$b || exit 1; done

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
