# Two entry points, each sets itself up on a fresh machine (Python >= 3.11 with venv).
#   make demo  — install, then run the main job (see README)
#   make test  — install with test extras, lint (ruff), type-check (mypy), run the test
#                suite's fast tier, then build the documentation (make docs)
#   make test-slow — the slow tier (tests marked `slow`: long physics and benchmark checks),
#                time-boxed by SLOW_BUDGET; CI runs it after `make test`
PYTHON ?= python3
VENV   ?= .venv
BIN     = $(VENV)/bin

.PHONY: demo test test-slow setup lint typecheck docs clean

# the slow tier's time box (coreutils timeout): a hang ends the job, not an assertion
SLOW_BUDGET ?= 45m

$(BIN)/echocal: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[test,fast,docs,visa,bluesky]"
	touch $(BIN)/echocal

setup: $(BIN)/echocal

demo: setup
	$(BIN)/echocal demo --out echocal-out/demo --overwrite

lint: setup
	$(BIN)/ruff check src tests docs $(wildcard benchmarks)

typecheck: setup
	$(BIN)/mypy

test: lint typecheck
	$(BIN)/python -m pytest -n 2 --dist worksteal -m "not slow" --durations=25
	$(MAKE) docs

test-slow: setup
	timeout --foreground --kill-after=1m $(SLOW_BUDGET) \
		$(BIN)/python -m pytest -n 2 --dist worksteal -m slow --durations=25

# The documentation site (Sphinx): warnings are errors, every gallery example is executed.
docs: setup
	rm -rf docs/_build docs/api/generated docs/auto_examples
	MPLBACKEND=Agg $(BIN)/sphinx-build -j auto -W --keep-going -q -b html docs docs/_build/html
	@echo "docs: docs/_build/html/index.html"

clean:
	rm -rf $(VENV) echocal-out docs/_build docs/api/generated docs/auto_examples
