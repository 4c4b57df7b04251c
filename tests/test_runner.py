"""Parameter validation and the in-place papermill runner."""

import json

import nbformat
import pytest

from mtaccuracy import paths, runner

NB03 = "03_guo2016_spearman_21_errors"


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


def _tiny(tmp_path, monkeypatch, body):
    nbdir = tmp_path / "notebooks"
    nbdir.mkdir()
    nb = nbformat.v4.new_notebook()
    p = nbformat.v4.new_code_cell(
        'n = 3  # {>= 1} a count\nlabel = "a#b"  # {in: a#b|c} a label\nerrs = ["dx(x)"]  '
        '# {errors: vertical_xyfz} errors')
    p.metadata["tags"] = ["parameters"]
    nb.cells = [p, nbformat.v4.new_code_cell(body)]
    nb.metadata = {"kernelspec": {"name": "python3", "display_name": "Python 3",
                                  "language": "python"}, "language_info": {"name": "python"}}
    path = nbdir / "01_tiny.ipynb"
    nbformat.write(nb, path)
    monkeypatch.setattr(paths, "NOTEBOOKS", nbdir)
    monkeypatch.setattr(paths, "ROOT", tmp_path)
    return path


def test_constraints_of_all_kinds(tmp_path, monkeypatch):
    path = _tiny(tmp_path, monkeypatch, "print(n)")
    assert runner.read_parameters(path)["label"].default == "a#b"
    with pytest.raises(runner.ParameterError, match="one of a#b\\|c"):
        runner.validate(path, {"label": "d"})
    with pytest.raises(runner.ParameterError, match="unknown error name 'dq\\(x\\)'; allowed"):
        runner.validate(path, {"errs": ["dx(x)", "dq(x)"]})
    assert runner.validate(path, {"errs": ["S_xy"], "label": "c"})


def test_run_replaces_in_place_only_on_success(tmp_path, monkeypatch):
    path = _tiny(tmp_path, monkeypatch, "assert n < 10, 'n too big'\nprint('n is', n)")
    runner.run(path, {"n": 4}, progress=False)
    nb = json.loads(path.read_text())
    assert "n is 4" in "".join(nb["cells"][-1]["outputs"][0]["text"])
    assert "injected-parameters" in nb["cells"][1]["metadata"]["tags"]
    assert "start_time" not in nb["metadata"]["papermill"]  # no timestamps kept
    assert all("execution" not in c["metadata"] for c in nb["cells"])

    before = path.read_bytes()
    with pytest.raises(RuntimeError, match="AssertionError: n too big") as info:
        runner.run(path, {"n": 20}, progress=False)
    assert "is unchanged" in str(info.value)
    assert path.read_bytes() == before
    assert (tmp_path / "notebooks" / ".failed" / path.name).exists()

    runner.run(path, {}, progress=False)  # the old injected cell does not linger
    nb = json.loads(path.read_text())
    assert not any("injected-parameters" in c["metadata"].get("tags", []) for c in nb["cells"])
    assert "n is 3" in "".join(nb["cells"][-1]["outputs"][0]["text"])
