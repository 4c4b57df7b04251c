"""The workflow: what `make reproduce` and `make sweep` refuse before any work, how a run is
executed and published, and what it never touches.

One tiny notebook (a fixture: one kernel start for the module) stands in for the compendium's;
the Snakemake end-to-end run uses notebook 03 with small parameters, into folders outside the
repository."""

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import nbformat
import pandas as pd
import pytest

from mtaccuracy.compendium import notebook, provenance, workflow
from mtaccuracy.compendium.notebook import FIGURES, ROOT, output_folder
from mtaccuracy.papers.parameters import ParameterError

GUO = "03_guo2016_spearman_21_errors"
SMALL_03 = "n_samples=40 n_repeats=3 n_search_poses=16 n_search_samples=100 grid_step_mm=250.0"


# --- what is refused before any work ---------------------------------------------------------

@pytest.mark.parametrize(("nb", "params", "message"), [
    ("03", "n_samples=-5", "'n_samples' must be at least 10"),
    ("03", "n_sample=5", "unknown parameter(s) n_sample"),
    ("03", "seed", "parameter 'seed' must be written name=value"),
    ("03", "x_mm='unclosed", "No closing quotation"),
    ("*", "", "no notebook matches '*'"),
    ("0", "", "several notebooks match '0'"),
    ("notebooks/../README.md", "", "is not one of the compendium's notebooks"),
    ("03", "output_dir=/", "the repository or a folder that contains it"),
    ("03", "output_dir=figures/02_rong_sobol_21_errors", "another notebook's folder"),
    ("03", "output_dir=data", "a folder inside the repository that is not this notebook's"),
    ("02", "ranges_file=data/rong/no_such_file.csv", "ranges_file 'data/rong/no_such_file.csv' "
                                                      "not found"),
])
def test_bad_requests_are_refused_in_one_line(nb, params, message):
    with pytest.raises(ParameterError) as err:
        workflow.plan(nb, params)
    assert message in str(err.value)


def test_a_plan_holds_what_the_user_gave_checked_and_typed():
    assert workflow.plan("03", "n_samples=40 x_mm=5") == {GUO: {"n_samples": 40, "x_mm": 5.0}}
    assert list(workflow.plan("all", "")) == [d.stem for d in workflow.DECLARATIONS]
    assert workflow.notebooks(str(ROOT / "notebooks" / f"{GUO}.ipynb")) == [GUO]


def test_params_are_split_like_a_shell_and_never_evaluated():
    got = workflow.parse_params("a=1 b='two words' c=[1,2] d='$(touch x)' e=__import__('os')")
    assert got == {"a": 1, "b": "two words", "c": [1, 2], "d": "$(touch x)",
                   "e": "__import__(os)"}


def test_several_notebooks_with_one_output_dir_get_a_folder_each(tmp_path):
    runs = workflow.plan("all", f"output_dir={tmp_path}")
    assert {s: g["output_dir"] for s, g in runs.items()} == {
        s: str(tmp_path / s) for s in runs}


def test_a_folder_the_compendium_did_not_write_is_refused(tmp_path):
    (tmp_path / "notes.txt").write_text("mine")
    with pytest.raises(ParameterError, match="not empty and was not written by the compendium"):
        output_folder(tmp_path, GUO)
    assert output_folder(tmp_path / "new", GUO) == tmp_path / "new"
    assert output_folder("figures/" + GUO, GUO) == FIGURES / GUO


def test_a_run_that_cannot_fit_is_refused_naming_the_limit(monkeypatch):
    monkeypatch.setattr(workflow, "available_memory", lambda: (3e8, "the cgroup limit"))
    with pytest.raises(ParameterError, match=r"need about 0\.\d+ GB .* 0\.3 GB left \(the "
                                             r"cgroup limit\)"):
        workflow.check_memory({GUO: {}})
    monkeypatch.setattr(workflow, "available_memory", lambda: (8e9, "available memory"))
    assert workflow.check_memory({GUO: {}}) == 8000


def test_available_memory_is_positive_and_says_what_limits_it():
    have, what = notebook.available_memory()
    assert have > 0 and what in ("available memory", "the cgroup limit")


# --- what a run depends on ----------------------------------------------------------------------

def test_a_notebook_depends_on_the_modules_it_imports_and_the_files_it_read():
    found = [provenance.shown(p) for p in workflow.inputs(GUO, {})]
    assert "lib/mtaccuracy/papers/guo2016.py" in found
    assert "lib/mtaccuracy/sensitivity/spearman.py" in found
    assert "lib/mtaccuracy/compendium/notebook.py" in found
    assert "data/papers/guo2016_fig3_spearman_top8.csv" in found
    assert not any(f.startswith(("lib/mtaccuracy/apps/", "lib/mtaccuracy/papers/zheng"))
                   for f in found)
    # a file parameter: the file it names, wherever it is
    rong = [provenance.shown(p) for p in workflow.inputs("02_rong_sobol_21_errors", {})]
    assert "data/rong/error_ranges.csv" in rong


