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
	@touch $(STAMP)

demo: $(STAMP)
	$(BIN)/vmnav sim snapshot --world lab --seed 1 --x 8 --y 10 --yaw 0 --out $(OUT)/lab
	$(BIN)/vmnav sim snapshot --world campus --seed 1 --x 26 --y 7 --yaw 30 --out $(OUT)/campus

test: $(STAMP) lint
	$(BIN)/python -m pytest -q

lint: $(STAMP)
	$(BIN)/ruff check .

bench: $(STAMP)
	$(BIN)/vmnav bench sim

clean:
	rm -rf $(VENV) out .pytest_cache .ruff_cache
