"""What the notebooks' runs in this session wrote, checked against what is committed.

nbval itself executes every committed notebook (``make test`` collects ``notebooks/`` with
``--nbval-lax``, see pyproject.toml and conftest.py): every cell must run, and the cells whose
first line is ``# NBVAL_CHECK_OUTPUT`` must print what the committed notebook prints (they print
the key tables, rounded).  Each run writes under the session's folder, never over ``figures/``.
After those runs, for each notebook:

* every regenerated CSV equals the committed one: text and integer columns exactly, float
  columns within the tolerance declared next to where the table is written
  (``reproduction.save_table(..., tolerance=...)``, recorded in the committed
  ``provenance.json``) plus one unit of the last printed digit; tables declared ``measured``
  (wall-clock times) are not compared;
* the files written are the files committed, each listed in ``provenance.json``.

Notebook 03 also runs twice with small parameters (through the runner, in the background): the
two runs must give byte-identical CSVs, figures and ``provenance.json``.
"""

import json
import re

import pandas as pd
import pytest

from mtaccuracy.compendium import paths, provenance, reproduction, runner

STEMS = [p.stem for p in runner.all_notebooks()]
CHECK = "# NBVAL_CHECK_OUTPUT"


def _ok(notebook_runs, name):
    code, log, seconds = notebook_runs.result(name)
    assert code == 0, f"{name} failed after {seconds:.0f} s:\n{log[-3000:]}"
    return notebook_runs.folder(name)


def _printed(cell) -> list[str]:
    out = []
    for o in cell.get("outputs", []):
        if o["output_type"] == "stream":
            out.append("".join(o["text"]))
        elif "data" in o and "text/plain" in o["data"]:
            out.append("".join(o["data"]["text/plain"]))
    return out


def _code(stem):
    nb = json.loads((paths.NOTEBOOKS / f"{stem}.ipynb").read_text(encoding="utf-8"))
    return [c for c in nb["cells"] if c["cell_type"] == "code"]


@pytest.mark.parametrize("stem", STEMS)
def test_notebook_marks_cells_for_nbval_visibly(stem):
    """Every notebook has cells nbval compares, each marked by its visible first line (not by a
    hidden tag), and each of them prints something to compare."""
    marked = [c for c in _code(stem) if "".join(c["source"]).startswith(CHECK)]
    assert marked, f"{stem}: no cell marked {CHECK}"
    assert all(_printed(c) for c in marked), f"{stem}: a marked cell prints nothing"
    for c in _code(stem):
        tags = {t.lower() for t in c.get("metadata", {}).get("tags", [])}
        assert not tags & {"nbval-check-output", "nbval-ignore-output", "nbval-skip"}, \
            f"{stem}: a cell is marked for nbval by a hidden tag"


@pytest.mark.parametrize("stem", STEMS)
def test_regenerated_tables_equal_committed(stem, nbval_output):
    fresh = nbval_output(stem) / "figures" / stem
    committed = paths.FIGURES / stem
    side = provenance.read(committed)
    assert side, f"figures/{stem}/provenance.json is missing"
    files = side["files"]
    assert sorted(p.name for p in fresh.iterdir()) == sorted([*files, provenance.SIDECAR])
    assert sorted(p.name for p in committed.iterdir()) == sorted([*files, provenance.SIDECAR])
    problems = []
    for name, entry in files.items():
        if name.endswith(".csv") and not entry.get("measured"):
            problems += reproduction.compare_tables(fresh / name, committed / name,
                                                    entry.get("tolerance", {}))
    assert not problems, "\n".join(problems)


def test_two_runs_give_byte_identical_outputs(notebook_runs):
    """Notebook 03 with small parameters, twice: every CSV, PNG, SVG and the provenance
    sidecar identical to the byte."""
    outs = []
    for k in (1, 2):
        out = _ok(notebook_runs, f"03_small_{k}") / "figures" / "03_guo2016_spearman_21_errors"
        outs.append({p.name: p.read_bytes() for p in sorted(out.iterdir())})
    assert outs[0].keys() == outs[1].keys()
    assert {".csv", ".png", ".svg", ".json"} <= {"." + n.rsplit(".", 1)[1] for n in outs[0]}
    assert [n for n in outs[0] if outs[0][n] != outs[1][n]] == []


