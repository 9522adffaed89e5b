# Two commands on a fresh machine with only python3: `make demo` and `make test`.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin

.PHONY: demo test core lint typecheck bench urdf docs api screenshots clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

# What `make demo` needs: pinrate and its dependencies, editable.
$(VENV)/.runtime: $(BIN)/python pyproject.toml
	$(BIN)/python -m pip install --quiet -e .
	touch $@

# What `make test` needs besides: the test extra (pytest, ruff, mypy, playwright, ...).
$(VENV)/.installed: $(VENV)/.runtime
	$(BIN)/python -m pip install --quiet -e ".[test]"
	touch $@

# The compiled core (core/, pinrate_core): built where a C++ compiler works, skipped where
# none does (pinrate then runs its pure-Python path). PINRATE_CORE=0 skips it on purpose.
# It is the README's own command, `pip install ./core`, with pip's build isolation: the
# headers and build tools come from core/pyproject.toml's build-system.requires. It costs
# about 2 minutes of compile time and 3.2 GB of memory, once.
PINRATE_CORE ?= 1
$(VENV)/.core: $(VENV)/.runtime core/pyproject.toml core/CMakeLists.txt $(wildcard core/src/*)
	@if [ "$(PINRATE_CORE)" = 0 ]; then \
		$(BIN)/python -m pip uninstall --quiet --yes pinrate-core 2>/dev/null; \
		echo "pinrate: the compiled core is off (PINRATE_CORE=0): the pure-Python path runs"; \
		echo 0 > $@; \
	elif echo "pinrate: building the compiled core (about 2 minutes, once; PINRATE_CORE=0 skips it)" && \
		$(BIN)/python -m pip install ./core > $(VENV)/core-build.log 2>&1; then \
		echo "pinrate: compiled core built ($$($(BIN)/python -c 'import pinrate.compiled as c; print(c.backend())'))"; \
		echo 1 > $@; \
	else \
		$(BIN)/python -m pip uninstall --quiet --yes pinrate-core 2>/dev/null; \
		grep -m 3 -E "CMake Error|error:|not able to compile|not found:" $(VENV)/core-build.log | sed 's/^ */  /'; \
		echo "pinrate: the compiled core did not build (no C++ compiler? $(VENV)/core-build.log says why):"; \
		echo "pinrate: the pure-Python path runs, with the same results"; \
		echo failed > $@; \
	fi

# A change of PINRATE_CORE rebuilds (or removes) the core; a build that failed is tried again.
ifneq ($(shell cat $(VENV)/.core 2>/dev/null),$(PINRATE_CORE))
.PHONY: $(VENV)/.core
endif

core: $(VENV)/.core

demo: $(VENV)/.core
	$(BIN)/pinrate demo ur5

# The static checks first (seconds), then the suite.
test: lint $(VENV)/.core
	$(BIN)/python -m pytest -q

LINTED := src tests examples benchmarks docs .ci
lint: $(VENV)/.installed
	$(BIN)/ruff check $(LINTED)
	$(BIN)/ruff format --check $(LINTED)
	$(BIN)/lint-imports
	$(BIN)/mypy src/pinrate

typecheck: $(VENV)/.installed
	$(BIN)/mypy src/pinrate

bench: $(VENV)/.installed
	$(BIN)/python benchmarks/step.py

clean:
	rm -rf $(VENV) build core/build src/*.egg-info .pytest_cache

urdf: $(VENV)/.installed
	$(BIN)/python -c "from pinrate.robots import write_urdfs; write_urdfs('urdf')"

docs: $(VENV)/.installed
	$(BIN)/pinrate paper > docs/paper-results.md

# The API reference from the docstrings (docs/api, Sphinx) in build/api: warnings are errors
# and every cross-reference must resolve (-n); -E rereads every docstring. make test checks
# the same (tests/test_api_docs.py).
api: $(VENV)/.installed
	$(BIN)/sphinx-build -b html -E -W --keep-going -n -q docs/api build/api
	@echo "pinrate: the API reference is build/api/index.html"

# The pictures in docs/, in Chromium with Mesa's llvmpipe (docs/screenshots.py): look at them.
screenshots: $(VENV)/.core
	$(BIN)/python docs/screenshots.py
