"""Parameter validation and the in-place papermill runner."""

import json
import os
import shutil
import signal
import subprocess
import sys
import threading
import time

import nbformat
import pytest

from mtaccuracy.compendium import paths, runner

NB03 = "03_guo2016_spearman_21_errors"
RUNNER = runner.__name__   # "mtaccuracy.compendium.runner", run with python -m


def test_reads_the_declared_parameters_of_notebook_03():
    params = runner.read_parameters("03")
    assert params["n_samples"].default == 500
    assert (">=", 10.0) in params["n_samples"].constraints
    assert params["angular_rad"].default == pytest.approx(3.2e-5)
    assert "Latin hypercube" in params["n_samples"].help


@pytest.mark.parametrize("overrides, message", [
    ({"n_samples": -5}, "'n_samples' = -5 is not allowed; it must be >= 10"),
    ({"n_sample": 100}, "unknown parameter\\(s\\) n_sample; allowed:\n  seed = 20160"),
    ({"n_samples": 2.5}, "'n_samples' must be int like its default 500, got float 2.5"),
    ({"n_samples": True}, "must be int"),
    ({"output_dir": 3}, "'output_dir' must be str"),
])
def test_bad_parameters_are_refused_with_the_allowed_ones(overrides, message):
    with pytest.raises(runner.ParameterError, match=message):
        runner.validate(NB03, overrides)


def test_good_parameters_are_cleaned():
    got = runner.validate("03", {"x_mm": 5, "n_samples": 50})
    assert got == {"x_mm": 5.0, "n_samples": 50} and isinstance(got["x_mm"], float)


def test_cli_refuses_before_any_work(capsys):
    assert runner.main(["03", "n_samples=-5"]) == 2
    err = capsys.readouterr().err
    assert "n_samples" in err and ">= 10" in err
    assert runner.main(["99"]) == 2
    assert "no notebook matches '99'" in capsys.readouterr().err
    assert runner.main(["03", "n_samples"]) == 2
    assert "name=value" in capsys.readouterr().err


def test_parse_value():
    assert runner.parse_value("12") == 12 and runner.parse_value("1e-3") == 1e-3
    assert runner.parse_value("[1, 2]") == [1, 2] and runner.parse_value("abc") == "abc"


def _tiny(tmp_path, monkeypatch, body, extra_params=""):
    """A one-notebook repository in tmp_path: the runner's paths point there, so nothing in
    the working tree is touched."""
    nbdir = tmp_path / "notebooks"
    nbdir.mkdir()
    nb = nbformat.v4.new_notebook()
    p = nbformat.v4.new_code_cell(
        'n = 3  # {>= 1, <= 100} a count\nlabel = "a#b"  # {in: a#b|c} a label\n'
        'errs = ["dx(x)"]  # {errors: vertical_xyfz} errors\nx = 1.5  # a float\n'
        'output_dir = "figures/01_tiny"  # where outputs go\n' + extra_params)
    p.metadata["tags"] = ["parameters"]
    nb.cells = [p, nbformat.v4.new_code_cell(body)]
    nb.metadata = {"kernelspec": {"name": "python3", "display_name": "Python 3",
                                  "language": "python"}, "language_info": {"name": "python"}}
    path = nbdir / "01_tiny.ipynb"
    nbformat.write(nb, path)
    monkeypatch.setattr(paths, "NOTEBOOKS", nbdir)
    monkeypatch.setattr(paths, "ROOT", tmp_path)
    monkeypatch.setattr(paths, "FIGURES", tmp_path / "figures")
    monkeypatch.setenv(paths.OUTPUT_BASE_ENV, str(tmp_path))
    return path


WRITE = ("import os, time\nfrom mtaccuracy.compendium import paths\n"
         "out = paths.output_dir(output_dir)\n"
         "(out / 'table.csv').write_text(f'n\\n{n}\\n')\n")


def test_constraints_of_all_kinds(tmp_path, monkeypatch):
    path = _tiny(tmp_path, monkeypatch, "print(n)")
    assert runner.read_parameters(path)["label"].default == "a#b"
    with pytest.raises(runner.ParameterError, match="one of a#b\\|c"):
        runner.validate(path, {"label": "d"})
    with pytest.raises(runner.ParameterError, match="unknown error name 'dq\\(x\\)'; allowed"):
        runner.validate(path, {"errs": ["dx(x)", "dq(x)"]})
    with pytest.raises(runner.ParameterError, match="'n' = 101 is not allowed; it must be <= 100"):
        runner.validate(path, {"n": 101})
    assert runner.validate(path, {"errs": ["S_xy"], "label": "c"})


