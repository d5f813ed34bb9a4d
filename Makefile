# Quick start: `make demo` and `make test`. Both create .venv and install the project.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
DEMO_OUT ?= demo_results

.PHONY: demo lint test bench clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip

# One stamp per set of extras, redone when pyproject.toml changes.
$(VENV)/.installed: $(BIN)/python pyproject.toml
	$(BIN)/python -m pip install -q -e .
	touch $@

$(VENV)/.installed-test: $(VENV)/.installed
	$(BIN)/python -m pip install -q -e ".[test,ray]"
	touch $@

demo: $(VENV)/.installed
	$(BIN)/ebrl demo --out $(DEMO_OUT)

# ruff (pyproject.toml's [tool.ruff]); make test runs it first, so CI (.ci/run) lints.
lint: $(VENV)/.installed-test
	$(BIN)/ruff check .

# Two workers (tests/conftest.py keeps the tests that start Ray or PostgreSQL on one);
# the 15 slowest tests listed at the end (make test stays under 10 minutes on 2 cores).
test: lint $(VENV)/.installed-test
	$(BIN)/python -m pytest -q -n 2 --dist loadgroup --durations=15

bench: $(VENV)/.installed
	$(BIN)/ebrl bench

clean:
	rm -rf $(VENV) $(DEMO_OUT) .pytest_cache
