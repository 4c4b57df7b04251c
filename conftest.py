"""Test-session setup.

* ``make test`` runs ``tests/`` on every core (pytest-xdist); ``make check`` (CI's second stage)
  runs nbval on parameterised copies of the committed notebooks (``tests/notebook_copies.py``:
  their outputs go to ``build/check/``, never over ``figures/``), then ``tests/check/`` with
  ``--check-dir=build/check``: the regenerated tables against the committed ones, the book in
  Chromium, the wheel.
* A session-wide guard fails the run if anything in the working tree's ``figures/`` or
  ``notebooks/`` changed while the tests ran.
"""

import hashlib
import os
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent
GUARDED = [ROOT / "figures", ROOT / "notebooks"]


def _snapshot() -> dict:
    return {str(p.relative_to(ROOT)): hashlib.sha256(p.read_bytes()).hexdigest()
            for top in GUARDED for p in sorted(top.rglob("*"))
            if p.is_file() and ".ipynb_checkpoints" not in p.parts}


def _controller(config) -> bool:
    return not hasattr(config, "workerinput")  # pytest-xdist: not one of its workers


def pytest_addoption(parser):
    parser.getgroup("mtaccuracy").addoption(
        "--check-dir", default=None,
        help="tests/check: the folder make check executed the notebooks into (build/check)")


def pytest_configure(config):
    if _controller(config):
        config._mtaccuracy_guard = _snapshot()


#: Tests that run a notebook through the whole workflow (a minute on one core): scheduled first,
#: so that an xdist worker starts them while the other runs the rest, instead of one worker
#: ending the run alone with them.
SLOW_FIRST = ("tests/test_workflow.py::test_reproduce_runs_a_changed_notebook_once_and_publishes",)


def pytest_collection_modifyitems(config, items):
    items.sort(key=lambda item: not item.nodeid.startswith(SLOW_FIRST))   # stable: else as is
    if config.getoption("--check-dir"):
        return
    skip = pytest.mark.skip(reason="needs make check (--check-dir)")
    for item in items:
        if "tests/check/" in item.nodeid:
            item.add_marker(skip)


def pytest_sessionfinish(session, exitstatus):
    before = getattr(session.config, "_mtaccuracy_guard", None)
    if before is None:
        return
    after = _snapshot()
    changed = sorted(k for k in set(before) | set(after) if before.get(k) != after.get(k))
    if changed:
        print(f"\nERROR: the tests changed the working tree's figures/ or notebooks/: "
              f"{', '.join(changed[:10])}", file=sys.stderr)
        session.exitstatus = pytest.ExitCode.TESTS_FAILED


@pytest.fixture(scope="session")
def check_dir(request) -> Path:
    """Where ``make check`` executed the committed notebooks (``build/check``)."""
    return Path(request.config.getoption("--check-dir")).resolve()


#: Debian's Chromium (``.ci/install-browser``; never a browser download) and its launch
#: arguments, for the browser tests.
CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--no-first-run",
                 "--disable-quic"]
BROWSER_TIMEOUT_MS = 30_000


@pytest.fixture(scope="session")
def browser():
    """Headless Chromium driven by Playwright; a missing Chromium skips the test, or fails it
    under CI (``$CI`` set), which must install it."""
    if not CHROMIUM.exists():
        message = (f"{CHROMIUM} is missing: install Debian's chromium and chromium-driver "
                   "packages (make browser, that is .ci/install-browser, as root)")
        if os.environ.get("CI"):
            pytest.fail(message)
        pytest.skip(message)
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS,
                              timeout=BROWSER_TIMEOUT_MS)
        try:
            yield b
        finally:
            b.close()