def test_the_import_closure_follows_relative_and_local_imports(tmp_path):
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell("from mtaccuracy.machines import build\n%matplotlib")]
    nbformat.write(nb, tmp_path / "x.ipynb")
    names = {p.relative_to(provenance.LIBRARY).as_posix()
             for p in provenance.library_modules(tmp_path / "x.ipynb")}
    assert {"mtaccuracy/__init__.py", "mtaccuracy/machines/__init__.py",
            "mtaccuracy/kinematics.py", "mtaccuracy/errors.py"} <= names
    assert not any("sensitivity" in n or "compendium" in n for n in names)


# --- the executed notebook as it is stored --------------------------------------------------------

def test_normalise_removes_what_differs_between_identical_runs():
    nb = {"metadata": {"papermill": {"start_time": "t", "duration": 3.0, "parameters": {}}},
          "cells": [
              {"cell_type": "code", "metadata": {"tags": ["parameters"]}, "source": "n = 1",
               "execution_count": 1, "outputs": []},
              {"cell_type": "code", "metadata": {"tags": ["injected-parameters"]},
               "source": "output_dir = '/x'", "execution_count": 2, "outputs": []},
              {"cell_type": "code", "metadata": {"tags": ["measured"], "papermill": {"d": 1}},
               "source": "print(t)", "execution_count": 3,
               "outputs": [{"output_type": "stream", "name": "stdout", "text": ["1.2 s\n"]}]},
              {"cell_type": "code", "metadata": {}, "source": "print(1); print(2)",
               "execution_count": 4,
               "outputs": [{"output_type": "stream", "name": "stdout", "text": ["1\n"]},
                           {"output_type": "stream", "name": "stdout", "text": ["2\n"]}]}]}
    out = workflow.normalise(nb, "99_x", {})
    assert [c["execution_count"] for c in out["cells"]] == [1, 2, 3]
    assert "start_time" not in out["metadata"]["papermill"]
    assert out["cells"][1]["outputs"][0]["text"] == [workflow.MEASURED_NOTE]
    assert out["cells"][2]["outputs"] == [{"output_type": "stream", "name": "stdout",
                                           "text": ["1\n", "2\n"]}]
    shown = workflow.normalise(nb, "99_x", {"n": 2})
    injected = shown["cells"][1]
    assert "injected-parameters" in injected["metadata"]["tags"]
    assert "".join(injected["source"]).strip().endswith("n = 2")
    assert "/x" not in json.dumps(shown)


# --- publishing: only what the previous run wrote is replaced ----------------------------------

def _run_folder(path: Path, stem: str, files: dict[str, str]) -> Path:
    path.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        (path / name).write_text(text)
    provenance.write_sidecar(path, {"run": {"notebook": stem},
                                    "files": {n: {"sha256": provenance.sha256(path / n)}
                                              for n in files}})
    return path


def test_publish_replaces_the_previous_run_and_leaves_a_users_files(tmp_path):
    target = _run_folder(tmp_path / "target", "99_x", {"a.csv": "old a", "gone.csv": "old"})
    (target / "notes.txt").write_text("mine")
    new = _run_folder(tmp_path / "run", "99_x", {"a.csv": "new a", "b.csv": "new b"})
    left = workflow.publish(new, target)
    assert (target / "a.csv").read_text() == "new a" and (target / "b.csv").exists()
    assert not (target / "gone.csv").exists()
    assert (target / "notes.txt").read_text() == "mine" and left == ["notes.txt"]
    assert provenance.read(target) == provenance.read(new)


def test_publish_refuses_before_copying_when_it_would_overwrite_an_edit(tmp_path):
    target = _run_folder(tmp_path / "target", "99_x", {"a.csv": "old a", "b.csv": "old b"})
    (target / "b.csv").write_text("edited by hand")
    before = {p.name: p.read_bytes() for p in target.iterdir()}
    new = _run_folder(tmp_path / "run", "99_x", {"a.csv": "new a", "b.csv": "new b"})
    with pytest.raises(workflow.PublishRefused, match="b.csv would be overwritten"):
        workflow.publish(new, target)
    assert {p.name: p.read_bytes() for p in target.iterdir()} == before


