# mtaccuracy: every target creates .venv from environment.txt when it is missing.
#   make reproduce              all notebooks (two at a time), in place; then the scorecard
#   make reproduce NB=03        one notebook (a number, a stem or a path)
#   make reproduce NB=03 PARAMS="n_samples=1000 seed=7"   with validated parameters
#   make lab LAB_ARGS="--port 9999"                       JupyterLab on 127.0.0.1
#   make book                                             the book (build/book/html) from what is committed
#   make explore EXPLORE_ARGS="--port 5007"               the interactive explorer on 127.0.0.1
#   make test | bench | clean | lock
#
# NB, PARAMS, LAB_ARGS, LAB_UNSAFE and EXPLORE_ARGS reach the programs raw, through the
# environment: make does not expand them ($(value ...) below: PARAMS='seed=$(shell ...)' is
# text, $HOME stays $HOME) and Python's shlex splits them, never a shell: PARAMS="--check;
# touch x" is an error.
#
# Every target first checks that .venv is this checkout's own (ownenv.py: a .venv shared with
# another checkout would run that checkout's code) and finishes a commit of results that a
# killed run left half done (mtaccuracy.compendium.commit).

SHELL := /bin/bash
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed-$(shell cat environment.txt pyproject.toml | cksum | cut -d' ' -f1)
NB ?= all
PARAMS ?=
LAB_ARGS ?=
LAB_UNSAFE ?=
override NB := $(value NB)
override PARAMS := $(value PARAMS)
override LAB_ARGS := $(value LAB_ARGS)
override LAB_UNSAFE := $(value LAB_UNSAFE)
export NB PARAMS LAB_ARGS LAB_UNSAFE
PIP := $(PY) -m pip --disable-pip-version-check --no-input
OWN_VENV := $(PY) -I lib/mtaccuracy/compendium/ownenv.py
RECOVER := PYTHONPATH=lib $(PYTHON) -m mtaccuracy.compendium.commit
GUARD := @$(OWN_VENV) && $(RECOVER)

.PHONY: reproduce book explore browser test test-notebooks lab bench clean distclean lint venv lock

venv: $(STAMP)

$(STAMP): environment.txt pyproject.toml
	@echo "==> setting up $(VENV) from environment.txt (first time: a few minutes)"
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	@$(OWN_VENV)
	@$(PIP) install --quiet "$$(grep -E '^pip==' environment.txt)"
	@$(PIP) install --quiet -r environment.txt
	@$(PIP) install --quiet --no-deps --no-build-isolation -e .
	@rm -f $(VENV)/.installed-*
	@touch $@
	@echo "==> $(VENV) ready"

reproduce: $(STAMP)
	$(GUARD)
	@$(PY) -m mtaccuracy.compendium.runner --from-env
	@$(PY) -m mtaccuracy.compendium.reproduction gather

# The book (Sphinx + MyST-NB, book theme) from the committed notebooks and figures/, executing
# nothing; checks every output shown against its provenance.json (exit 1 names what is wrong).
book: $(STAMP)
	$(GUARD)
	@$(PY) -m mtaccuracy.compendium.book

# The interactive explorer (Panel) on 127.0.0.1; EXPLORE_ARGS for more (--port N).
EXPLORE_ARGS ?=
override EXPLORE_ARGS := $(value EXPLORE_ARGS)
export EXPLORE_ARGS
explore: $(STAMP)
	$(GUARD)
	@$(PY) -m mtaccuracy.compendium.explore --from-env

# Debian's Chromium and ChromeDriver for the browser test (root; apt-get; never a browser download).
browser:
	bash .ci/install-browser

# Two pytest sessions at once (tests/parallel.py): the unit tests, and nbval's notebook checks
# with the tests of what they wrote; `.venv/bin/python -m pytest` alone runs both in one session.
test: $(STAMP)
	$(GUARD)
	$(PY) -m ruff check lib tests notebooks conftest.py
	$(PY) tests/parallel.py "--part=unit" "--part=notebooks"

# The notebook checks alone: nbval executes every notebook and compares its marked cells, then
# the regenerated CSVs are compared (two sessions, the notebooks shared out by running time);
# CI runs them once more with OPENBLAS_NUM_THREADS=1.
test-notebooks: $(STAMP)
	$(GUARD)
	$(PY) tests/parallel.py "--part=notebooks --notebooks=01,03,04,07" \
	    "--part=notebooks --notebooks=02,05,06"

lint: $(STAMP)
	$(GUARD)
	$(PY) -m ruff check lib tests notebooks conftest.py

# At the repository root, opening on notebooks/; bound to 127.0.0.1 with a token; --allow-root
# when run as root (containers); LAB_ARGS for more.
lab: $(STAMP)
	$(GUARD)
	@$(PY) -m mtaccuracy.compendium.lab

# The speed targets; BENCH_ARGS=--quick skips timing make reproduce and make test themselves.
BENCH_ARGS ?=
export BENCH_ARGS
bench: $(STAMP)
	$(GUARD)
	@$(PY) -m mtaccuracy.compendium.bench --from-env

# Regenerate the lock in a throw-away venv from the direct requirements pyproject.toml declares
# (.ci/direct-requirements: dependencies and the compendium and test extras).
lock:
	rm -rf /tmp/mtaccuracy-lock && $(PYTHON) -m venv /tmp/mtaccuracy-lock
	/tmp/mtaccuracy-lock/bin/pip install --quiet --upgrade pip setuptools
	$(PYTHON) .ci/direct-requirements > /tmp/mtaccuracy-lock/direct.txt
	/tmp/mtaccuracy-lock/bin/pip install --quiet -r /tmp/mtaccuracy-lock/direct.txt
	{ echo "# Full pip lock for mtaccuracy: 'pip freeze --all' in a clean Python 3.11 venv after"; \
	  echo "# installing the direct requirements of pyproject.toml (dependencies and the"; \
	  echo "# compendium and test extras: .ci/direct-requirements). Regenerate with 'make lock'."; \
	  /tmp/mtaccuracy-lock/bin/pip freeze --all; } > environment.txt.new
	mv environment.txt.new environment.txt

# First finishes a commit a killed run left half done and removes what dead runs left (staging
# folders, temporary notebooks; a live run's are kept): never a pending commit's files.
clean:
	@$(RECOVER)
	rm -rf notebooks/.running notebooks/.failed .pytest_cache .ruff_cache .test-output build
	rm -rf figures/index.html figures/html figures/.runs.json
	find . -path ./.venv -prune -o -name __pycache__ -type d -exec rm -rf {} +
	find . -path ./.venv -prune -o -name .ipynb_checkpoints -type d -exec rm -rf {} +

distclean: clean
	rm -rf $(VENV) notebooks/.backup lib/*.egg-info
