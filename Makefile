# Two entry points, each sets itself up on a fresh machine (Python >= 3.11 with venv).
#   make demo  — install, then run the main job (see README)
#   make test  — install with test extras, lint (ruff), type-check (mypy), run the test suite
PYTHON ?= python3
VENV   ?= .venv
BIN     = $(VENV)/bin

.PHONY: demo test setup lint typecheck clean

$(BIN)/echocal: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[test,fast]"
	touch $(BIN)/echocal

setup: $(BIN)/echocal

demo: setup
	$(BIN)/echocal demo --out echocal-out/demo --overwrite

lint: setup
	$(BIN)/ruff check src tests $(wildcard benchmarks)

typecheck: setup
	$(BIN)/mypy

test: lint typecheck
	$(BIN)/python -m pytest -n 2 --timeout=600

clean:
	rm -rf $(VENV) echocal-out