def test_publish_never_overwrites_a_users_file_of_the_same_name(tmp_path):
    target = tmp_path / "target"
    target.mkdir()
    (target / "a.csv").write_text("mine")
    new = _run_folder(tmp_path / "run", "99_x", {"a.csv": "new a"})
    with pytest.raises(workflow.PublishRefused):
        workflow.publish(new, target)
    assert (target / "a.csv").read_text() == "mine"


def test_an_edited_output_stops_reproduce_before_any_work(tmp_path):
    target = _run_folder(tmp_path / "t", GUO, {"a.csv": "x"})
    (target / "a.csv").write_text("y")
    assert workflow.edited_outputs(target, GUO) == ["a.csv"]


# --- sweeps -------------------------------------------------------------------------------------

def test_sweep_runs_cover_every_seed_and_setting():
    runs = workflow.sweep_runs(GUO, 3, "n_samples=40|80 x_mm=5")
    assert len(runs) == 6
    assert runs["setting2-seed20162"] == {"x_mm": 5.0, "n_samples": 80, "seed": 20162}
    with pytest.raises(ParameterError, match="no seed parameter"):
        workflow.sweep_runs("07_your_spindle", 3, "")
    with pytest.raises(ParameterError, match="'n_samples' must be at least 10"):
        workflow.sweep_runs(GUO, 2, "n_samples=40|5")


def test_summarise_counts_each_verdict_per_row(tmp_path):
    runs = {f"seed{s}": {"seed": s} for s in (1, 2, 3)}
    folders = {}
    for k, verdict in zip(runs, ("reproduced", "reproduced", "differs"), strict=True):
        folders[k] = tmp_path / k
        folders[k].mkdir()
        pd.DataFrame({"item": ["Fig. 1", "Fig. 2"], "quantity": ["a", "b"],
                      "reproduced": [k, "1"], "verdict": [verdict, "close"]}).to_csv(
            folders[k] / "reproduction.csv", index=False)
    workflow.summarise(GUO, runs, folders, tmp_path / "sweep")
    stab = pd.read_csv(tmp_path / "sweep" / "verdict_stability.csv")
    assert stab.columns.tolist() == ["item", "quantity", "reproduced", "close", "differs",
                                     "not_reproducible", "changes_with_seed"]
    assert stab.iloc[0][["reproduced", "differs"]].tolist() == [2, 1]
    assert stab.changes_with_seed.tolist() == [True, False]
    values = pd.read_csv(tmp_path / "sweep" / "values.csv")
    assert values.columns.tolist() == ["item", "quantity", "seed", "reproduced"]
    assert len(values) == 6
    assert set(provenance.read(tmp_path / "sweep")["files"]) == {"values.csv",
                                                                 "verdict_stability.csv"}


# --- one real run of a tiny notebook -----------------------------------------------------------

TINY = '''import param
from mtaccuracy.compendium import notebook, reproduction
from mtaccuracy.papers.figure import Caption
from mtaccuracy.papers.parameters import NotebookParameters, OutputFolder


class Parameters(NotebookParameters):
    stem = "99_tiny"
    n = param.Integer(3, bounds=(1, 10), doc="rows")
    output_dir = OutputFolder("figures/99_tiny", doc="where")'''


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    """A two-output notebook run once with papermill (``workflow.execute``)."""
    base = tmp_path_factory.mktemp("tiny")
    path = base / "99_tiny.ipynb"
    nb = nbformat.v4.new_notebook()
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3",
                                 "language": "python"}
    params = nbformat.v4.new_code_cell('n: int = 3  # rows\noutput_dir: str = "figures/99_tiny"'
                                       '  # where')
    params.metadata["tags"] = ["parameters"]
    timing = nbformat.v4.new_code_cell("print('took 1.23 s')")
    timing.metadata["tags"] = ["measured"]
    nb.cells = [
        nbformat.v4.new_code_cell(TINY), params,
        nbformat.v4.new_code_cell(f"run = notebook.start(Parameters, globals(), "
                                  f"notebook={str(path)!r})"),
        nbformat.v4.new_code_cell(
            "import matplotlib\nmatplotlib.use('Agg')\nimport matplotlib.pyplot as plt\n"
            "import pandas as pd\n"
            "run.table(pd.DataFrame({'i': range(n), 'x': [0.5 * i for i in range(n)]}), "
            "'t.csv')\nfig, ax = plt.subplots()\nax.plot(range(n))\n"
            "run.figure(fig, Caption('f', 'Figure 1', 'a line of {n} points').format(n=n))\n"
            "print(n)"),
        timing]
    nbformat.write(nb, path)
    run_dir = base / "run"
    workflow.execute(path, {"n": 4}, run_dir, base / "log" / "99_tiny.log")
    return base, path, run_dir


