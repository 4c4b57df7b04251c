"""Test-session setup shared by the unit tests and the notebook (nbval) items.

Executed notebooks write their figures and tables under ``.test-output/`` (through
``$MTACCURACY_OUTPUT_BASE``), never over the committed ``figures/``; items marked
``after_notebooks`` run after every notebook item, so they can compare what the notebooks
just regenerated with what is committed.
"""

import os
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent
# One folder per test session, so that two sessions running at once cannot clear each other's
# regenerated outputs; it is removed when the session ends, except the browser test's
# screenshot, kept in .test-output/report/.
TEST_OUTPUT = ROOT / ".test-output" / f"session-{os.getpid()}"


def pytest_configure(config):
    shutil.rmtree(TEST_OUTPUT, ignore_errors=True)
    TEST_OUTPUT.mkdir(parents=True)
    os.environ["MTACCURACY_OUTPUT_BASE"] = str(TEST_OUTPUT)


def pytest_unconfigure(config):
    # keep the browser test's screenshot (.test-output/report/index.png), drop the rest
    kept = TEST_OUTPUT / "report"
    if kept.is_dir():
        target = TEST_OUTPUT.parent / "report"
        shutil.rmtree(target, ignore_errors=True)
        shutil.move(str(kept), target)
    shutil.rmtree(TEST_OUTPUT, ignore_errors=True)


def pytest_collection_modifyitems(config, items):
    late = [i for i in items if i.get_closest_marker("after_notebooks")]
    items[:] = [i for i in items if i not in late] + late


@pytest.fixture(scope="session")
def test_output() -> Path:
    return TEST_OUTPUT
