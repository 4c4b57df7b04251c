"""Parameter validation and the in-place papermill runner."""

import json
import os
import re
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


def test_the_parameter_language_stands_apart_from_the_runner():
    """Notebooks import the parameter language (``compendium.parameters``), not the execution
    engine; one exception type, a ValueError, for every parameter error."""
    code = ("import sys, mtaccuracy.compendium.parameters; print(sorted(m for m in sys.modules "
            "if m in ('mtaccuracy.compendium.runner', 'mtaccuracy.compendium.commit', "
            "'papermill', 'nbformat')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=paths.ROOT)
    assert out.stdout.strip() == "[]"
    from mtaccuracy.compendium import parameters, rong, xu2022

    assert runner.ParameterError is parameters.ParameterError is rong.ParameterError \
        is xu2022.ParameterError and issubclass(parameters.ParameterError, ValueError)
    for nb in runner.all_notebooks():
        text = nb.read_text(encoding="utf-8")
        assert "from mtaccuracy.compendium.parameters import check_parameters" in text, nb.stem
        assert "compendium.runner import" not in text and "import runner" not in text, nb.stem


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


def test_a_long_comment_continues_on_indented_comment_lines(tmp_path, monkeypatch):
    """Notebooks are linted at 100 characters: a parameter's constraints and help, and the
    memory expression, may continue on indented comment lines; an unindented one does not."""
    path = _tiny(tmp_path, monkeypatch, "print(n)",
                 "m = 2  # {>= 1,\n    # <= 5} a long\n    #  help\n# not help\n"
                 "# {memory: 1e8 +\n    # 1e9 * m}  peak bytes\n")
    m = runner.read_parameters(path)["m"]
    assert m.constraints == [(">=", 1.0), ("<=", 5.0)] and m.help == "a long help"
    with pytest.raises(runner.ParameterError, match="'m' = 6 is not allowed; it must be <= 5"):
        runner.validate(path, {"m": 6})
    assert runner.memory_estimate(path, {"n": 3, "m": 4}) == 1e8 + 4e9


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
    from mtaccuracy.compendium import memory

    path = _tiny(tmp_path, monkeypatch, "print(n)", "# {memory: 1e8 + 1e9 * n}  peak bytes\n")
    limits = [memory.Limit(20e9, "available memory"),
              memory.Limit(30e9, "the address-space limit (ulimit -v)", per_process=True)]
    monkeypatch.setattr(memory, "limits", lambda: limits)
    assert runner.validate(path, {"n": 10}) == {"n": 10}
    with pytest.raises(runner.ParameterError, match="need about 50.1 GB of memory, more than "
                                                    "the 20 GB left under available memory"):
        runner.validate(path, {"n": 50})
    with pytest.raises(runner.ParameterError, match="shared by 2 runs at once"):
        runner.validate(path, {"n": 15}, share=2)
    limits[0] = memory.Limit(200e9, "available memory")  # each run has its own ulimit -v
    assert runner.validate(path, {"n": 25}, share=2) == {"n": 25}
    with pytest.raises(runner.ParameterError, match="left under the address-space limit "
                                                    "\\(ulimit -v\\) on this machine"):
        runner.validate(path, {"n": 31}, share=2)


def test_the_memory_expression_is_arithmetic_only(tmp_path, monkeypatch):
    path = _tiny(tmp_path, monkeypatch, "print(n)", "# {memory: __import__('os').getpid()}\n")
    with pytest.raises(runner.ParameterError, match="numbers, parameter names"):
        runner.validate(path, {})


@pytest.mark.parametrize("value, message", [
    ("", "output_dir is empty, which would be the repository root"),
    (".", "the repository root"),
    ("figures/02_other", "another notebook's folder \\(02_other\\)"),
    ("figures/mine", "figures/mine' is .*, a folder inside the repository that is not this "
                     "notebook's"),
    ("notebooks", "a folder inside the repository that is not this notebook's"),
    ("figures/01_tiny/sub", "a folder inside the repository"),
    ("..", "a folder that contains the repository"),
])
def test_output_dir_inside_the_repository_is_only_its_own_folder(tmp_path, monkeypatch, value,
                                                                   message):
    (tmp_path / "repo").mkdir()
    path = _tiny(tmp_path / "repo", monkeypatch, "print(n)")
    shutil.copy(path, path.with_name("02_other.ipynb"))
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
    assert {p.name for p in (tmp_path / "figures").iterdir()} == {"01_tiny", runner.RUNS}

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


@pytest.mark.parametrize("sig, installed", [(signal.SIGINT, "default"),
                                             (signal.SIGINT, "ignored"),
                                             (signal.SIGTERM, "default")], indirect=["installed"])
def test_an_interrupted_run_changes_nothing(tmp_path, monkeypatch, sig, installed):
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
    assert signal.getsignal(signal.SIGINT) is installed  # the handler of before, restored


@pytest.fixture
def installed(request):
    """The SIGINT handler the run finds: Python's default, or SIG_IGN as under ``nohup`` or
    ``make test &`` from a script (the run still stops on SIGINT, and restores SIG_IGN)."""
    old = signal.getsignal(signal.SIGINT)
    if request.param == "ignored":
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    yield signal.getsignal(signal.SIGINT)
    signal.signal(signal.SIGINT, old)


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


# --- issue 21: nothing of the user's is lost or mixed ---------------------------------------

READ_INPUT = WRITE + ("src = globals().get('src', '')\n"
                      "if src:\n    (out / 'copy.csv').write_text(open(src).read())\n")


def test_a_rerun_leaves_alone_what_it_did_not_write_and_says_so(tmp_path, monkeypatch, capsys):
    """A re-run replaced the whole folder: the user's notes and the run's own input file in it
    were deleted.  Now only the files of the previous run's manifest are replaced."""
    path = _tiny(tmp_path, monkeypatch, READ_INPUT, 'src = ""  # an input file\n')
    runner.run(path, {}, progress=False)
    out = tmp_path / "figures" / "01_tiny"
    (out / "notes.txt").write_text("the user's notes\n")
    (out / "my_input.csv").write_text("x\n1\n")
    runner.run(path, {"n": 5, "src": str(out / "my_input.csv")}, progress=False)
    assert (out / "notes.txt").read_text() == "the user's notes\n"
    assert (out / "my_input.csv").read_text() == "x\n1\n"
    assert (out / "table.csv").read_text() == "n\n5\n" and (out / "copy.csv").exists()
    assert "left alone in figures/01_tiny/" in capsys.readouterr().err
    runner.run(path, {}, progress=False)  # copy.csv was ours and is not written again: removed
    assert not (out / "copy.csv").exists() and (out / "notes.txt").exists()
    side = json.loads((out / "provenance.json").read_text())
    assert set(side["files"]) == {"table.csv"}  # a file written without provenance is listed


def test_a_new_output_folder_outside_the_repository_passes_the_notebooks_own_check(
        tmp_path, monkeypatch):
    """The run stages inside its output folder; the notebook's own check of ``output_dir``
    (``check_parameters`` -> ``paths.check_output_dir``, in the kernel) must not take that
    staging folder for a file of someone else's."""
    check = ("from mtaccuracy.compendium import paths as P\n"
             "P.check_output_dir(output_dir, '01_tiny')\n")
    path = _tiny(tmp_path, monkeypatch, check + WRITE)
    away = tmp_path.parent / f"{tmp_path.name}-new"
    runner.run(path, {"output_dir": str(away)}, progress=False)
    assert (away / "table.csv").read_text() == "n\n3\n"
    shutil.rmtree(away)


def test_notes_in_an_output_folder_outside_the_repository_survive_a_rerun(tmp_path, monkeypatch):
    path = _tiny(tmp_path, monkeypatch, WRITE)
    away = tmp_path.parent / f"{tmp_path.name}-away"
    runner.run(path, {"output_dir": str(away)}, progress=False)
    (away / "notes.txt").write_text("mine\n")
    runner.run(path, {"n": 6, "output_dir": str(away)}, progress=False)
    assert (away / "notes.txt").read_text() == "mine\n"
    assert (away / "table.csv").read_text() == "n\n6\n"
    assert sorted(p.name for p in away.iterdir()) == ["01_tiny.ipynb", "notes.txt",
                                                      "provenance.json", "table.csv"]
    shutil.rmtree(away)


def test_an_output_edited_by_hand_is_refused_before_the_run(tmp_path, monkeypatch):
    path = _tiny(tmp_path, monkeypatch, WRITE)
    runner.run(path, {}, progress=False)
    table = tmp_path / "figures" / "01_tiny" / "table.csv"
    table.write_text("n\n99\n")
    with pytest.raises(runner.ParameterError, match="table.csv in figures/01_tiny changed since "
                                                    "the compendium wrote it"):
        runner.run(path, {}, progress=False)
    assert table.read_text() == "n\n99\n"
    assert not (tmp_path / "notebooks" / ".running" / "01_tiny.ipynb").exists()


@pytest.mark.parametrize("where", ["notebooks", ".", "figures", "figures/01_tiny"])
def test_copy_to_inside_the_repository_is_refused(tmp_path, monkeypatch, capsys, where):
    """``--copy-to notebooks`` rewrote the committed notebook; ``--copy-to .`` the figures."""
    path = _tiny(tmp_path, monkeypatch, WRITE)
    runner.run(path, {}, progress=False)
    before = {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}
    monkeypatch.setattr(paths, "ROOT", tmp_path)
    monkeypatch.chdir(tmp_path)
    assert runner.main(["01", "n=7", "--copy-to", where]) == 2
    err = capsys.readouterr().err
    assert "give a folder outside the repository" in err and err.count("\n") == 1
    assert {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()} == before


def test_copy_to_goes_through_the_same_checks_and_staging(tmp_path, monkeypatch, capsys):
    _tiny(tmp_path, monkeypatch, WRITE)
    dest = tmp_path.parent / f"{tmp_path.name}-copy"
    assert runner.main(["01", "n=7", "--copy-to", str(dest)]) == 0
    out = dest / "figures" / "01_tiny"
    assert (out / "table.csv").read_text() == "n\n7\n" and (dest / "01_tiny.ipynb").exists()
    (out / "notes.txt").write_text("mine\n")
    assert runner.main(["01", "n=8", "--copy-to", str(dest)]) == 0
    assert (out / "notes.txt").read_text() == "mine\n" and "left alone" in capsys.readouterr().err
    assert not list(out.glob(".staging-*"))
    assert runner.main(["01", "n=0", "--copy-to", str(dest)]) == 2  # checked like a run in place
    (dest / "01_tiny.ipynb").write_text("the user's own notebook\n")
    assert runner.main(["01", "--copy-to", str(dest)]) == 2
    assert "is not a notebook the compendium stored" in capsys.readouterr().err
    assert (dest / "01_tiny.ipynb").read_text() == "the user's own notebook\n"
    assert not (tmp_path / "figures" / "01_tiny").exists()  # the repository untouched
    shutil.rmtree(dest)


def test_all_notebooks_into_one_output_dir_get_a_folder_each(tmp_path, monkeypatch):
    path = _tiny(tmp_path, monkeypatch, WRITE + "print(output_dir)")
    nb = json.loads(path.read_text())
    nb["cells"][0]["source"] = "".join(nb["cells"][0]["source"]).replace("01_tiny", "02_tiny")
    path.with_name("02_tiny.ipynb").write_text(json.dumps(nb))
    x = tmp_path.parent / f"{tmp_path.name}-all"
    assert runner.main(["all", "n=4", f"output_dir={x}", "--jobs", "1"]) == 0
    for stem in ("01_tiny", "02_tiny"):
        assert (x / stem / "table.csv").read_text() == "n\n4\n"
        assert json.loads((x / stem / "provenance.json").read_text())["run"]["notebook"] == stem
        assert (x / stem / f"{stem}.ipynb").exists()
    assert sorted(p.name for p in x.iterdir()) == ["01_tiny", "02_tiny"]
    shutil.rmtree(x)


def test_a_run_leaves_the_working_files_of_other_runs_alone(tmp_path, monkeypatch):
    """The tests run notebook 03 three times at once with --copy-to; the runs shared
    ``notebooks/.running/<stem>.ipynb`` (each unlinked and rewrote it) and one read the
    other's half-written JSON.  Each run now works in a file of its own."""
    path = _tiny(tmp_path, monkeypatch, WRITE)
    running = tmp_path / "notebooks" / ".running"
    running.mkdir()
    others = [running / "01_tiny.ipynb", running / "01_tiny.999999.ipynb",
              running / "01_tiny.kernel.log"]
    for f in others:
        f.write_text("another run's, being written\n")
    runner.run(path, {}, progress=False)
    assert [f.read_text() for f in others] == ["another run's, being written\n"] * 3
    assert sorted(p.name for p in running.iterdir()) == sorted(f.name for f in others)


def test_a_signal_during_the_commit_waits_for_the_commit_to_be_whole(tmp_path, monkeypatch):
    from mtaccuracy.compendium import commit

    path = _tiny(tmp_path, monkeypatch, WRITE + "(out / 'b.csv').write_text(str(n))\n")
    runner.run(path, {}, progress=False)
    monkeypatch.setattr(commit, "_step", lambda name: name == "move a.csv" or (
        name.startswith("move") and os.kill(os.getpid(), signal.SIGINT)))
    with pytest.raises(runner.Interrupted, match="the commit was completed"):
        runner.run(path, {"n": 9}, progress=False)
    out = tmp_path / "figures" / "01_tiny"
    assert (out / "table.csv").read_text() == "n\n9\n" and (out / "b.csv").read_text() == "9"
    assert "n = 9" in path.read_text()


@pytest.mark.parametrize("name, message", [
    ("*", "no notebook matches '\\*'"), ("**", "no notebook matches '\\*\\*'"),
    ("/etc/passwd", "'/etc/passwd' is not one of the compendium's notebooks"),
    ("x" * 5000, "no notebook matches 'x{57}\\.\\.\\.'; notebooks"),
    ("../notebooks/03_guo2016_spearman_21_errors.ipynb", "not one of the compendium's"),
])
def test_a_bad_notebook_name_is_one_clear_line(capsys, name, message):
    assert runner.main([name, "--check"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert re.search(message, err), err


def test_check_may_come_before_the_parameters(capsys):
    assert runner.main(["03", "--check", "seed=7"]) == 0
    assert capsys.readouterr().out.strip() == "parameters ok"


def test_a_checkout_the_runner_cannot_write_is_one_clear_line(tmp_path, monkeypatch, capsys):
    """A read-only clone (as a non-root user) crashed with PermissionError on
    notebooks/.running; the refusal is injected here (root may write anywhere)."""
    path = _tiny(tmp_path, monkeypatch, WRITE)
    real = runner.tempfile.TemporaryFile

    def refuse(*a, dir=None, **k):
        if dir is not None and str(dir).endswith(".running"):
            raise PermissionError(13, "Permission denied")
        return real(*a, dir=dir, **k)

    monkeypatch.setattr(runner.tempfile, "TemporaryFile", refuse)
    assert runner.main([str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "cannot write in notebooks/.running (Permission denied)" \
        in err and "nothing was run or changed" in err
    assert not (tmp_path / "figures" / "01_tiny").exists()


def _make(*args, env=None):
    return subprocess.run(["make", "--no-print-directory", *args], cwd=paths.ROOT,
                          env={**os.environ, **(env or {})}, capture_output=True, text=True,
                          timeout=300)


def test_make_never_expands_nb_params_or_lab_args(tmp_path):
    """``PARAMS='seed=$(shell touch x; echo 7)'`` ran the command; ``$HOME`` lost its ``$H``."""
    x = tmp_path / "x"
    res = _make("reproduce", "NB=03", f"PARAMS=--check seed=$(shell touch {x}; echo 7)")
    assert res.returncode != 0 and not x.exists()
    assert "parameter 'touch' must be written name=value" in res.stderr
    res = _make("reproduce", "NB=03", "PARAMS=--check output_dir=$HOME/run")
    assert res.returncode != 0 and "output_dir '$HOME/run'" in res.stderr
    res = _make("reproduce", f"NB=$(shell touch {x})", "PARAMS=--check")
    assert res.returncode != 0 and not x.exists() and "'$(shell touch " in res.stderr
    res = _make("lab", f"LAB_ARGS=--ip=0.0.0.0 $(shell touch {x})")
    assert res.returncode != 0 and not x.exists()
    res = _make("reproduce", "NB=03", env={"PARAMS": f"--check seed=$(shell touch {x})"})
    assert res.returncode != 0 and not x.exists()


def test_make_clean_removes_what_dead_runs_left_and_keeps_a_live_runs(tmp_path):
    for name in ("Makefile", "environment.txt", "pyproject.toml"):
        shutil.copy(paths.ROOT / name, tmp_path / name)
    shutil.copytree(paths.ROOT / "lib", tmp_path / "lib",
                    ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True).stdout.strip()
    nbs, figs = tmp_path / "notebooks", tmp_path / "figures" / "03_x"
    figs.mkdir(parents=True)
    nbs.mkdir()
    (nbs / f".03_x.ipynb.commit-{dead}.tmp").write_text("{}")
    (nbs / f".03_x.ipynb.commit-{os.getpid()}.tmp").write_text("{}")
    (figs / f".staging-{dead}").mkdir()
    (figs / "table.csv").write_text("kept\n")
    res = subprocess.run(["make", "--no-print-directory", "clean"], cwd=tmp_path,
                         capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    assert sorted(p.name for p in nbs.iterdir()) == [f".03_x.ipynb.commit-{os.getpid()}.tmp"]
    assert sorted(p.name for p in figs.iterdir()) == ["table.csv"]
