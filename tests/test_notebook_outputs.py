"""Regenerated tables against the committed ones, and run-to-run determinism.

The nbval items (``pytest --nbval-lax``) execute every notebook with its committed parameters,
writing under ``.test-output/`` (see conftest.py).  The comparison below runs after them; when
the notebooks were not collected (``pytest tests``), it executes them itself with papermill.

Tolerance: numbers must agree to the six significant digits the CSVs are written with
(relative 1e-5, absolute 1e-12), so a last-digit rounding flip on another BLAS does not fail
the test; text cells must be equal.  On one machine the files are byte-identical, with one
documented exception: wall-clock timings (Zheng et al.'s Table 3), which are measurements of the
machine, not results of the parameters.  They live in ``*timing*.csv`` columns named ``ours_*``
and in scorecard rows whose quantity says "(measured)"; those values are not compared.
"""

import os

import numpy as np
import pandas as pd
import papermill as pm
import pytest

from mtaccuracy import paths, runner

STEMS = [p.stem for p in runner.all_notebooks()]


def _regenerated(stem, base):
    out = base / "figures" / stem
    if not out.exists():
        nb = paths.NOTEBOOKS / f"{stem}.ipynb"
        pm.execute_notebook(str(nb), str(base / f"{stem}.ipynb"), cwd=str(paths.NOTEBOOKS),
                            kernel_name="python3", progress_bar=False)
    return out


def _deterministic_part(df, name):
    """Drop the measured wall-clock values (see the module docstring)."""
    if "timing" in name:
        df = df[[c for c in df.columns if not c.startswith("ours_")]]
    if name == "reproduction.csv":
        df = df[~df["quantity"].str.contains("(measured)", regex=False)]
    return df.reset_index(drop=True)


def _assert_tables_equal(a_path, b_path):
    a = _deterministic_part(pd.read_csv(a_path, dtype=str, keep_default_na=False), a_path.name)
    b = _deterministic_part(pd.read_csv(b_path, dtype=str, keep_default_na=False), b_path.name)
    assert list(a.columns) == list(b.columns), a_path.name
    assert a.shape == b.shape, a_path.name
    for c in a.columns:
        na, nb_ = pd.to_numeric(a[c], errors="coerce"), pd.to_numeric(b[c], errors="coerce")
        numeric = na.notna() & nb_.notna()
        assert (a[c][~numeric] == b[c][~numeric]).all(), f"{a_path.name}: column {c}"
        assert np.allclose(na[numeric], nb_[numeric], rtol=1e-5, atol=1e-12), \
            f"{a_path.name}: column {c}"


@pytest.mark.after_notebooks
@pytest.mark.parametrize("stem", STEMS)
def test_regenerated_tables_equal_committed(stem, test_output):
    committed = sorted((paths.FIGURES / stem).glob("*.csv"))
    assert committed, f"nothing committed in figures/{stem}"
    fresh = _regenerated(stem, test_output)
    assert sorted(p.name for p in fresh.glob("*.csv")) == [p.name for p in committed]
    for p in committed:
        _assert_tables_equal(fresh / p.name, p)


def test_two_runs_give_byte_identical_outputs(tmp_path):
    """Notebook 03 with small parameters, twice: every CSV, PNG, SVG and the provenance
    sidecar identical to the byte (output_dir differs, and is not part of the provenance)."""
    small = dict(n_samples=40, n_repeats=3, n_search_poses=16, n_search_samples=100,
                 grid_step_mm=250.0)
    outs = []
    for k in range(2):
        out = tmp_path / f"run{k}"
        pm.execute_notebook(str(paths.NOTEBOOKS / "03_guo2016_spearman_21_errors.ipynb"),
                            str(tmp_path / f"nb{k}.ipynb"), cwd=str(paths.NOTEBOOKS),
                            parameters=dict(small, output_dir=str(out)), kernel_name="python3",
                            progress_bar=False)
        outs.append({p.name: p.read_bytes() for p in sorted(out.iterdir())})
    assert outs[0].keys() == outs[1].keys()
    assert {".csv", ".png", ".svg", ".json"} <= {p.rsplit(".", 1)[1] and "." + p.rsplit(".", 1)[1]
                                                 for p in outs[0]}
    different = [name for name in outs[0] if outs[0][name] != outs[1][name]]
    assert different == []  # CSVs, figures (with provenance) and provenance.json alike
    assert os.environ.get(paths.OUTPUT_BASE_ENV)  # conftest redirected relative outputs


@pytest.mark.parametrize("stem", STEMS)
def test_outputs_do_not_depend_on_where_the_repository_lives(stem):
    """A stored output that shows this checkout's absolute path would differ in every clone."""
    text = (paths.NOTEBOOKS / f"{stem}.ipynb").read_text(encoding="utf-8")
    assert str(paths.ROOT) not in text