@pytest.mark.parametrize("stem", STEMS)
def test_outputs_do_not_depend_on_where_the_repository_lives(stem):
    """A stored output that shows this checkout's absolute path would differ in every clone."""
    text = (paths.NOTEBOOKS / f"{stem}.ipynb").read_text(encoding="utf-8")
    assert str(paths.ROOT) not in text


@pytest.mark.parametrize("stem", STEMS)
def test_committed_notebook_stores_no_measurement(stem):
    """Cells tagged ``measured`` are stored with the runner's note only (re-running an
    unchanged notebook leaves it unchanged)."""
    nb = json.loads((paths.NOTEBOOKS / f"{stem}.ipynb").read_text(encoding="utf-8"))
    for c in nb["cells"]:
        if "measured" in c.get("metadata", {}).get("tags", []):
            assert _printed(c) == [runner.MEASURED_NOTE]


# ------------------------------------------------ notebook 04 on data not in the repository

STEM_04 = "04_xu2022_thermal_mlr_svr"


def _svg_titles(folder) -> list[str]:
    return [re.search(r"<dc:title>(.*?)</dc:title>", p.read_text(encoding="utf-8"), re.S).group(1)
            for p in sorted(folder.glob("*.svg"))]


def test_notebook_04_runs_on_a_readers_own_measurements(notebook_runs):
    """Experiments 11-15, 19 measurements each, nine sensors named after their places, 25
    targets over 960 mm (conftest.own_data_runs), with the documented defaults: the method's
    figures and tables, no paper comparison, no reconstruction stamp."""
    run = _ok(notebook_runs, "04_own")
    out = run / "figures" / STEM_04
    names = {p.name for p in out.iterdir()}
    assert not names & {"reproduction.csv", "sampling_se.csv", "eq9_consistency.csv"}
    assert {"table4_point_by_point_metrics.csv", "table7_mlr_metrics.csv", "table8_svr_metrics.csv",
            "leave_one_experiment_out.csv", "selection_vs_baselines.csv",
            "beyond_selection_vs_baselines.svg", "fig15_mlr_error_prediction.svg"} <= names
    titles = _svg_titles(out)
    assert titles and not any("reconstructed" in t for t in titles)
    t7 = pd.read_csv(out / "table7_mlr_metrics.csv")
    assert set(t7.split) == {"train 11 12 13 14, test 15"}
    versus = pd.read_csv(out / "selection_vs_baselines.csv")
    assert set(versus.held_out) == {"11", "12", "13", "14", "15", "all"}
    pooled = versus[versus.held_out == "all"].set_index("model")
    # the screw's expansion follows its temperatures: every model removes most of the error
    assert (pooled.rmse.drop("uncompensated") < 0.5 * pooled.rmse["uncompensated"]).all()
    assert (pooled.n_residuals == 5 * 19 * 25).all()
    text = (run / f"{STEM_04}.ipynb").read_text(encoding="utf-8")
    assert "not the paper&#x27;s reconstruction" in text or "not the paper's reconstruction" in text


def test_notebook_04_on_a_copy_of_the_reconstruction_keeps_every_label(notebook_runs):
    """A byte-identical copy of data/thermal elsewhere is the reconstruction: the same
    scorecard (every row's verdict and basis) as the committed one, and every figure stamped."""
    out = _ok(notebook_runs, "04_copy") / "figures" / STEM_04
    fresh = pd.read_csv(out / "reproduction.csv")
    committed = pd.read_csv(paths.FIGURES / STEM_04 / "reproduction.csv")
    cols = ["item", "quantity", "verdict", "basis"]
    assert fresh[cols].equals(committed[cols])
    assert (committed.basis == "constructed").sum() >= 21
    titles = _svg_titles(out)
    assert titles and all("reconstructed data" in t for t in titles)
