# carom: `make demo` runs the main job, `make test` runs every check.
# Both create .venv on first use and are quick when nothing changed.

# The first Python >= 3.11 on PATH (override with `make PYTHON=/path/to/python3.12 ...`).
PYTHON ?= $(shell for p in python3 python3.13 python3.12 python3.11 python; do \
	command -v $$p >/dev/null 2>&1 && $$p -c 'import sys; sys.exit(sys.version_info < (3, 11))' 2>/dev/null \
	&& { echo $$p; break; }; done)
VENV   := .venv
BIN    := $(VENV)/bin
OUT    := out

.PHONY: pooltool demo play test lint browser unit unit-nojit clean help

help:
	@echo "make demo   set up .venv and run the showcase (results under $(OUT)/)"
	@echo "make play   the live testbed in the browser (SCENE=name or file; default pyramid)"
	@echo "make test   set up .venv with the dev tools and run lint, type checks and all tests"
	@echo "            (on every core; the kernels' own tests once more without the JIT)"
	@echo "make clean  remove .venv and $(OUT)/"

$(BIN)/python:
	@test -n "$(PYTHON)" || { echo "carom needs Python >= 3.11 on PATH (or make PYTHON=...)" >&2; exit 2; }
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

# One stamp per set of extras: reinstall only when pyproject.toml changes.
$(VENV)/.stamp-demo: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e '.[viz,io,sweep,rigid3d,play]'
	@touch $@

$(VENV)/.stamp-dev: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e '.[viz,io,view,compare,rigid3d,sweep,parquet,play,dev]'
	@touch $@ $(VENV)/.stamp-demo

demo: $(VENV)/.stamp-demo
	$(BIN)/carom showcase --out $(OUT) --force
	@echo "play with a scene live in the browser: make play  (or $(BIN)/carom play SCENE)"

# pooltool, carom compare's billiards reference, in its own environment (its pins conflict with
# carom's Numba; docs/compare.md): ~/.cache/carom/pooltool, or $CAROM_POOLTOOL
pooltool: $(VENV)/.stamp-dev
	$(BIN)/python -m carom.compare.engines.pooltool_engine

# the live testbed (docs/play.md): serves http://127.0.0.1:8765/ and opens it; Ctrl-C stops it
SCENE ?= pyramid
play: $(VENV)/.stamp-demo
	$(BIN)/carom play $(SCENE)

lint: $(VENV)/.stamp-dev
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/mypy

# Both cores (pytest-xdist: one worker a core); `-m "not slow"` leaves out the slow system tests
# when iterating (CI and make test run them).
PYTEST := $(BIN)/python -m pytest -n auto

unit: $(VENV)/.stamp-dev
	$(PYTEST)

# The kernels' own tests once more as plain Python, so that kernel code is exercised without
# the JIT (DESIGN.md): the kernel packages' tests (their closed forms among them) and doctests,
# the reference twins and the regression tests that drive them; runs of millions of collisions
# are skipped there (marker needs_jit).
KERNEL_TESTS := tests/engines tests/geometry tests/laws tests/reference tests/regression \
	src/carom/engines src/carom/geometry src/carom/laws
unit-nojit: $(VENV)/.stamp-dev
	NUMBA_DISABLE_JIT=1 $(PYTEST) -q $(KERNEL_TESTS)

# Debian's chromium for the browser tests of carom play (playwright, from PyPI, drives it: its
# own browser download cannot work here). apt-get installs it once, as root or through sudo;
# where neither can, the browser tests say what is missing (and fail under CI=true).
browser:
	@command -v chromium >/dev/null 2>&1 || { \
		echo "installing Debian's chromium for the browser tests (apt-get)"; \
		if [ "$$(id -u)" -eq 0 ]; then SUDO=""; else SUDO="sudo -n"; fi; \
		$$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install \
			-y -qq --no-install-recommends chromium >/dev/null; \
	} || echo "could not install chromium; the browser tests will say so"

test: lint browser unit unit-nojit

clean:
	rm -rf $(VENV) $(OUT)
