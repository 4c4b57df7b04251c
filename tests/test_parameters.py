"""One declaration per parameter: each notebook's `param` class, its cell, and the checks.

The notebook's cell tagged ``parameters`` is the declaration's rendering, which papermill's own
``inspect_notebook`` reads whole; every refusal is one line naming the parameter."""

import json
import math
import re

import papermill
import param
import pytest

from mtaccuracy.compendium import workflow
from mtaccuracy.compendium.notebook import NOTEBOOKS
from mtaccuracy.papers import guo2016, rong, xu2022, yang2021, your_spindle, zheng2024
from mtaccuracy.papers.parameters import (
    NotebookParameters,
    NumberList,
    OutputFolder,
    ParameterError,
    check,
    literal,
    type_name,
    values,
)

DECLARED = {d.stem: d for d in workflow.DECLARATIONS}


def _cell(stem: str) -> str:
    nb = json.loads((NOTEBOOKS / f"{stem}.ipynb").read_text(encoding="utf-8"))
    [cell] = [c for c in nb["cells"] if "parameters" in c["metadata"].get("tags", [])]
    return "".join(cell["source"])


def test_every_notebook_has_a_declaration():
    assert sorted(DECLARED) == sorted(p.stem for p in NOTEBOOKS.glob("[0-9][0-9]_*.ipynb"))


@pytest.mark.parametrize("stem", sorted(DECLARED))
def test_the_parameters_cell_is_the_declaration(stem):
    decl = DECLARED[stem]
    assert _cell(stem) == decl.cell(), (
        f"notebooks/{stem}.ipynb: the cell tagged 'parameters' differs from "
        f"{decl.__module__}.Parameters; change the declaration and write its cell() there")


@pytest.mark.parametrize("stem", sorted(DECLARED))
def test_papermill_reads_every_parameter_with_its_default_type_and_help(stem):
    decl = DECLARED[stem]
    found = papermill.inspect_notebook(str(NOTEBOOKS / f"{stem}.ipynb"))
    assert list(found) == decl.names()
    for name, p in found.items():
        spec = decl.param[name]
        assert eval(p["default"]) == spec.default  # noqa: S307 - the cell's own literal
        assert p["inferred_type_name"] == type_name(spec)
        assert p["help"] == spec.doc and spec.doc


@pytest.mark.parametrize("stem", sorted(DECLARED))
def test_cell_lines_fit_the_notebooks_line_length(stem):
    long = [line for line in DECLARED[stem].cell().splitlines() if len(line) > 100]
    assert not long


def test_a_help_with_an_equals_sign_would_break_papermill():
    # papermill gives up on a line with two '=': this is why no help may hold one
    class Bad(NotebookParameters):
        stem = "99_bad"
        n = param.Integer(1, doc="n = 1 is fine")
        output_dir = OutputFolder("figures/99_bad", doc="where")

    nb = {"cells": [{"cell_type": "code", "source": Bad.cell(), "metadata": {},
                     "outputs": [], "execution_count": None}]}
    cell = nb["cells"][0]
    from papermill.translators import PythonTranslator

    assert [p.name for p in PythonTranslator.inspect(cell)] == ["output_dir"]
    assert not any("=" in DECLARED[s].param[n].doc for s in DECLARED
                   for n in DECLARED[s].names())


def test_defaults_pass_their_own_checks_and_fit_in_memory_bounds():
    for decl in DECLARED.values():
        filled = check(decl, {})
        assert values(filled) == decl.defaults()
        assert 1e8 < filled.memory_bytes() < 4e9


@pytest.mark.parametrize(("given", "message"), [
    ({"n_samples": 5}, "'n_samples' must be at least 10, not 5"),
    ({"n_samples": 2.5}, "'n_samples' must be an integer"),
    ({"nsamples": 50}, "unknown parameter(s) nsamples; allowed:\n  seed = 20160 (int; [0, inf])"),
    ({"x_mm": 1e400}, "'x_mm' = inf is not a finite number"),
    ({"angular_rad": 0.0}, "'angular_rad' must be greater than 0"),
    ({"grid_step_mm": 1.0}, "the pose grid would have 501 points per axis; at most 101"),
    ({"n_bound_designs": 100, "alpha_bound": 0.001}, "the eigenvalue test cannot reach"),
])
def test_refusals_name_the_notebook_and_the_parameter(given, message):
    with pytest.raises(ParameterError) as err:
        check(guo2016.Parameters, given)
    assert str(err.value).startswith("03_guo2016_spearman_21_errors: ")
    assert message in str(err.value)


