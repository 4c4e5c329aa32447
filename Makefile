# Two targets matter: `make demo` and `make test`; both create the environment first.
PYTHON ?= python3.11
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

DOCS_STAMP := $(VENV)/.installed-docs

.PHONY: venv demo test lint typecheck bench docs clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
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

test: lint typecheck
	$(BIN)/pytest
	NUMBA_DISABLE_JIT=1 $(BIN)/pytest -q -p no:cacheprovider tests/unit/test_stack.py \
		tests/unit/estimation tests/integration/test_stack_golden.py::test_short_run_reproduces_the_pinned_start

$(DOCS_STAMP): $(STAMP)
	$(BIN)/python -m pip install --quiet -e '.[dev,docs]'
	touch $(DOCS_STAMP)

# the site in docs/_build/html: warnings are errors, the examples of examples/ run
docs: $(DOCS_STAMP)
	MPLBACKEND=Agg $(BIN)/sphinx-build -W --keep-going -b html docs docs/_build/html
	@echo "Open docs/_build/html/index.html"

bench: $(STAMP)
	$(BIN)/python bench/run.py

clean:
	rm -rf $(VENV) out .pytest_cache .mypy_cache .ruff_cache docs/_build docs/api docs/auto_examples
	rm -f docs/sg_execution_times.rst
	find src -name __pycache__ -prune -exec rm -rf {} +