def test_a_run_writes_its_outputs_and_records_them(tiny):
    base, _, run_dir = tiny
    out = run_dir / "outputs"
    assert sorted(p.name for p in out.iterdir()) == ["f.png", "f.svg", "provenance.json",
                                                     "t.csv"]
    side = provenance.read(out)
    assert side["run"]["parameters"] == {"n": 4}
    assert side["files"]["f.png"]["caption"] == "a line of 4 points"
    assert side["files"]["f.png"]["label"] == "Figure 1"
    assert provenance.from_png(out / "f.png")["notebook"] == "99_tiny"
    assert not (base / "log" / "99_tiny.ipynb").exists()  # a log only when a run fails
    assert not (run_dir / ".jupyter").exists()


def test_the_executed_notebook_shows_the_users_parameters_only(tiny):
    _, _, run_dir = tiny
    nb = json.loads((run_dir / "99_tiny.ipynb").read_text())
    assert str(run_dir) not in json.dumps(nb)
    printed = json.dumps([c.get("outputs", []) for c in nb["cells"]])
    assert "took 1.23 s" not in printed and "wall-clock" in printed
    injected = [c for c in nb["cells"] if "injected-parameters" in c["metadata"].get("tags", [])]
    assert "".join(injected[0]["source"]).strip().endswith("n = 4")
    outputs = [o for c in nb["cells"] for o in c.get("outputs", [])]
    assert any("".join(o.get("text", [])) == "4\n" for o in outputs)


def test_a_failing_cell_is_named_and_its_notebook_kept(tiny, tmp_path):
    _, path, _ = tiny
    nb = nbformat.read(path, as_version=4)
    nb.cells.append(nbformat.v4.new_code_cell("raise ValueError('bad data in row 7')"))
    bad = tmp_path / "99_tiny.ipynb"
    nbformat.write(nb, bad)
    with pytest.raises(RuntimeError, match=r"99_tiny failed in cell \[7\]: ValueError: bad "
                                           r"data in row 7; the executed notebook is"):
        workflow.execute(bad, {}, tmp_path / "run", tmp_path / "log" / "99_tiny.log")
    assert (tmp_path / "log" / "99_tiny.ipynb").exists()


# --- the engine itself, end to end -------------------------------------------------------------

def _command(workdir: Path, params: str) -> list[str]:
    return [sys.executable, "-m", "mtaccuracy.compendium.workflow", "reproduce", "--nb", "03",
            "--params", params, "--cores", "1", "--workdir", str(workdir)]


ENV = {**os.environ, "PYTHONPATH": str(ROOT / "lib")}


def _reproduce(workdir: Path, params: str) -> subprocess.CompletedProcess:
    return subprocess.run(_command(workdir, params), capture_output=True, text=True, timeout=600,
                          env=ENV)


def _files(folder: Path) -> dict:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


def test_reproduce_runs_a_changed_notebook_once_and_publishes_it_whole(tmp_path):
    out = tmp_path / "out"
    params = f"{SMALL_03} output_dir={out}"
    first = _reproduce(tmp_path / "wd", params)
    assert first.returncode == 0, first.stdout + first.stderr
    assert f"{GUO} ran in" in first.stdout + first.stderr
    assert (out / "reproduction.csv").exists() and (out / f"{GUO}.ipynb").exists()
    assert provenance.folder_problems(out) == []
    (out / "notes.txt").write_text("mine")
    again = _reproduce(tmp_path / "wd", params)
    assert again.returncode == 0, again.stdout + again.stderr
    assert "Nothing to be done" in again.stdout + again.stderr
    assert (out / "notes.txt").read_text() == "mine"
    assert not (tmp_path / "wd" / "build" / "scorecard.done").exists()  # not in place
    # another seed, killed (-9, the whole process group) while the notebook runs: nothing of the
    # published run changes, and the next command runs it again from the start
    before = _files(out)
    other = f"{params} seed=7"
    proc = subprocess.Popen(_command(tmp_path / "wd", other), env=ENV, start_new_session=True,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    running = tmp_path / "wd" / "build" / "logs" / f"{GUO}.ipynb"
    deadline = time.monotonic() + 300
    while not running.exists() and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.2)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    assert _files(out) == before
    last = _reproduce(tmp_path / "wd", other)
    assert last.returncode == 0, last.stdout + last.stderr
    assert provenance.read(out)["run"]["parameters"]["seed"] == 7
    assert (out / "notes.txt").read_text() == "mine"
    shutil.rmtree(tmp_path / "wd")