@pytest.mark.parametrize("value", [float("inf"), float("-inf"), float("nan"), 1e400])
def test_floats_must_be_finite(tmp_path, monkeypatch, value):
    path = _tiny(tmp_path, monkeypatch, "print(x)")
    with pytest.raises(runner.ParameterError, match="'x' = .* is not a finite number"):
        runner.validate(path, {"x": value})


def test_cli_refuses_an_infinite_float(capsys):
    assert runner.main(["03", "positioning_um=1e400"]) == 2
    assert "'positioning_um' = inf is not a finite number" in capsys.readouterr().err


def test_every_count_parameter_of_every_notebook_has_an_upper_bound():
    for nb in runner.all_notebooks():
        for p in runner.read_parameters(nb).values():
            if isinstance(p.default, int) and not isinstance(p.default, bool) \
                    and p.name != "seed":
                assert any(op in ("<=", "<") for op, _ in p.constraints), (nb.stem, p.name)


def test_every_notebook_estimates_its_memory_and_the_estimate_grows_with_the_counts():
    for nb in runner.all_notebooks():
        declared = runner.read_parameters(nb)
        values = {k: p.default for k, p in declared.items()}
        base = runner.memory_estimate(nb, values)
        assert base is not None and 5e7 < base < 8e9, nb.stem
        ints = [k for k, p in declared.items() if isinstance(p.default, int)
                and not isinstance(p.default, bool) and k != "seed"]
        biggest = {k: max(b for op, b in declared[k].constraints if op in ("<=", "<"))
                   for k in ints}
        assert runner.memory_estimate(nb, {**values, **biggest}) >= base, nb.stem


def test_a_run_that_cannot_fit_in_memory_is_refused(tmp_path, monkeypatch):
    path = _tiny(tmp_path, monkeypatch, "print(n)", "# {memory: 1e8 + 1e9 * n}  peak bytes\n")
    monkeypatch.setattr(runner, "memory_available", lambda: (20e9, "available memory"))
    assert runner.validate(path, {"n": 10}) == {"n": 10}
    with pytest.raises(runner.ParameterError,
                       match="need about 50.1 GB of memory, more than the 20 GB available"):
        runner.validate(path, {"n": 50})
    with pytest.raises(runner.ParameterError, match="shared by 2 runs at once"):
        runner.validate(path, {"n": 15}, share=2)


def test_the_memory_expression_is_arithmetic_only(tmp_path, monkeypatch):
    path = _tiny(tmp_path, monkeypatch, "print(n)", "# {memory: __import__('os').getpid()}\n")
    with pytest.raises(runner.ParameterError, match="numbers, parameter names"):
        runner.validate(path, {})


@pytest.mark.parametrize("value, message", [
    ("", "output_dir is empty, which would be the repository root"),
    (".", "the repository root"),
    ("figures/02_other", "another notebook's folder"),
    ("notebooks", "a folder inside the repository that is not this notebook's"),
    ("figures/01_tiny/sub", "a folder inside the repository"),
    ("..", "a folder that contains the repository"),
])
def test_output_dir_inside_the_repository_is_only_its_own_folder(tmp_path, monkeypatch, value,
                                                                   message):
    (tmp_path / "repo").mkdir()
    path = _tiny(tmp_path / "repo", monkeypatch, "print(n)")
    with pytest.raises(runner.ParameterError, match=message):
        runner.validate(path, {"output_dir": value})
    assert runner.validate(path, {"output_dir": "figures/01_tiny"})


def test_output_dir_outside_the_repository(tmp_path, monkeypatch):
    (tmp_path / "repo").mkdir()
    path = _tiny(tmp_path / "repo", monkeypatch, "print(n)")
    assert runner.validate(path, {"output_dir": str(tmp_path / "new" / "folder")})
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("mine")
    with pytest.raises(runner.ParameterError, match="not empty and was not written by the "
                                                    "compendium; nothing there is overwritten"):
        runner.validate(path, {"output_dir": str(foreign)})
    other = tmp_path / "other"
    other.mkdir()
    (other / "provenance.json").write_text(json.dumps({"run": {"notebook": "02_other"}}))
    with pytest.raises(runner.ParameterError, match="holds the outputs of 02_other"):
        runner.validate(path, {"output_dir": str(other)})
    (other / "provenance.json").write_text(json.dumps({"run": {"notebook": "01_tiny"}}))
    assert runner.validate(path, {"output_dir": str(other)})
    with pytest.raises(runner.ParameterError, match="is a file"):
        runner.validate(path, {"output_dir": str(foreign / "notes.txt")})


