# Two targets matter: `make demo` and `make test`; both create the environment first.
PYTHON ?= python3.11
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
DOCS_STAMP := $(VENV)/.installed-docs
# every package version the tests pass with (CPython 3.11, Linux x86-64); `make lock` writes it
LOCK := requirements/lock.txt
# pip reads the lock as constraints, in the build environments too
PIP_LOCKED := PIP_CONSTRAINT=$(abspath $(LOCK)) $(BIN)/python -m pip install --quiet
LATEST := .venv-latest

.PHONY: venv demo check test test-latest lint typecheck lock bench docs clean

$(STAMP): pyproject.toml $(LOCK)
	$(PYTHON) -m venv $(VENV)
	$(PIP_LOCKED) pip setuptools
	$(PIP_LOCKED) -e '.[dev]'
	@echo "compiling the closed loops ahead of the first run (about a minute, once)"
	$(BIN)/motosim cache warm
	touch $(STAMP)

venv: $(STAMP)

demo: $(STAMP)
	mkdir -p out
	$(BIN)/motosim paper --out out/paper --overwrite
	$(BIN)/motosim modes --range 2:60:0.5 --plot out/modes.png --overwrite > out/modes.txt
	@echo "Open out/paper/index.html: the paper's section V regenerated, one report per run."

lint: $(STAMP)
	$(BIN)/ruff check src tests bench scripts examples docs
	$(BIN)/ruff format --check src tests bench scripts examples docs

typecheck: $(STAMP)
	$(BIN)/mypy

# a contributor's quick check: lint, types and the tests not marked slow (tests/conftest.py)
check: lint typecheck
	$(BIN)/pytest -q -p no:randomly -m "not slow"

# the whole suite, in its file order, on the locked versions
test: lint typecheck
	$(BIN)/pytest -p no:randomly
	NUMBA_DISABLE_JIT=1 $(BIN)/pytest -q -p no:cacheprovider -p no:randomly tests/unit/test_stack.py \
		tests/unit/estimation tests/integration/test_stack_golden.py::test_short_run_reproduces_the_pinned_start

# the tests not marked slow on the newest versions pyproject.toml's ranges allow, in a shuffled
# order (the seed is printed: `pytest -p randomly --randomly-seed=N` repeats it), with
# OpenBLAS's kernels of another x86 CPU, so that drift, an order dependence or a claim decided
# by rounding shows up; `make test-latest LATEST_TESTS=` runs the whole suite so (as long
# again as `make test`)
LATEST_TESTS ?= -m "not slow"
test-latest:
	rm -rf $(LATEST)
	$(PYTHON) -m venv $(LATEST)
	$(LATEST)/bin/python -m pip install --quiet --upgrade pip setuptools
	$(LATEST)/bin/python -m pip install --quiet --upgrade --upgrade-strategy eager -e '.[dev]'
	$(LATEST)/bin/python -m pip freeze --exclude-editable > $(LATEST)/versions.txt
	@echo "newest versions: $(LATEST)/versions.txt (against $(LOCK): diff them)"
	$(if $(filter x86_64,$(shell uname -m)),OPENBLAS_CORETYPE=Prescott) $(LATEST)/bin/pytest -p randomly -p no:cacheprovider $(LATEST_TESTS)

# write the lock from a fresh environment of today's newest versions within the ranges; then
# run `make test` (and `make docs`) on it before committing it
lock:
	rm -rf .venv-lock
	$(PYTHON) -m venv .venv-lock
	.venv-lock/bin/python -m pip install --quiet --upgrade pip setuptools wheel
	.venv-lock/bin/python -m pip install --quiet '.[dev,docs]'
	mkdir -p $(dir $(LOCK))
	{ echo "# make lock: every package version the tests pass with (CPython 3.11, Linux x86-64)"; \
	  .venv-lock/bin/python -m pip freeze --all --exclude-editable | grep -iv '^motosim'; } > $(LOCK)
	rm -rf .venv-lock build
	@echo "wrote $(LOCK); now: make clean test docs"

$(DOCS_STAMP): $(STAMP)
	$(PIP_LOCKED) -e '.[dev,docs]'
	touch $(DOCS_STAMP)

# the site in docs/_build/html: warnings are errors, the examples of examples/ run
docs: $(DOCS_STAMP)
	MPLBACKEND=Agg $(BIN)/sphinx-build -W --keep-going -b html docs docs/_build/html
	@echo "Open docs/_build/html/index.html"

bench: $(STAMP)
	$(BIN)/python bench/run.py

clean:
	rm -rf $(VENV) $(LATEST) out .pytest_cache .mypy_cache .ruff_cache docs/_build docs/api docs/auto_examples
	rm -f docs/sg_execution_times.rst
	find src -name __pycache__ -prune -exec rm -rf {} +
