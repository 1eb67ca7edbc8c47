# Two commands do everything on a fresh machine with python3 (>= 3.11) and make:
#   make demo   -- bootstrap .venv, then run the showcase
#   make test   -- bootstrap .venv, then lint and run the test suite
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
OUT    ?= out/demo

.PHONY: demo test lint bench clean

$(STAMP): pyproject.toml
	@$(PYTHON) -c 'import sys; sys.exit(0 if sys.version_info >= (3, 11) else "vmnav needs Python >= 3.11, found " + sys.version.split()[0])'
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	$(BIN)/python -c 'from sim.renderer import compile_kernels; compile_kernels()'
	@touch $(STAMP)

demo: $(STAMP)
	$(BIN)/vmnav demo --out $(OUT)

test: $(STAMP) lint
	$(BIN)/python -m pytest -q -n 2 --dist worksteal

lint: $(STAMP)
	$(BIN)/ruff check .

bench: $(STAMP)
	$(BIN)/vmnav bench sim

clean:
	rm -rf $(VENV) out .pytest_cache .ruff_cache