def test_cli_refuses_a_foreign_folder_and_another_notebooks_folder(capsys, monkeypatch,
                                                                    tmp_path):
    """A relative path out of the repository into a folder of the user's (as ``../../etc``
    would be): refused, like another notebook's folder.  ``--check``: a test that cannot run
    a notebook into the working tree even when the check is broken."""
    monkeypatch.delenv(paths.OUTPUT_BASE_ENV)  # relative to the repository, as make runs it
    mine = tmp_path / "etc"
    mine.mkdir()
    (mine / "passwd").write_text("the user's\n")
    rel = os.path.relpath(mine, paths.ROOT)
    assert rel.startswith("..")
    assert runner.main(["03", f"output_dir={rel}", "--check"]) == 2
    assert "was not written by the compendium" in capsys.readouterr().err
    assert runner.main(["03", "output_dir=figures/01_zheng2024_pce_sobol_41_errors",
                        "--check"]) == 2
    assert "another notebook's folder" in capsys.readouterr().err
    assert (mine / "passwd").read_text() == "the user's\n"


def test_params_from_the_environment_are_never_evaluated_by_a_shell(tmp_path):
    """``make reproduce NB=03 PARAMS="...; touch x"``: an error, and no file."""
    env = dict(os.environ, NB="03", PARAMS=f"n_samples=-5; touch {tmp_path / 'x'}")
    res = subprocess.run(["make", "--no-print-directory", "reproduce"], cwd=paths.ROOT, env=env,
                         capture_output=True, text=True, timeout=300)
    assert res.returncode != 0
    assert "must be written name=value" in res.stderr and not (tmp_path / "x").exists()
    env["PARAMS"] = "seed=7 'unbalanced"
    res = subprocess.run([sys.executable, "-m", RUNNER, "--from-env", "--check"],
                         env=env, capture_output=True, text=True, timeout=60)
    assert res.returncode == 2 and "No closing quotation" in res.stderr
    env["PARAMS"] = "seed=7 n_samples=100"
    res = subprocess.run([sys.executable, "-m", RUNNER, "--from-env", "--check"],
                         env=env, capture_output=True, text=True, timeout=60)
    assert res.returncode == 0, res.stderr


def test_run_is_all_or_nothing(tmp_path, monkeypatch, caplog):
    body = WRITE + "assert n < 10, 'n too big'\nprint('n is', n)"
    path = _tiny(tmp_path, monkeypatch, body)
    runner.run(path, {"n": 4}, progress=False)
    out = tmp_path / "figures" / "01_tiny"
    nb = json.loads(path.read_text())
    assert "n is 4" in "".join(nb["cells"][-1]["outputs"][0]["text"])
    assert "injected-parameters" in nb["cells"][1]["metadata"]["tags"]
    assert "start_time" not in nb["metadata"]["papermill"]  # no timestamps kept
    assert all("execution" not in c["metadata"] for c in nb["cells"])
    assert (out / "table.csv").read_text() == "n\n4\n"
    assert not [r for r in caplog.records if "unknown parameter" in r.getMessage()
                or "Unable to parse" in r.getMessage()]  # papermill agrees with the runner
    assert json.loads((tmp_path / "figures" / runner.RUNS).read_text())["01_tiny"]["seconds"] > 0

    before, table = path.read_bytes(), (out / "table.csv").read_bytes()
    with pytest.raises(RuntimeError, match="AssertionError: n too big") as info:
        runner.run(path, {"n": 20}, progress=False)
    assert "01_tiny.ipynb and figures/01_tiny unchanged" in str(info.value)
    assert path.read_bytes() == before and (out / "table.csv").read_bytes() == table
    failed = tmp_path / "notebooks" / ".failed"
    assert (failed / path.name).exists()
    assert (failed / "01_tiny.figures" / "table.csv").read_text() == "n\n20\n"
    assert {p.name for p in (tmp_path / "figures").iterdir()} == {"01_tiny", runner.RUNS, "html"}
    assert "n is 4" in (tmp_path / "figures" / "html" / "01_tiny.html").read_text()

    runner.run(path, {}, progress=False)  # the old injected cell does not linger
    nb = json.loads(path.read_text())
    assert not any("injected-parameters" in c["metadata"].get("tags", []) for c in nb["cells"])
    assert "n is 3" in "".join(nb["cells"][-1]["outputs"][0]["text"])


