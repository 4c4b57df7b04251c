# mtaccuracy: every target creates .venv from environment.txt when it is missing.
#   make reproduce                        the notebooks whose inputs changed, then the scorecard
#   make reproduce NB=03 PARAMS="n_samples=1000 seed=7"   one notebook, with checked parameters
#   make reproduce FORCE=1                every notebook again
#   make sweep NB=02 SEEDS=5 [PARAMS="n_base=4096|8192"]  a notebook over seeds (and settings)
#   make test                             lint and the tests (about two minutes)
#   make check                            what CI adds: nbval on every notebook, the book, the wheel
#   make lab | book | explore | bench | lock | clean
#
# NB, PARAMS, LAB_ARGS and EXPLORE_ARGS reach the programs as typed: make does not expand them
# ($(value ...)), the shell passes them as one quoted word, and Python splits them with shlex,
# never a shell.  PYTHONPATH makes every command run this checkout's library, whichever
# checkout the .venv was made in.

SHELL := /bin/bash
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed-$(shell cat environment.txt pyproject.toml | cksum | cut -d' ' -f1)
export PYTHONPATH := $(CURDIR)/lib
NB ?= all
PARAMS ?=
SEEDS ?= 5
CORES ?=
PROFILE ?=
LAB_ARGS ?=
EXPLORE_ARGS ?=
BENCH_ARGS ?=
override NB := $(value NB)
override PARAMS := $(value PARAMS)
override LAB_ARGS := $(value LAB_ARGS)
override EXPLORE_ARGS := $(value EXPLORE_ARGS)
export NB PARAMS LAB_ARGS EXPLORE_ARGS BENCH_ARGS
PIP := $(PY) -m pip --disable-pip-version-check --no-input
WORKFLOW := $(PY) -m mtaccuracy.compendium.workflow

.PHONY: reproduce sweep test check book explore browser lab bench clean distclean lint venv lock

venv: $(STAMP)

$(STAMP): environment.txt pyproject.toml
	@echo "==> setting up $(VENV) from environment.txt (first time: a few minutes)"
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	@$(PIP) install --quiet "$$(grep -E '^pip==' environment.txt)"
	@$(PIP) install --quiet -r environment.txt
	@$(PIP) install --quiet --no-deps --no-build-isolation -e .
	@rm -f $(VENV)/.installed-*
	@touch $@
	@echo "==> $(VENV) ready"

# Snakemake (workflow/Snakefile) with all the cores, re-running a notebook only when its source,
# the library modules it imports, its data or its parameters changed.
reproduce: $(STAMP)
	@$(WORKFLOW) reproduce --nb "$$NB" --params "$$PARAMS" $(if $(FORCE),--force) \
	    $(if $(CORES),--cores $(CORES)) $(if $(PROFILE),--profile $(PROFILE))

sweep: $(STAMP)
	@$(WORKFLOW) sweep --nb "$$NB" --seeds $(SEEDS) --params "$$PARAMS" \
	    $(if $(CORES),--cores $(CORES)) $(if $(PROFILE),--profile $(PROFILE))

# The book (Sphinx + MyST-NB, book theme) from the committed notebooks and figures/, executing
# nothing; every output shown is checked against its provenance.json first.
book: $(STAMP)
	@$(PY) -m mtaccuracy.apps.book

# The interactive explorer (Panel) on 127.0.0.1; EXPLORE_ARGS for more (--port N).
explore: $(STAMP)
	@$(PY) -m mtaccuracy.apps.explore --from-env

# JupyterLab as Jupyter starts it (127.0.0.1, a token), at the repository root; LAB_ARGS are
# JupyterLab's own options, passed on untouched (yours to answer for).
lab: $(STAMP)
	@$(PY) -m mtaccuracy.apps.lab

# Debian's Chromium for the browser tests (root; apt-get; never a browser download).
browser:
	bash .ci/install-browser

lint: $(STAMP)
	$(PY) -m ruff check lib tests notebooks conftest.py

# Lint, then the tests on both cores (pytest-xdist).
test: $(STAMP)
	$(PY) -m ruff check lib tests notebooks conftest.py
	$(PY) -m pytest -n auto tests

# What CI adds to `make test`: nbval executes every committed notebook (into build/check/, never
# over figures/) and compares its marked cells; then every regenerated table is compared with
# the committed one within its declared tolerance; the book is built and opened in Chromium; the
# wheel is built and its examples run outside the repository.
check: $(STAMP)
	rm -rf build/check
	$(PY) tests/notebook_copies.py build/check
	$(PY) -m pytest -n auto --dist loadfile --nbval-lax --nbval-current-env build/check/notebooks
	$(PY) -m pytest -n auto --check-dir=build/check tests/check

# The speed targets; BENCH_ARGS=--quick skips timing make reproduce and make test themselves.
bench: $(STAMP)
	@$(PY) -m mtaccuracy.apps.bench --from-env

# Regenerate the lock in a private, throw-away venv from the direct requirements that
# pyproject.toml declares (.ci/direct-requirements).
lock:
	@set -e; tmp=$$(mktemp -d); trap 'rm -rf "$$tmp"' EXIT; \
	$(PYTHON) -m venv "$$tmp/venv"; \
	"$$tmp/venv/bin/pip" install --quiet --upgrade pip setuptools; \
	$(PYTHON) .ci/direct-requirements > "$$tmp/direct.txt"; \
	"$$tmp/venv/bin/pip" install --quiet -r "$$tmp/direct.txt"; \
	{ echo "# Full pip lock for mtaccuracy: 'pip freeze --all' in a clean Python 3.11 venv after"; \
	  echo "# installing the direct requirements of pyproject.toml (dependencies and the"; \
	  echo "# compendium and test extras: .ci/direct-requirements). Regenerate with 'make lock'."; \
	  "$$tmp/venv/bin/pip" freeze --all; } > "$$tmp/environment.txt"; \
	mv "$$tmp/environment.txt" environment.txt

# Caches, the workflow's runs and records (build/, .snakemake/), the tests' outputs.
clean:
	rm -rf build .snakemake .pytest_cache .ruff_cache .test-output
	find . -path ./.venv -prune -o -name __pycache__ -type d -exec rm -rf {} +
	find . -path ./.venv -prune -o -name .ipynb_checkpoints -type d -exec rm -rf {} +

distclean: clean
	rm -rf $(VENV) lib/*.egg-info
