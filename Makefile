# Two commands do everything on a fresh machine with python3 (>= 3.11) and make:
#   make demo   -- bootstrap .venv, then run the showcase
#   make test   -- bootstrap .venv, then lint and run the test suite
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
OUT    ?= out/demo
# The web app's browser tests (tests/ground/web/) drive Debian's headless Chromium through
# its ChromeDriver; `browser` installs both with apt-get when either is missing.
CHROMIUM     ?= /usr/bin/chromium
CHROMEDRIVER ?= /usr/bin/chromedriver
APT_GET      ?= apt-get

.PHONY: demo test lint bench clean browser

$(STAMP): pyproject.toml
	@$(PYTHON) -c 'import sys; sys.exit(0 if sys.version_info >= (3, 11) else "vmnav needs Python >= 3.11, found " + sys.version.split()[0])'
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	$(BIN)/python -c 'from sim.renderer import compile_kernels; compile_kernels()'
	@touch $(STAMP)

browser:
	@if [ -x $(CHROMIUM) ] && [ -x $(CHROMEDRIVER) ]; then exit 0; fi; \
	sudo=""; [ "$$(id -u)" = 0 ] || sudo="sudo"; \
	echo "make: installing Debian's chromium and chromium-driver for the browser tests"; \
	{ $$sudo $(APT_GET) update -qq && \
	  DEBIAN_FRONTEND=noninteractive $$sudo $(APT_GET) install -y -qq chromium chromium-driver \
	  && [ -x $(CHROMIUM) ] && [ -x $(CHROMEDRIVER) ]; } || { \
	  echo "make: the browser tests need $(CHROMIUM) and $(CHROMEDRIVER), and installing" \
	       "them failed: run 'apt-get install chromium chromium-driver' as root (or install" \
	       "Chromium and ChromeDriver there), then make again" >&2; exit 1; }

# The showcase teaches the two routes its mission drives: the corridor it starts on and the
# office loop its goal lies on (`vmnav demo` alone teaches all three of the lab's routes,
# the north loop too: about half a minute more on two cores).
demo: $(STAMP)
	$(BIN)/vmnav demo --routes corridor,office_loop --out $(OUT)

# Bytecode for the project's own modules first: the suite starts hundreds of Python
# processes, and where PYTHONDONTWRITEBYTECODE is set none of them would write it, so each
# would compile every module it imports again (about 0.3 s of CPU per process).
# Three workers on two cores: each computes on one thread (tests/conftest.py), and the
# hardware-in-the-loop tests, which run in real time, leave their core idle part of the
# time (on an idle 2-core machine: 8 min 25 s with 3, 10 min 25 s with 2).
TEST_WORKERS ?= 3
test: $(STAMP) lint browser
	$(BIN)/python -m compileall -q -j 0 shared robot ground sim tools tests >/dev/null
	$(BIN)/python -m pytest -q -n $(TEST_WORKERS) --dist worksteal

lint: $(STAMP)
	$(BIN)/ruff check .

bench: $(STAMP)
	$(BIN)/vmnav bench sim

clean:
	rm -rf $(VENV) out .pytest_cache .ruff_cache
