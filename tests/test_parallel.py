"""``make test`` as two pytest sessions at once: what ``--part`` and ``--notebooks`` select
(conftest.py) and how ``tests/parallel.py`` reports and exits."""

import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import conftest

ROOT = Path(__file__).resolve().parents[1]


class _Config:
    def __init__(self, part, notebooks=""):
        self.options = {"--part": part, "--notebooks": notebooks}
        self.deselected = []
        self.hook = SimpleNamespace(pytest_deselected=lambda items: self.deselected.extend(items))

    def getoption(self, name):
        return self.options[name]


def _items():
    def item(nodeid, fixtures=(), stem=None):
        out = SimpleNamespace(nodeid=nodeid, fixturenames=list(fixtures))
        if stem:
            out.callspec = SimpleNamespace(params={"stem": stem})
        return out
    return [item("tests/test_a.py::test_unit"),
            item("tests/test_notebooks.py::test_extra_run", ["notebook_runs"]),
            item("tests/test_notebooks.py::test_tables[01_x]", ["nbval_output"], "01_x"),
            item("tests/test_notebooks.py::test_tables[02_y]", ["nbval_output"], "02_y"),
            item("tests/test_notebooks.py::test_style[02_y]", [], "02_y"),
            item("notebooks/01_x.ipynb::Cell 0"), item("notebooks/02_y.ipynb::Cell 0")]


def _select(part, notebooks=""):
    items, config = _items(), _Config(part, notebooks)
    conftest._select(config, items)
    kept = [i.nodeid for i in items]
    assert sorted(kept + [i.nodeid for i in config.deselected]) == \
        sorted(i.nodeid for i in _items())          # every item is kept or reported deselected
    return kept


def test_the_two_parts_share_out_every_test_once():
    unit, notebooks = _select("unit"), _select("notebooks")
    assert not set(unit) & set(notebooks)
    assert set(unit) | set(notebooks) == {i.nodeid for i in _items()}
    assert notebooks == ["tests/test_notebooks.py::test_tables[01_x]",
                         "tests/test_notebooks.py::test_tables[02_y]",
                         "notebooks/01_x.ipynb::Cell 0", "notebooks/02_y.ipynb::Cell 0"]
    # a test about a notebook that does not need nbval's run of it is a unit test
    assert "tests/test_notebooks.py::test_style[02_y]" in unit
    assert _select("all") == [i.nodeid for i in _items()]


def test_notebooks_picks_the_cells_and_the_checks_of_those_notebooks():
    assert _select("notebooks", "02") == ["tests/test_notebooks.py::test_tables[02_y]",
                                          "notebooks/02_y.ipynb::Cell 0"]
    # the unit tests are never filtered by notebook
    assert "tests/test_notebooks.py::test_style[02_y]" in _select("unit", "01")


def _run(tmp_path, *sessions):
    for name, body in (("test_ok.py", "def test_ok():\n    print('ran ok')\n"),
                       ("test_bad.py", "def test_bad():\n    assert 0, 'failed here'\n")):
        (tmp_path / name).write_text(body)
    (tmp_path / "pytest.ini").write_text("[pytest]\n")
    common = f"-c {tmp_path / 'pytest.ini'} --rootdir {tmp_path} -p no:cacheprovider -q"
    return subprocess.run([sys.executable, str(ROOT / "tests" / "parallel.py"),
                           *(f"{common} {tmp_path / s}" for s in sessions)],
                          cwd=tmp_path, capture_output=True, text=True, timeout=300)


def test_parallel_exits_zero_only_when_every_session_passes(tmp_path):
    ok = _run(tmp_path, "test_ok.py", "test_ok.py")
    assert ok.returncode == 0, ok.stdout + ok.stderr
    assert "2 pytest sessions" in ok.stdout and "exit codes [0, 0]" in ok.stdout
    bad = _run(tmp_path, "test_ok.py", "test_bad.py")
    assert bad.returncode == 1
    # the second session's report is printed whole, after its header
    head = bad.stdout.index("(ran alongside; exit 1)")
    assert bad.stdout.index("failed here") > head
    assert bad.stdout.index("1 passed") < head          # the first session printed live
