# Two entry points, each self-contained on a machine with python3 and make:
#   make demo   set up .venv and run the calibration workflow on two built-in arms (planar, six-axis)
#               and on the six-axis industrial-6r (a laser tracker, three reflectors)
#   make test   set up .venv with the test extras and run lint, types and tests
#   make test-slow   the few long end-to-end checks (CI runs them after make test)
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
DEMO_DIR ?= demo-out
DEMO_6R_DIR ?= demo-6r
LINT_PATHS := src tests tools $(wildcard benchmarks)

.PHONY: demo test test-slow lint types bench readme clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

# The stamp files record which extras are installed; pyproject.toml changes re-install.
# Installing is most of a fresh clone's `make test`: uv (a pip-compatible installer,
# used here only to set up .venv) installs in parallel and byte-compiles on every
# core, about 25 s against pip's 55-60 s here. Where uv cannot be had, pip does the
# same job: it installs without its one-core byte-compilation, and compileall then
# compiles on every core (the byte-code is only a cache, so a file that does not
# compile, such as a package's deliberately broken test file, is no error).
define INSTALL
	( $(BIN)/python -m pip install --quiet --disable-pip-version-check uv \
	  && $(BIN)/uv pip install --quiet --python $(BIN)/python --compile-bytecode -e '$(1)' ) \
	|| ( $(BIN)/python -m pip install --quiet --disable-pip-version-check --no-compile -e '$(1)' \
	  && ( $(BIN)/python -m compileall -q -j 0 $(VENV)/lib > /dev/null 2>&1 || true ) )
endef

$(VENV)/.installed: pyproject.toml | $(BIN)/python
	$(call INSTALL,.)
	touch $@

$(VENV)/.installed-test: pyproject.toml | $(BIN)/python
	$(call INSTALL,.[test])
	touch $@ $(VENV)/.installed

demo: $(VENV)/.installed
	$(BIN)/armcal demo -o $(DEMO_DIR)
	$(BIN)/armcal demo --robot industrial-6r -o $(DEMO_6R_DIR)

lint: $(VENV)/.installed-test
	$(BIN)/ruff check $(LINT_PATHS)
	$(BIN)/ruff format --check $(LINT_PATHS)

types: $(VENV)/.installed-test
	$(BIN)/mypy

# Two workers, one BLAS thread each: this project's machines have 2 cores, and
# OpenBLAS's own thread pool on top of two workers oversubscribes them.
TEST_ENV := OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 MKL_NUM_THREADS=1

# A few tests start the armcal program as a real process (the rest run it
# in-process); compiling its modules once first saves each start the ~0.3 s of
# compiling them again where PYTHONDONTWRITEBYTECODE is set.
COMPILE := $(BIN)/python -m compileall -q -j 0 src

test: lint types
	$(COMPILE)
	$(TEST_ENV) $(BIN)/python -m pytest -n 2 src tests

test-slow: $(VENV)/.installed-test
	$(COMPILE)
	$(TEST_ENV) $(BIN)/python -m pytest -n 2 -m slow tests

bench: $(VENV)/.installed
	$(BIN)/python benchmarks/bench_design.py
	$(BIN)/python benchmarks/bench_order.py
	$(BIN)/python benchmarks/bench_simulate.py
	$(BIN)/python benchmarks/bench_scale.py
	$(BIN)/python benchmarks/bench_spatial.py
	$(BIN)/python benchmarks/bench_spatial_design.py
	$(BIN)/python benchmarks/bench_spatial_compliance.py
	$(BIN)/python benchmarks/bench_outliers.py
	$(BIN)/python benchmarks/bench_floor.py
	$(BIN)/python benchmarks/bench_floor_spatial.py
	$(BIN)/python benchmarks/bench_design_floor.py
	$(BIN)/python benchmarks/bench_startup.py

# Run every example of README.md and write its real output into it (and docs/img/).
readme: $(VENV)/.installed
	$(BIN)/python tools/readme.py

clean:
	rm -rf $(VENV) $(DEMO_DIR) .pytest_cache .ruff_cache .mypy_cache