def test_an_int_is_taken_for_a_float_and_a_tuple_for_a_list():
    filled = check(rong.Parameters, {"range_factor": 3, "workspace_mm": (700, 600, 500)})
    assert filled.range_factor == 3.0 and isinstance(filled.range_factor, float)
    assert filled.workspace_mm == [700.0, 600.0, 500.0]
    assert all(isinstance(v, float) for v in filled.workspace_mm)


@pytest.mark.parametrize(("given", "message"), [
    ({"workspace_mm": [700.0, 600.0]}, "length must be"),
    ({"tool_offset_mm": [0.0, 0.0, 5000.0]}, "5000.0 is outside [-1000.0, 1000.0]"),
    ({"sweep_thresholds": [0.8, 1.0, 0.01]}, "1.0 is outside (0.0, 1.0)"),
    ({"sweep_thresholds": [0.9, 0.8, 0.01]}, "first <= last"),
    ({"n_plot": 2000, "n_base": 1024}, "n_plot = 2000 must be at most n_base = 1024"),
    ({"layout": "z/yx"}, "does not accept 'z/yx'"),
])
def test_lists_and_cross_checks_are_refused_before_any_work(given, message):
    with pytest.raises(ParameterError, match=None) as err:
        check(rong.Parameters, given)
    assert message in str(err.value)


def test_yang_and_zheng_cross_checks():
    with pytest.raises(ParameterError, match="even pop_size"):
        check(yang2021.Parameters, {"pop_size": 51})
    with pytest.raises(ParameterError, match="probe_positions must be 4 distinct"):
        check(yang2021.Parameters, {"probe_positions": [0, 14, 14, 116]})
    with pytest.raises(ParameterError, match="'key_threshold' must be less than 1"):
        check(zheng2024.Parameters, {"key_threshold": 1.0})


def test_memory_grows_with_the_sizes_that_drive_it():
    small = check(zheng2024.Parameters, {"n_reference": 1000}).memory_bytes()
    big = check(zheng2024.Parameters, {"n_reference": 1_000_000}).memory_bytes()
    assert big > small
    assert check(guo2016.Parameters, {"n_repeats": 1000}).memory_bytes() > \
        check(guo2016.Parameters, {}).memory_bytes()


def test_file_parameters_are_declared_as_such():
    assert xu2022.Parameters.files() == ["data_dir"]
    assert your_spindle.Parameters.files() == ["probe_file"]
    assert rong.Parameters.files() == ["ranges_file"]


def test_number_list_bounds_each_item():
    spec = NumberList([1.0], item_type=float, item_bounds=(0.0, 1.0),
                      item_inclusive=(False, True))
    assert spec.describe_items() == "(0.0, 1.0]"
    with pytest.raises(ValueError, match="outside"):
        spec._validate([0.0])
    spec._validate([1.0])
    untyped = NumberList([], item_bounds=(0, None))
    with pytest.raises(ValueError, match="not a number"):
        untyped._validate([True])


def test_literals_are_what_papermill_and_python_read_back():
    for v in ("figures/x", 'a "quoted" name', 3, 2.5, True, [1.0, 2.0], []):
        assert eval(literal(v)) == v  # noqa: S307 - a literal we wrote
    assert literal("figures/x") == '"figures/x"'
    assert not math.isnan(check(your_spindle.Parameters, {}).amplified_above)


@pytest.mark.parametrize("path, words", [
    ("/tmp/caf\udce9.csv", "not valid UTF-8 text (byte 0xe9 at character 8)"),
    ("data/x\x00.csv", "holds a NUL character"),
])
def test_a_path_that_is_not_utf8_text_is_refused_naming_the_parameter(path, words):
    """A Latin-1 file name reaches Python with surrogate escapes; it cannot go into the
    notebook's JSON, so the parameter check refuses it, for input files, folders and outputs."""
    for declared, name in ((your_spindle.Parameters, "probe_file"),
                           (xu2022.Parameters, "data_dir"),
                           (guo2016.Parameters, "output_dir")):
        pattern = f"parameter '{name}': the path .*{re.escape(words)}"
        with pytest.raises(ParameterError, match=pattern):
            check(declared, {name: path})
    assert check(your_spindle.Parameters, {"probe_file": "/tmp/café.csv"}).probe_file \
        == "/tmp/café.csv"
