# Two commands on a fresh machine with only python3: `make demo` and `make test`.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin

.PHONY: demo test lint typecheck bench urdf docs clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

$(VENV)/.installed: $(BIN)/python pyproject.toml
	$(BIN)/python -m pip install --quiet -e ".[test]"
	touch $@

demo: $(VENV)/.installed
	$(BIN)/pinrate demo ur5

test: $(VENV)/.installed
	$(BIN)/ruff check src tests examples benchmarks
	$(BIN)/lint-imports
	$(BIN)/python -m pytest -q

lint: $(VENV)/.installed
	$(BIN)/ruff check src tests examples benchmarks
	$(BIN)/lint-imports

typecheck: $(VENV)/.installed
	$(BIN)/python -m pip install --quiet mypy
	$(BIN)/mypy src/pinrate

bench: $(VENV)/.installed
	$(BIN)/python benchmarks/step.py

clean:
	rm -rf $(VENV) build src/*.egg-info .pytest_cache

urdf: $(VENV)/.installed
	$(BIN)/python -c "from pinrate.robots import write_urdfs; write_urdfs('urdf')"

docs: $(VENV)/.installed
	$(BIN)/pinrate paper > docs/paper-results.md
