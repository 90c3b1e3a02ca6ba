# Two entry points, each sets itself up on a fresh machine (Python >= 3.11 with venv).
#   make demo  — install the package with its fast engines (numba, embree), then run the
#                demo: a simulated calibration study and the thesis comparison
#   make test  — install with the test, docs and rig extras, lint (ruff), type-check (mypy),
#                run the test suite's fast tier, then build the documentation (make docs)
#   make test-slow — the slow tier (tests marked `slow`: long physics and benchmark checks),
#                time-boxed by SLOW_BUDGET; CI runs it after `make test`
# Each installs only what it needs, once: a stamp file in the venv remembers which extras
# are in (reinstalled when pyproject.toml changes).  --no-compile: Python compiles the
# modules a command imports when it first imports them, not every module of every package.
PYTHON ?= python3
VENV   ?= .venv
BIN     = $(VENV)/bin
PIP     = $(BIN)/python -m pip install --quiet --disable-pip-version-check --no-compile

.PHONY: demo test test-slow setup setup-test lint typecheck docs clean

# the slow tier's time box (coreutils timeout): a hang ends the job, not an assertion
SLOW_BUDGET ?= 45m

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

# core (numba included) + fast (embree): what `echocal demo` and everyday use need
$(VENV)/.installed-demo: pyproject.toml | $(BIN)/python
	$(PIP) -e ".[fast]"
	touch $@

# + test, docs and the rig extras (VISA simulator, bluesky): the whole suite runs, none skipped
$(VENV)/.installed-test: pyproject.toml | $(BIN)/python
	$(PIP) -e ".[fast,test,docs,visa,bluesky]"
	touch $@ $(VENV)/.installed-demo

setup: $(VENV)/.installed-demo

setup-test: $(VENV)/.installed-test

demo: setup
	$(BIN)/echocal demo --out echocal-out/demo --overwrite

lint: setup-test
	$(BIN)/ruff check src tests docs $(wildcard benchmarks)

typecheck: setup-test
	$(BIN)/mypy

test: lint typecheck
	$(BIN)/python -m pytest -n 2 --dist worksteal -m "not slow" --durations=25
	$(MAKE) docs

test-slow: setup-test
	timeout --foreground --kill-after=1m $(SLOW_BUDGET) \
		$(BIN)/python -m pytest -n 2 --dist worksteal -m slow --durations=25

# The documentation site (Sphinx): warnings are errors, every gallery example is executed.
docs: setup-test
	rm -rf docs/_build docs/api/generated docs/auto_examples
	MPLBACKEND=Agg $(BIN)/sphinx-build -j auto -W --keep-going -q -b html docs docs/_build/html
	@echo "docs: docs/_build/html/index.html"

clean:
	rm -rf $(VENV) echocal-out docs/_build docs/api/generated docs/auto_examples
