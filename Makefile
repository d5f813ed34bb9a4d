# Quick start: `make demo` and `make test`. Both create .venv and install the project.
PYTHON ?= python3
# Python writes the bytecode of the project's modules (and pytest its rewritten tests)
# into __pycache__, where numba's cache already is, though the environment says not to:
# with PYTHONDONTWRITEBYTECODE set, every process of the test suite (pytest's workers,
# the commands they start, their pool and Ray workers) compiled the project's modules
# from source again, and each pytest worker rewrote every test module (docs/speed.md).
unexport PYTHONDONTWRITEBYTECODE
VENV := .venv
BIN := $(VENV)/bin
DEMO_OUT ?= demo_results

.PHONY: demo lint test test-fast bench clean lock docs wheel-check

# The venv, with uv in it (pinned; pip installs it): uv installs the locks, about 10 s on a
# fresh machine where pip took 30-50 s (it fetches in parallel and links from its cache;
# docs/speed.md). pip stays in the venv for the user's own installs.
UV_VERSION := 0.13.9
$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

# Its own target, so that a venv made before uv was used gets it too.
$(BIN)/uv: $(BIN)/python
	$(BIN)/python -m pip install -q "uv==$(UV_VERSION)"

# The exact environment: requirements.lock (the base install) and requirements-test.lock
# (with the test and Ray extras) pin every package with its hashes (--require-hashes, as
# pip's hash-checking mode); the project itself is installed on top without dependencies
# (its build backend, setuptools, is in the lock). `make lock` makes both again from
# pyproject.toml's ranges. LOCK=no installs from the ranges instead (Python 3.10, which the
# lock's numpy does not support; `make clean` first).
LOCK ?= yes
UV_PIP := $(BIN)/uv pip install -q --python $(BIN)/python
ifeq ($(LOCK),yes)
INSTALL_BASE = $(UV_PIP) --compile-bytecode --require-hashes -r requirements.lock
INSTALL_TEST = $(UV_PIP) --require-hashes -r requirements-test.lock
SELF = $(UV_PIP) --no-deps --no-build-isolation -e .
else
INSTALL_BASE = $(UV_PIP) --compile-bytecode -e .
INSTALL_TEST = $(UV_PIP) -e ".[test,ray]"
SELF = true
endif

# One stamp per set of extras, redone when pyproject.toml or a lock changes. The test
# lock holds the base lock's every package at its version (make lock), so one install of
# it stands for both stamps: make test on a fresh clone installs once, not twice. It does
# not compile every installed module to bytecode (make demo's base install does): the
# test processes write the bytecode of what they import, once (docs/speed.md).
$(VENV)/.installed: $(BIN)/uv pyproject.toml requirements.lock
	$(INSTALL_BASE)
	$(SELF)
	touch $@

$(VENV)/.installed-test: $(BIN)/uv pyproject.toml requirements.lock requirements-test.lock
	$(INSTALL_TEST)
	$(SELF)
	touch $@ $(VENV)/.installed

# The venv's uv; --fork-strategy fewest: one version of each package for every Python
# from 3.11 on, the base lock the test lock's versions.
UV_COMPILE = $(BIN)/uv pip compile pyproject.toml --universal --fork-strategy fewest \
	--python-version 3.11 --generate-hashes --quiet
lock: $(BIN)/uv
	$(UV_COMPILE) --extra test --extra ray -o requirements-test.lock
	$(UV_COMPILE) -c requirements-test.lock -o requirements.lock

demo: $(VENV)/.installed
	$(BIN)/ebrl demo --out $(DEMO_OUT)

# ruff (pyproject.toml's [tool.ruff]); make test runs it first, so CI (.ci/run) lints.
lint: $(VENV)/.installed-test
	$(BIN)/ruff check .

# The tests in two tiers (pyproject.toml's `slow` marker). make test first compiles every
# kernel once into numba's cache (experiments/ops/warm.py: on a fresh clone the tests'
# processes would each compile the same kernels at once; the boxhead is the tests' robot of
# the one realisation no shipped robot has, joint_motors), then runs every test on two
# workers (tests/conftest.py keeps the tests that start Ray or PostgreSQL on one), the 15
# slowest listed at the end; make test-fast, the edit loop, runs the unit tier: the
# equations, kernels, parsers and command-line refusals in process, no test that starts
# processes, renders a video, runs a study or checks a golden run.
test: lint $(VENV)/.installed-test
	$(BIN)/python -m experiments.ops.warm tests/mounts/boxhead.toml
	$(BIN)/python -m pytest -q -n 2 --dist loadgroup --durations=15

test-fast: lint $(VENV)/.installed-test
	$(BIN)/python -m pytest -q -n 2 -m "not slow" --durations=5

# The docs site (mkdocs.yml): docs/, with the README as its home page and RESULTS.md,
# EVOLVE.md and CHANGELOG.md beside it, and an API page from the docstrings, built into
# site/ with --strict: a broken link or anchor, or a page missing from the nav, fails it
# (make test builds it too: tests/test_docs_site.py). MkDocs is in the test extra's lock.
docs: $(VENV)/.installed-test
	$(BIN)/mkdocs build --strict

bench: $(VENV)/.installed
	$(BIN)/ebrl bench

# The wheel a user installs (pip install .), built from the tracked files into a fresh
# virtual environment with the locks' packages: every module imported, ebrl --help, ebrl
# robots and a short ebrl run from it (experiments/ops/wheel.py; make test does all but
# the run, whose kernels compile anew there: about 40 s).
wheel-check: $(VENV)/.installed
	$(BIN)/python -m experiments.ops.wheel --run

clean:
	rm -rf $(VENV) $(DEMO_OUT) .pytest_cache site
