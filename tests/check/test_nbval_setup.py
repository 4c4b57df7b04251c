"""The notebook checks are nbval's own: the project's pytest configuration makes ``pytest
notebooks`` run each notebook through nbval with ``--nbval-lax``, so a cell marked
``# NBVAL_CHECK_OUTPUT`` whose output changed fails, an unmarked one does not, and a cell that
raises fails.  Shown here on small notebooks in a temporary folder, run with this repository's
pytest configuration (a separate pytest process, ``-c pyproject.toml``)."""

import subprocess
import sys
from pathlib import Path

import nbformat
import pytest

ROOT = Path(__file__).resolve().parents[2]


def _notebook(path, stored: str, code: str = "print(6 * 7)", marked: bool = True) -> None:
    nb = nbformat.v4.new_notebook()
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3",
                                 "language": "python"}
    cell = nbformat.v4.new_code_cell(("# NBVAL_CHECK_OUTPUT\n" if marked else "") + code)
    cell.outputs = [nbformat.v4.new_output("stream", name="stdout", text=stored)]
    cell.execution_count = 2
    nb.cells = [nbformat.v4.new_code_cell("x = 1", execution_count=1), cell]
    nbformat.write(nb, path)


def _run(path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "pytest", "-c", str(ROOT / "pyproject.toml"),
                           "--rootdir", str(path.parent), "-p", "no:cacheprovider", "-q",
                           str(path)], cwd=path.parent, capture_output=True, text=True,
                          timeout=300)


@pytest.mark.parametrize(("stored", "code", "marked", "passes"), [
    ("42\n", "print(6 * 7)", True, True),
    ("41\n", "print(6 * 7)", True, False),     # a marked cell printing something else fails
    ("41\n", "print(6 * 7)", False, True),     # an unmarked cell is executed, not compared
    ("42\n", "raise ValueError('bad')", False, False),  # any cell that raises fails
], ids=["same-output", "changed-output", "unmarked", "raises"])
def test_pytest_runs_notebooks_through_nbval(tmp_path, stored, code, marked, passes):
    nb = tmp_path / "check.ipynb"
    _notebook(nb, stored, code, marked)
    res = _run(nb)
    assert (res.returncode == 0) == passes, res.stdout[-2000:] + res.stderr[-2000:]
    assert "passed" in res.stdout or "failed" in res.stdout