def test_a_run_elsewhere_leaves_notebooks_and_figures_untouched(tmp_path, monkeypatch):
    path = _tiny(tmp_path, monkeypatch, WRITE + "print('n is', n)")
    runner.run(path, {}, progress=False)
    committed = path.read_bytes()
    runs = (tmp_path / "figures" / runner.RUNS).read_bytes()
    away = tmp_path.parent / f"{tmp_path.name}-elsewhere"
    runner.run(path, {"n": 7, "output_dir": str(away)}, progress=False)
    assert path.read_bytes() == committed
    assert (tmp_path / "figures" / runner.RUNS).read_bytes() == runs
    assert (tmp_path / "figures" / "01_tiny" / "table.csv").read_text() == "n\n3\n"
    assert (away / "table.csv").read_text() == "n\n7\n"
    assert "n is 7" in (away / "01_tiny.ipynb").read_text()
    assert runner.written_notebook(path, {"output_dir": str(away)}) == away / "01_tiny.ipynb"
    assert runner.written_notebook(path, {}) == path
    shutil.rmtree(away)


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_an_interrupted_run_changes_nothing(tmp_path, monkeypatch, sig):
    path = _tiny(tmp_path, monkeypatch, WRITE + "time.sleep(0 if n == 3 else 60)")
    runner.run(path, {}, progress=False)
    out = tmp_path / "figures" / "01_tiny"
    before, table = path.read_bytes(), (out / "table.csv").read_bytes()
    timer = threading.Timer(4.0, os.kill, (os.getpid(), sig))
    timer.start()
    t0 = time.perf_counter()
    with pytest.raises(runner.Interrupted, match=f"interrupted \\({sig.name}\\): "
                                                 "notebooks/01_tiny.ipynb and figures/01_tiny "
                                                 "unchanged; partial run kept in"):
        runner.run(path, {"n": 5}, progress=False)
    timer.cancel()
    assert time.perf_counter() - t0 < 40
    assert path.read_bytes() == before and (out / "table.csv").read_bytes() == table
    assert (tmp_path / "notebooks" / ".failed" / "01_tiny.figures" / "table.csv").read_text() \
        == "n\n5\n"
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # handlers restored


def test_measured_cells_are_stored_without_their_output(tmp_path, monkeypatch):
    path = _tiny(tmp_path, monkeypatch, "import time\nprint('took', time.perf_counter())")
    nb = nbformat.read(path, as_version=4)
    nb.cells[-1].metadata["tags"] = ["measured"]
    nbformat.write(nb, path)
    runner.run(path, {}, progress=False)
    first = path.read_bytes()
    runner.run(path, {}, progress=False)
    assert path.read_bytes() == first
    cell = json.loads(first)["cells"][-1]
    assert cell["outputs"] == [{"name": "stdout", "output_type": "stream",
                                "text": [runner.MEASURED_NOTE]}]


def test_a_cells_printing_is_stored_as_one_output_whatever_the_timing():
    pieces = [{"name": "stdout", "output_type": "stream", "text": ["a\n", "b"]},
              {"name": "stdout", "output_type": "stream", "text": ["c\n"]},
              {"name": "stderr", "output_type": "stream", "text": ["w\n"]},
              {"name": "stdout", "output_type": "stream", "text": ["d\n"]}]
    one = [{"name": "stdout", "output_type": "stream", "text": ["a\nbc\n"]},
           {"name": "stderr", "output_type": "stream", "text": ["w\n"]},
           {"name": "stdout", "output_type": "stream", "text": ["d\n"]}]
    nb = {"metadata": {}, "cells": [{"cell_type": "code", "metadata": {}, "outputs": pieces}]}
    got = runner._normalise(nb, "x.ipynb")["cells"][0]["outputs"]
    assert got == runner._normalise(
        {"metadata": {}, "cells": [{"cell_type": "code", "metadata": {}, "outputs": one}]},
        "x.ipynb")["cells"][0]["outputs"]
    assert "".join(got[0]["text"]) == "a\nbc\n" and len(got) == 3
