"""Thermal module (Xu et al. 2022): decoupling, fuzzy clustering, grey relational grade,
the CSV schema and its validation, the models, and the reconstructed dataset."""

import shutil

import numpy as np
import pandas as pd
import papermill as pm
import pytest
from sklearn.linear_model import LinearRegression

from mtaccuracy import thermal
from mtaccuracy.compendium.notebook import NOTEBOOKS
from mtaccuracy.papers import printed, xu2022, xu2022_reconstruction

COMMITTED = xu2022.DATA
RNG = np.random.default_rng(5)


# ------------------------------------------------------------------ decoupling (Eq. 6, Eq. 7)

def test_decouple_recovers_known_lines_exactly():
    x = np.arange(0.0, 261.0, 20.0)
    k = np.array([-9.8, 0.0, 12.5])
    b = np.array([0.1, -4.0, 2.0])
    y = thermal.compose(k, b, x)
    assert y.shape == (3, 14) and y[0, -1] == pytest.approx(-9.8 * 0.26 + 0.1)
    k2, b2 = thermal.decouple(x, y)
    assert np.allclose(k2, k) and np.allclose(b2, b)


def test_decouple_ignores_residuals_orthogonal_to_lines_and_matches_polyfit():
    x = np.arange(185.0, 446.0, 20.0) - 185.0
    basis = np.column_stack([np.ones_like(x), x])
    noise = RNG.normal(size=(5, len(x)))
    noise -= noise @ (basis @ np.linalg.pinv(basis)).T          # project out 1 and x
    y = thermal.compose([1.0, -2.0, 3.0, -4.0, 5.0], [0.5, 0, 0, 0, -1], x) + noise
    k, b = thermal.decouple(x, y)
    assert np.allclose(k, [1, -2, 3, -4, 5]) and np.allclose(b, [0.5, 0, 0, 0, -1])
    rough = y + RNG.normal(size=y.shape)
    k, b = thermal.decouple(x, rough)
    ref = np.array([np.polyfit(x, r, 1) for r in rough])
    assert np.allclose(k, ref[:, 0] * 1000) and np.allclose(b, ref[:, 1])


def test_decouple_refuses_mismatched_positions():
    with pytest.raises(ValueError, match="distinct positions"):
        thermal.decouple(np.zeros(3), np.zeros((2, 3)))
    with pytest.raises(ValueError, match="matching the last axis"):
        thermal.decouple(np.arange(4.0), np.zeros((2, 3)))


def test_printed_model_reads_rises_for_d_terms():
    coef = {"intercept": 1.0, "T1": 2.0, "dT2": -3.0}
    values = {"T1": np.array([1.0]), "T2": np.array([0.5])}
    assert xu2022_reconstruction.printed_model(coef, values) == pytest.approx([1.5])


def test_metrics_by_hand():
    m = thermal.metrics([1.0, -3.0, 0.0, 2.0])
    assert m == pytest.approx({"rmse": np.sqrt(14 / 4), "max_residual": 3.0, "mae": 1.5})


# ------------------------------------------------------------------ fuzzy clustering (Eqs. 1-3)

def test_similarity_matrix_by_hand_is_blind_to_sign():
    x = np.array([[1.0, 3.0, 1.0], [2.0, 2.0, 1.0], [3.0, 1.0, 4.0]])   # a, b = reversed a, c
    r = thermal.similarity_matrix(x)
    assert np.allclose(np.diag(r), 1.0)
    assert r[0, 1] == pytest.approx(1.0)                        # |dev| patterns identical
    assert r[0, 2] == pytest.approx(3 / np.sqrt(12))            # (1*1 + 0*1 + 1*2) / (sqrt2 sqrt6)
    assert np.allclose(r, r.T)
    with pytest.raises(ValueError, match=r"variable\(s\) \[1\] are constant"):
        thermal.similarity_matrix(np.array([[1.0, 2.0], [2.0, 2.0]]))


def test_transitive_closure_by_hand():
    r = np.array([[1.0, 0.8, 0.2], [0.8, 1.0, 0.5], [0.2, 0.5, 1.0]])
    assert np.allclose(thermal.max_min_compose(r, r)[0, 2], 0.5)   # max(min(.8,.5), ...)
    t, k = thermal.transitive_closure(r)
    assert np.allclose(t, [[1.0, 0.8, 0.5], [0.8, 1.0, 0.5], [0.5, 0.5, 1.0]])
    assert k == 1                                                   # R^2 = R^4
    assert np.array_equal(thermal.max_min_compose(t, t), t)


def test_lambda_cut_by_hand():
    t = np.array([[1.0, 0.8, 0.5], [0.8, 1.0, 0.5], [0.5, 0.5, 1.0]])
    assert thermal.lambda_cut(t, 0.9).tolist() == [0, 1, 2]
    assert thermal.lambda_cut(t, 0.8).tolist() == [0, 0, 1]
    assert thermal.lambda_cut(t, 0.5).tolist() == [0, 0, 0]


def test_fuzzy_clusters_recover_three_obvious_groups():
    t = np.linspace(0, 1, 12)
    shapes = [t, np.exp(-5 * (t - 0.5) ** 2), np.sin(9 * t) + 3 * t]
    cols, names = [], []
    for g, s in enumerate(shapes):
        for j in range(3):
            cols.append(s * (1 + 0.3 * j) + 0.002 * RNG.normal(size=t.size))
            names.append(f"g{g}s{j}")
    order = RNG.permutation(len(names))
    cl = thermal.fuzzy_clusters(np.column_stack(cols)[:, order], [names[i] for i in order], 3)
    assert len(cl.groups) == 3
    assert sorted(sorted(g) for g in cl.groups) == [[f"g{g}s{j}" for j in range(3)]
                                                   for g in range(3)]
    assert 0 < cl.lam <= 1 and cl.squarings >= 1


def test_levels_closer_than_the_tolerance_are_one_level_and_ties_stay_ties():
    """Two pairs merging at 0.9 and at 0.9 (1 - 1e-14), equal but for rounding: a cut between
    the two would split the pairs' symmetry by noise; they merge at one level, whichever of
    the two is the larger, and no partition into exactly 3 classes exists."""
    def closure(a, b):
        return np.array([[1.0, a, 0.5, 0.5], [a, 1.0, 0.5, 0.5],
                         [0.5, 0.5, 1.0, b], [0.5, 0.5, b, 1.0]])
    lo = 0.9 * (1 - 1e-14)
    for a, b in ((0.9, lo), (lo, 0.9)):
        t = closure(a, b)
        assert thermal.cut_levels(t).tolist() == [1.0, lo, 0.5]
        lam, labels = thermal.cut_for(t, 3)
        assert lam == 1.0 and labels.tolist() == [0, 1, 2, 3]       # 4 classes, symmetric
        lam, labels = thermal.cut_for(t, 2)
        assert lam == lo and labels.tolist() == [0, 0, 1, 1]
    same = closure(1.0, 0.9)                             # variables 0 and 1 are one
    lam, labels = thermal.cut_for(same, 4)
    assert lam == 1.0 and labels.tolist() == [0, 0, 1, 2]
    assert thermal.cut_levels(closure(0.9, 0.8)).tolist() == [1.0, 0.9, 0.8, 0.5]
    # exact ties stay exact: Eq. 1 is exactly symmetric, equal columns give equal rows
    x = RNG.normal(size=(30, 7))
    x[:, 5] = x[:, 2]
    r = thermal.similarity_matrix(x)
    assert np.array_equal(r, r.T)
    assert np.array_equal(np.delete(r[2], [2, 5]), np.delete(r[5], [2, 5])) and r[2, 5] == 1.0


def _partition(labels) -> list[list[int]]:
    labels = np.asarray(labels)
    return sorted(np.flatnonzero(labels == g).tolist() for g in np.unique(labels))


def _assert_lambda_cuts_are_single_linkage(x):
    """The max-min transitive closure of R is the single-linkage (minimax path) similarity:
    scipy's cophenetic distances of single linkage on d = 1 - R are exactly 1 - t(R), and the
    lambda cut at every level of t(R) is scipy's flat clustering at distance 1 - lambda."""
    from scipy.cluster.hierarchy import cophenet, fcluster, linkage
    from scipy.spatial.distance import squareform

    r = thermal.similarity_matrix(x)
    t, _ = thermal.transitive_closure(r)
    z = linkage(squareform(1.0 - r, checks=False), method="single")
    assert np.array_equal(squareform(cophenet(z)), 1.0 - t)
    levels = thermal.cut_levels(t)
    assert len(levels) >= 3
    for lam in levels:
        assert _partition(thermal.lambda_cut(t, lam)) == \
            _partition(fcluster(z, 1.0 - lam, criterion="distance")), lam
    return z


def test_lambda_cuts_of_the_closure_are_scipy_single_linkage_on_random_data():
    for n_vars in (5, 12, 30):
        x = RNG.normal(size=(16, n_vars)).cumsum(axis=0)      # random walks: varied similarity
        _assert_lambda_cuts_are_single_linkage(x)


def test_lambda_cuts_are_scipy_single_linkage_on_the_notebooks_data(recon):
    """On the inputs of the notebook's selections (training experiments 1-3: temperature rises
    for Table 3 and b, absolute temperatures for k), and for the cut fuzzy_clusters picks."""
    from scipy.cluster.hierarchy import fcluster

    tr = recon.subset([1, 2, 3])
    for temps in (tr.rises(), tr.temperatures):
        x = temps.to_numpy()
        z = _assert_lambda_cuts_are_single_linkage(x)
        cl = thermal.fuzzy_clusters(x, temps.columns, 3)
        assert len(cl.groups) == 3
        assert _partition(cl.labels) == _partition(fcluster(z, 1.0 - cl.lam,
                                                            criterion="distance"))


def test_fuzzy_clusters_refuses_impossible_counts():
    with pytest.raises(ValueError, match=r"n_clusters must be an integer in \[1, 2\], got 3"):
        thermal.fuzzy_clusters(RNG.normal(size=(5, 2)), ["a", "b"], 3)


def test_integer_arguments_are_checked_once_with_the_same_words():
    """Every integer argument of the package goes through mtaccuracy.validate: a float with an
    integral value is taken, anything else refused naming the argument, range and value."""
    r = thermal.similarity_matrix(RNG.normal(size=(6, 3)))
    assert thermal.transitive_closure(r, max_squarings=5.0)[1] <= 2       # ceil(log2 3)
    with pytest.raises(ValueError, match=r"max_squarings must be an integer >= 0, got -1"):
        thermal.transitive_closure(r, max_squarings=-1)
    with pytest.raises(ValueError, match=r"n_clusters must be an integer >= 1, got 0"):
        thermal.cut_for(thermal.transitive_closure(r)[0], 0)
    with pytest.raises(ValueError, match=r"n must be an integer >= 0, got 1.5"):
        thermal.most_frequent([["T1"]], 1.5)
    with pytest.raises(ValueError, match=r"n_sensors must be an integer >= 1, got 0"):
        thermal.ridge_all_sensors(np.arange(3.0), 0)
    with pytest.raises(ValueError, match=r"n_samples must be an integer >= 1, got 0"):
        thermal.bounded_grid(thermal.SVR_GRID, 0)


# ------------------------------------------------------------------ grey relational grade (Eq. 4)

def test_grey_relational_grade_by_hand():
    x0 = np.array([1.0, 0.5, 0.0])
    x = np.array([[1.0, 0.0], [0.5, 0.5], [0.0, 1.0]])
    # column 1 equals x0: every coefficient is 1; column 2: deltas 1, 0, 1 with min 0, max 1:
    # (0 + 0.5) / (1 + 0.5) = 1/3, 1, 1/3 -> 5/9
    assert np.allclose(thermal.grey_relational_grade(x0, x, 0.5), [1.0, 5 / 9])
    # rho = 1: 1/2, 1, 1/2 -> 2/3
    assert np.allclose(thermal.grey_relational_grade(x0, x, 1.0), [1.0, 2 / 3])
    assert np.allclose(thermal.grey_relational_grade(x0, x0[:, None]), [1.0])
    with pytest.raises(ValueError, match="rho must be in"):
        thermal.grey_relational_grade(x0, x, 0.0)


def test_selection_keeps_the_best_graded_sensor_per_cluster_and_mirrors_falling_ones():
    t = np.linspace(0.0, 1.0, 10)
    target = t**2
    temps = pd.DataFrame({"A1": t**2 + 0.001 * t, "A2": t**1.2, "B1": -(t**2) * 3,
                          "B2": -t * 3 + 0.2 * np.sin(7 * t), "C1": np.sin(6 * t)})
    sel = thermal.select_sensitive_points(temps, target, n_clusters=3, rho=0.5)
    groups = sorted(sorted(g) for g in sel.clusters)
    assert ["C1"] in groups
    assert set(sel.selected) >= {"C1"}
    for g in sel.clusters:                                   # the winner has the top grade
        best = max(g, key=lambda s: sel.grades[s])
        assert best in sel.selected
    assert "B1" in sel.mirrored and "A1" not in sel.mirrored
    assert sel.grades["A1"] == pytest.approx(1.0, abs=1e-3)
    assert sel.grades["B1"] == pytest.approx(1.0, abs=1e-3)  # mirrored, same shape
    # how far each decision is from flipping
    leads = [np.subtract(*sel.grades[g].sort_values(ascending=False).iloc[:2])
             for g in sel.clusters if len(g) > 1]
    assert sel.margins["grade"] == pytest.approx(min(leads))
    corr = [abs(np.corrcoef(temps[c], target)[0, 1]) for c in temps]
    assert sel.margins["correlation"] == pytest.approx(min(corr))
    t_levels = thermal.cut_levels(thermal.transitive_closure(
        thermal.similarity_matrix(temps.to_numpy()))[0])
    others = t_levels[t_levels != sel.lam]
    assert sel.margins["level"] == pytest.approx(np.abs(others - sel.lam).min() / sel.lam)


def test_most_frequent_breaks_ties_by_sensor_order():
    picks = [["T1", "T6", "T12"], ["T1", "T7", "T12"], ["T2", "T6", "T11"]]
    assert thermal.most_frequent(picks, 3, order=[f"T{i}" for i in range(1, 13)]) == \
        ["T1", "T6", "T12"]


# ------------------------------------------------------------------ the CSV schema

@pytest.fixture
def good_dir(tmp_path):
    d = tmp_path / "good"
    shutil.copytree(COMMITTED, d, ignore=shutil.ignore_patterns("*.md"))
    return d


def _edit(path, fn):
    df = pd.read_csv(path, dtype=str, keep_default_na=False)
    fn(df).to_csv(path, index=False)


def test_reads_the_committed_reconstruction(good_dir):
    d = thermal.read_measurements(good_dir)
    assert d.temperatures.shape == (32, 12) and d.errors.shape == (32, 14)
    assert d.sensors[0] == "T1" and d.sensors[-1] == "T12"
    assert d.positions_mm[0] == 185 and d.positions_mm[-1] == 445
    assert d.feeds == {1: 2000, 2: 4000, 3: 6000, 4: 8000}
    assert np.allclose(d.rises().groupby(d.index.experiment).first(), 0.0)
    assert d.subset([4]).experiments == [4]


def test_write_then_read_is_byte_stable(good_dir, tmp_path):
    d = thermal.read_measurements(good_dir)
    assert thermal.write_measurements(d, good_dir) == []          # nothing changes
    out = tmp_path / "copy"
    assert len(thermal.write_measurements(d, out)) == 3
    for f in COMMITTED.glob("*.csv"):
        assert (out / f.name).read_bytes() == f.read_bytes()
    with pytest.raises(ValueError, match=r"error_decimals must be an integer >= 0, got 2.5"):
        thermal.write_measurements(d, tmp_path / "never", error_decimals=2.5)
    assert not (tmp_path / "never").exists()


@pytest.mark.parametrize("file, change, message", [
    ("errors.csv", lambda df: df.drop(columns="error_um"),
     r"errors.csv: missing column\(s\) \['error_um'\]"),
    ("temperatures.csv", lambda df: df.drop(columns="measurement"),
     r"temperatures.csv: missing column\(s\) \['measurement'\]"),
    ("errors.csv", lambda df: df.rename(columns={"error_um": "error_mm"}),
     r"errors.csv: column 'error_mm' gives error in 'mm'; the schema needs 'error_um'"),
    ("errors.csv", lambda df: df.rename(columns={"position_mm": "position_m"}),
     r"column 'position_m' gives position in 'm'; the schema needs 'position_mm'"),
    ("temperatures.csv", lambda df: df.rename(columns={"time_min": "time_s"}),
     r"column 'time_s' gives time in 's'; the schema needs 'time_min'"),
    ("temperatures.csv", lambda df: df.rename(columns={"T3_degC": "T3_K"}),
     r"temperatures.csv: column 'T3_K': temperatures must be in degrees Celsius"),
    ("temperatures.csv", lambda df: df.rename(columns={"T3_degC": "T3"}),
     r"column 'T3': temperatures must be in degrees Celsius.*found 'no unit'"),
    ("errors.csv", lambda df: df.assign(error_um=df.error_um.mask(df.index == 7, "NaN")),
     r"errors.csv: column 'error_um' has a missing, NaN or non-numeric value \('NaN'\) "
     r"on line\(s\) \[9\]"),
    ("temperatures.csv", lambda df: df.assign(T5_degC=df.T5_degC.mask(df.index == 2, "")),
     r"temperatures.csv: column 'T5_degC' has a missing, NaN or non-numeric value"),
    ("errors.csv", lambda df: df.drop(index=30),
     r"errors.csv: unequal lengths: experiment 1 measurement 3 has 13 positions, the data "
     r"hold 14 \(missing 225 mm\)"),
    ("temperatures.csv", lambda df: df.drop(index=31),
     r"unequal lengths: the files do not list the same measurements.*only in errors.csv: "
     r"\[\(4, 8\)\]"),
    ("temperatures.csv", lambda df: pd.concat([df, df.iloc[[0]]]),
     r"temperatures.csv: experiment 1 measurement 1 appears more than once"),
    ("errors.csv", lambda df: pd.concat([df, df.iloc[[0]]]),
     r"errors.csv: experiment 1 measurement 1 lists position 185 mm twice"),
    ("temperatures.csv", lambda df: df.assign(time_min=df.time_min.mask(df.index == 3, "10")),
     r"temperatures.csv: experiment 1: time_min must increase"),
    ("temperatures.csv", lambda df: df[["experiment", "measurement", "time_min", "T1_degC"]],
     r"needs at least 3 temperature columns"),
])
def test_malformed_files_are_refused_naming_file_and_problem(good_dir, file, change, message):
    _edit(good_dir / file, change)
    with pytest.raises(thermal.DataFormatError, match=message):
        thermal.read_measurements(good_dir)


def test_missing_file_and_folder_are_refused(good_dir, tmp_path):
    (good_dir / "errors.csv").unlink()
    with pytest.raises(thermal.DataFormatError, match=r"errors.csv: file not found"):
        thermal.read_measurements(good_dir)
    with pytest.raises(thermal.DataFormatError, match="not a folder"):
        thermal.read_measurements(tmp_path / "nowhere")


def test_times_are_checked_in_measurement_order_not_file_order(good_dir):
    """Measurement numbers give the order; a file whose numbers contradict its times is
    refused (times 0, 23, 69, 46 in measurement order), one with rows shuffled is read."""
    def swap(df):   # experiment 1: measurement 3 at 69 min, measurement 4 at 46 min
        df = df.copy()
        df.loc[2, "measurement"], df.loc[3, "measurement"] = "4", "3"
        return df
    _edit(good_dir / "temperatures.csv", swap)
    with pytest.raises(thermal.DataFormatError,
                       match=r"temperatures.csv: experiment 1: time_min must increase with the "
                             r"measurement number, but measurement 4 \(line 4, 46 min\) does not "
                             r"come after measurement 3 \(line 5, 69 min\); times in "
                             r"measurement order: 0 -> 23 -> 69 -> 46 -> 92"):
        thermal.read_measurements(good_dir)


def test_rows_in_any_order_read_the_same(good_dir):
    ref = thermal.read_measurements(good_dir)
    for name in ("temperatures.csv", "errors.csv"):
        _edit(good_dir / name, lambda df: df.iloc[np.random.default_rng(3).permutation(len(df))])
    d = thermal.read_measurements(good_dir)
    assert d.index.equals(ref.index) and d.temperatures.equals(ref.temperatures)
    assert np.array_equal(d.errors, ref.errors)


def _at(df, experiment=None, measurement=None, position=None):
    m = np.ones(len(df), dtype=bool)
    for col, v in (("experiment", experiment), ("measurement", measurement),
                   ("position_mm", position)):
        if v is not None:
            m &= df[col].astype(float).to_numpy() == v
    return m


def test_re_zeroed_measurements_are_refused(good_dir):
    """Every measurement of an experiment reading exactly 0 at one target is the signature of
    re-zeroing before each measurement; a single later zero reading is not (it may be drift)."""
    _edit(good_dir / "errors.csv", lambda df: df.assign(
        error_um=df.error_um.mask(_at(df, experiment=2, measurement=5, position=185), "0")))
    assert thermal.read_measurements(good_dir).errors.shape == (32, 14)
    _edit(good_dir / "errors.csv", lambda df: df.assign(
        error_um=df.error_um.mask(_at(df, experiment=3, position=305), "0.0")))
    with pytest.raises(thermal.DataFormatError,
                       match=r"errors.csv: experiment 3: all 8 measurements read exactly 0 at "
                             r"305 mm, the signature of an interferometer re-zeroed before every "
                             r"measurement"):
        thermal.read_measurements(good_dir)


def _scaled(column, factor, fmt):
    return lambda df: df.assign(**{column: (df[column].astype(float) * factor).map(fmt.format)})


@pytest.mark.parametrize("file, change, message", [
    ("temperatures.csv", lambda df: df.assign(T3_degC=(df.T3_degC.astype(float) + 273.15)
                                              .map("{:.2f}".format)),
     r"temperatures.csv: column 'T3_degC' has value\(s\) 304.07, .* degC on line\(s\) "
     r"\[2, 3, .*outside the plausible range -30 .. 200 degC.*kelvin\?"),
    ("temperatures.csv", lambda df: df.assign(T7_degC=df.T7_degC.mask(df.index == 5, "-45")),
     r"column 'T7_degC' has value\(s\) -45 degC on line\(s\) \[7\], outside the plausible "
     r"range -30 .. 200 degC"),
    ("errors.csv", _scaled("error_um", 1e-3, "{:.6f}"),
     r"errors.csv: column 'error_um' spans only 0.013935 um \(-0.013884 .. 5.1e-05\), less than "
     r"the plausible 1 um .*mm\?"),
    ("errors.csv", _scaled("error_um", 1e3, "{:.0f}"),
     r"errors.csv: column 'error_um' has value\(s\) -1251, .* um on line\(s\) .* outside the "
     r"plausible range -1000 .. 1000 um.*nm\?"),
    ("errors.csv", _scaled("position_mm", 1e-3, "{:.3f}"),
     r"errors.csv: column 'position_mm' spans only 0.26 mm \(0.185 .. 0.445\), less than the "
     r"plausible 1 mm.*m\?"),
])
def test_values_in_the_wrong_unit_are_refused_with_the_limits(good_dir, file, change, message):
    _edit(good_dir / file, change)
    with pytest.raises(thermal.DataFormatError, match=message):
        thermal.read_measurements(good_dir)


def test_duplicated_experiment_in_experiments_csv_is_refused(good_dir):
    _edit(good_dir / "experiments.csv",
          lambda df: pd.concat([df, df.iloc[[1]].assign(feed_mm_per_min="5000")]))
    with pytest.raises(thermal.DataFormatError,
                       match=r"experiments.csv: experiment\(s\) \[2\] listed more than once "
                             r"\(lines \[3, 6\]\)"):
        thermal.read_measurements(good_dir)


def test_data_beyond_the_size_limits_are_refused(good_dir):
    _edit(good_dir / "temperatures.csv", lambda df: df.assign(
        **{f"X{i}_degC": df.T1_degC for i in range(thermal.MAX_SENSORS - 11)}))
    with pytest.raises(thermal.DataFormatError,
                       match=r"temperatures.csv: 101 temperature columns; at most 100 are "
                             r"supported"):
        thermal.read_measurements(good_dir)
    _edit(good_dir / "temperatures.csv",
          lambda df: df.filter(regex="^(?!X)").iloc[np.arange(1001) % len(df)])
    with pytest.raises(thermal.DataFormatError, match=r"1001 measurements \(rows\); at most 1000"):
        thermal.read_measurements(good_dir)


def test_an_oversized_file_is_refused_before_it_is_read(good_dir, monkeypatch):
    monkeypatch.setattr(thermal.csvfile, "MAX_FILE_BYTES", 5000)
    with pytest.raises(thermal.DataFormatError,
                       match=r"errors.csv: 6776 bytes; files up to 5000 bytes are read"):
        thermal.read_measurements(good_dir)


# ------------------------------------------------------------------ line numbers in messages

def _respace(header: str, rows: list[str], layout: str) -> str:
    """A file of ``header`` and ``rows`` with blank lines (empty, spaces, a tab) before the
    header, after it and between data rows; ``crlf``: Windows line ends; ``quoted``: the last
    field of the first and of the middle row quoted with two line breaks inside (the value
    still reads as its number, the rows after it move down two lines)."""
    nl = "\r\n" if layout == "crlf" else "\n"
    rows = list(rows)
    if layout == "quoted":
        for i in (0, len(rows) // 2):
            head, last = rows[i].rsplit(",", 1)
            rows[i] = f'{head},"{last}{nl}{nl}"'
    out = ["", " \t", header, ""]
    for i, r in enumerate(rows):
        out += [r] + (["", "  "] if i % 3 == 0 else [])
    return nl.join(out + ["", ""]) + nl


def _file_lines(text: str, prefix: str) -> list[int]:
    """The 1-based line numbers, as an editor shows them, of the lines starting with
    ``prefix`` (found in the text, independently of the reader)."""
    return [i + 1 for i, line in enumerate(text.splitlines()) if line.startswith(prefix)]


def _set(prefix: str, column: int, value: str):
    """An edit of a file's rows: field ``column`` of the row starting with ``prefix``."""
    def edit(rows):
        out = []
        for r in rows:
            if r.startswith(prefix):
                fields = r.split(",")
                fields[column] = value
                r = ",".join(fields)
            out.append(r)
        return out
    return edit


def _swap_3_4(rows):   # experiment 1: measurement 3 at 69 min, measurement 4 at 46 min
    return [r.replace("1,3,46,", "1,4,46,", 1) if r.startswith("1,3,46,") else
            r.replace("1,4,69,", "1,3,69,", 1) if r.startswith("1,4,69,") else r for r in rows]


# (file, edit of its rows, the message with {line...} where the lines go: the file's lines of
# the rows starting with the given prefixes)
BAD_ROWS = [
    ("temperatures.csv", _set("2,2,", 7, "x"),
     r"column 'T5_degC' has a missing, NaN or non-numeric value \('x'\) on line\(s\) \[{0}\]",
     ["2,2,"]),
    ("temperatures.csv", _set("3,4,", 1, "4.5"),
     r"column 'measurement' must hold whole numbers \(line\(s\) \[{0}\]\)", ["3,4.5,"]),
    ("temperatures.csv", _set("4,6,", 9, "-45"),
     r"column 'T7_degC' has value\(s\) -45 degC on line\(s\) \[{0}\], outside", ["4,6,"]),
    ("temperatures.csv", lambda rows: rows + [rows[2]],
     r"experiment 1 measurement 3 appears more than once \(lines \[{0}, {1}\]\)", ["1,3,"]),
    ("temperatures.csv", _swap_3_4,
     r"measurement 4 \(line {0}, 46 min\) does not come after measurement 3 \(line {1}, 69 min\)",
     ["1,4,", "1,3,"]),
    ("temperatures.csv", lambda rows: rows[:9] + ["# sensors recalibrated"] + rows[9:],
     r"column 'experiment' has a missing, NaN or non-numeric value \('# sensors recalibrated'\) "
     r"on line\(s\) \[{0}\]", ["#"]),
    ("temperatures.csv", lambda rows: rows[:17] + [rows[17] + ",9"] + rows[18:],
     r"temperatures.csv: line {0} has 16 fields, the header \(line 3\) has 15$", ["3,2,"]),
    ("temperatures.csv", lambda rows: [rows[0] + ",9"] + rows[1:],   # pandas: an index column
     r"temperatures.csv: line {0} has 16 fields, the header \(line 3\) has 15$", ["1,1,"]),
    ("temperatures.csv", lambda rows: rows[:-1] + [',"'.join(rows[-1].rsplit(",", 1))],
     r"a quoted field of the row starting on line {0} is never closed", ["4,8,"]),
    ("errors.csv", _set("2,5,305,", 3, "n/a"),
     r"errors.csv: column 'error_um' has a missing, NaN or non-numeric value \('n/a'\) on "
     r"line\(s\) \[{0}\]", ["2,5,305,"]),
    ("errors.csv", lambda rows: rows + [rows[0]],
     r"experiment 1 measurement 1 lists position 185 mm twice \(lines \[{0}, {1}\]\)",
     ["1,1,185,"]),
    ("experiments.csv", lambda rows: rows + ["2,5000"],
     r"experiment\(s\) \[2\] listed more than once \(lines \[{0}, {1}\]\)", ["2,"]),
]


@pytest.mark.parametrize("layout", ["blank", "crlf", "quoted"])
@pytest.mark.parametrize("file, edit, message, prefixes", BAD_ROWS,
                         ids=[f"{f[:-4]}-{i}" for i, (f, *_) in enumerate(BAD_ROWS)])
def test_messages_name_the_files_real_lines(good_dir, layout, file, edit, message, prefixes):
    """Blank lines before the header and between rows, Windows line ends, line breaks inside
    quoted fields and a comment line (the schema has none: a row like any other): every
    message about a bad row names the lines an editor shows."""
    header, *rows = (good_dir / file).read_text().splitlines()
    text = _respace(header, edit(rows), layout)
    (good_dir / file).write_bytes(text.encode())
    lines = [n for prefix in prefixes for n in _file_lines(text, prefix)]
    with pytest.raises(thermal.DataFormatError, match=message.format(*lines)):
        thermal.read_measurements(good_dir)


@pytest.mark.parametrize("layout", ["blank", "crlf", "quoted"])
def test_blank_lines_and_quoted_line_breaks_read_the_same(good_dir, layout):
    ref = thermal.read_measurements(good_dir)
    for f in good_dir.glob("*.csv"):
        header, *rows = f.read_text().splitlines()
        f.write_bytes(_respace(header, rows, layout).encode())
    d = thermal.read_measurements(good_dir)
    assert d.index.equals(ref.index) and d.temperatures.equals(ref.temperatures)
    assert np.array_equal(d.errors, ref.errors) and d.feeds == ref.feeds


def test_a_byte_that_is_not_utf8_is_refused_naming_its_line(good_dir):
    header, *rows = (good_dir / "errors.csv").read_text().splitlines()
    text = _respace(header, _set("3,3,245,", 3, "-0.2\u00b5")(rows), "blank")
    (good_dir / "errors.csv").write_bytes(text.encode("latin-1"))
    with pytest.raises(thermal.DataFormatError,
                       match=rf"errors.csv: not UTF-8 text: byte 0xb5 on line "
                             rf"{_file_lines(text, '3,3,245,')[0]}; save the file as UTF-8"):
        thermal.read_measurements(good_dir)


# ------------------------------------------------------------------ models

def _synthetic(n_exp=4, n_meas=6, seed=0):
    """Temperatures with k and b exactly linear in them (k from absolute T1, T2; b from rises
    of T3): every model family should recover the relations."""
    rng = np.random.default_rng(seed)
    rows, temps, errors = [], [], []
    x = np.arange(0.0, 100.0, 20.0)
    for e in range(1, n_exp + 1):
        base = rng.normal(25, 1, size=4)
        for j in range(n_meas):
            t = base + rng.normal(0, 0.5, size=4) + [0.3 * j, 0.2 * j, 0.4 * j, 0.0]
            temps.append(t)
            rows.append((e, j + 1, 10.0 * j))
        block = np.array(temps[-n_meas:])
        k = 2.0 * block[:, 0] - 1.0 * block[:, 1]
        b = -3.0 * (block[:, 2] - block[0, 2]) + 0.5
        errors.append(thermal.compose(k, b, x))
    index = pd.DataFrame(rows, columns=["experiment", "measurement", "time_min"])
    return thermal.ThermalData(index, pd.DataFrame(temps, columns=["T1", "T2", "T3", "T4"]),
                               np.vstack(errors), x + 100.0)


def test_decoupled_mlr_recovers_exact_linear_relations():
    d = _synthetic()
    inputs = {"k": ["T1", "T2"], "b": ["T3"]}
    m = thermal.decoupled(d.subset([1, 2, 3]), inputs)
    c = thermal.eq9_table(m, inputs).set_index(["target", "term"]).coefficient
    assert c[("k (um/m)", "T1")] == pytest.approx(2.0) and c[("k (um/m)", "T2")] == \
        pytest.approx(-1.0)
    assert c[("b (um)", "dT3")] == pytest.approx(-3.0) and c[("b (um)", "intercept")] == \
        pytest.approx(0.5)
    test = d.subset(4)
    assert np.allclose(m.predict(thermal.design(test, inputs, "decoupled")), test.errors)


def test_point_by_point_is_one_regression_per_position():
    d = _synthetic()
    inputs = {"point": ["T1", "T3"]}
    p = thermal.point_by_point(d.subset([1, 2, 3]), inputs)
    assert len(p.estimators_) == len(d.positions_mm)
    x4 = thermal.design(d.subset(4), inputs, "point")
    assert p.predict(x4).shape == d.subset(4).errors.shape
    assert list(thermal.eq8_table(p, inputs["point"], d.positions_mm).columns) == [
        "position_mm", "intercept", "T1", "T3"]
    for j, m in enumerate(p.estimators_):                  # each column its own regression
        one = LinearRegression().fit(thermal.design(d.subset([1, 2, 3]), inputs, "point"),
                                     d.subset([1, 2, 3]).errors[:, j])
        assert np.allclose(m.coef_, one.coef_) and np.isclose(m.intercept_, one.intercept_)


def test_svr_search_is_grouped_and_deterministic():
    d = _synthetic()
    tr = d.subset([1, 2, 3])
    k, _ = thermal.decouple(tr.offsets_mm(), tr.errors)
    x = tr.temperatures[["T1", "T2"]].to_numpy()
    a = thermal.svr_search(x, k, groups=tr.groups)
    b = thermal.svr_search(x, k, groups=tr.groups)
    assert a.best_params_ == b.best_params_ and a.best_index_ == b.best_index_
    assert a.n_splits_ == 3                                       # one fold per experiment
    assert a.best_params_["kernel"] == "linear"                   # the truth is linear
    with pytest.raises(ValueError, match="at least 2 training experiments"):
        thermal.svr_search(x, k, groups=np.ones(len(k)))


def test_svr_ties_go_to_the_simplest_candidate_whatever_the_grid_order():
    """Exactly linear data inside the tube: C = 1000 and C = 10 give the same model and equal
    scores; scikit-learn's first best would take C = 1000 (listed first), the canonical rule
    the smaller C."""
    rng = np.random.default_rng(0)
    x = rng.normal(size=(24, 2))
    y = x @ [1.0, -2.0] + 0.5
    grid = [{"kernel": ["linear"], "C": [1000.0, 10.0], "epsilon": [0.1]}]
    s = thermal.svr_search(x, y, groups=np.repeat([1, 2, 3], 8), grid=grid)
    rmse = -s.cv_results_["mean_test_score"]
    assert rmse[0] <= rmse[1] * (1 + thermal.SVR_TIE_RTOL)        # a tie
    assert s.best_params_["C"] == 10.0


def test_standardised_svr_is_the_scaled_pipeline():
    """Cross-check with scikit-learn's own composition of the same model."""
    from sklearn.compose import TransformedTargetRegressor
    from sklearn.pipeline import Pipeline
    from sklearn.preprocessing import StandardScaler
    from sklearn.svm import SVR
    rng = np.random.default_rng(4)
    x = rng.normal(30, 2, size=(20, 3))
    x[:, 2] = 25.0                                              # a constant column
    y = np.sin(x[:, 0]) + 0.1 * x[:, 1] + rng.normal(0, 0.05, 20)
    for kw in ({"kernel": "rbf", "C": 10.0, "gamma": 0.1, "epsilon": 0.05},
               {"kernel": "linear", "C": 1.0, "epsilon": 0.1}):
        ours = thermal.StandardisedSVR(**kw).fit(x[:15], y[:15]).predict(x[15:])
        ref = TransformedTargetRegressor(
            Pipeline([("s", StandardScaler()), ("svr", SVR(tol=1e-6, **kw))]),
            transformer=StandardScaler()).fit(x[:15], y[:15]).predict(x[15:])
        assert np.allclose(ours, ref, rtol=0, atol=1e-5 * np.ptp(y))


def test_canonical_best_treats_scores_within_the_tolerance_as_ties():
    params = [{"kernel": "rbf", "C": 1.0, "gamma": 0.1, "epsilon": 0.1},
              {"kernel": "linear", "C": 100.0, "epsilon": 0.01},
              {"kernel": "linear", "C": 10.0, "epsilon": 0.01},
              {"kernel": "linear", "C": 10.0, "epsilon": 0.1},
              {"kernel": "linear", "C": 0.1, "epsilon": 0.1}]
    rmse = np.array([1.0, 1.0004, 1.0009, 1.0009, 1.0011])
    res = {"mean_test_score": -rmse, "params": params}
    assert thermal.canonical_best(res) == 3          # linear, smallest C, then larger epsilon
    assert thermal.canonical_best(res, rtol=1e-4) == 0
    assert thermal.canonical_best(res, rtol=0.0) == 0
    assert thermal.canonical_best(res, rtol=2e-3) == 4
    tied, margin = thermal.tie_margin(res)
    assert tied == 4 and margin == pytest.approx(1e-4)
    far = {"mean_test_score": [-1.0, -1.5], "params": params[:2]}
    assert thermal.tie_margin(far) == (1, pytest.approx(0.5 - 1e-3))   # the best is no edge
    with pytest.raises(ValueError, match="every SVR candidate failed"):
        thermal.canonical_best({"mean_test_score": [np.nan], "params": params[:1]})


def test_leave_one_out_reuses_a_split_already_evaluated(monkeypatch):
    d = _synthetic()
    fixed = {"point": ["T1", "T3"], "k": ["T1", "T2"], "b": ["T3"]}
    full = thermal.leave_one_experiment_out(d, n_clusters=2, kinds=("mlr",), sensors=fixed)
    done = thermal.evaluate_split(d, train=[1, 2, 3], test=[4], n_clusters=2, kinds=("mlr",),
                                  sensors=fixed)
    other = thermal.evaluate_split(d, train=[1, 2, 3], test=[4], n_clusters=2,
                                   kinds=("mlr",))                           # other settings
    calls = []
    real = thermal.evaluate_split
    monkeypatch.setattr(thermal.validation, "evaluate_split",
                        lambda data, **k: calls.append(k["test"]) or real(data, **k))
    again = thermal.leave_one_experiment_out(d, n_clusters=2, kinds=("mlr",), sensors=fixed,
                                             reuse=[other, done])
    assert calls == [[1], [2], [3]]
    pd.testing.assert_frame_equal(again, full)


def test_evaluate_split_refuses_unknown_sensors_and_experiments():
    d = _synthetic()
    with pytest.raises(ValueError, match=r"no sensor\(s\) \['T9'\]"):
        thermal.evaluate_split(d, train=[1, 2, 3], test=[4], sensors={"k": ["T9"]})
    with pytest.raises(ValueError, match=r"unknown experiment\(s\) \[7\]"):
        d.subset([7])


# ------------------------------------------------------------------ the reconstruction

@pytest.fixture(scope="module")
def recon():
    return xu2022.reconstruct()


def test_generator_regenerates_the_committed_files_byte_identically(recon, tmp_path):
    written = thermal.write_measurements(recon, tmp_path)
    assert sorted(p.name for p in written) == sorted(p.name for p in COMMITTED.glob("*.csv"))
    for f in COMMITTED.glob("*.csv"):
        assert (tmp_path / f.name).read_bytes() == f.read_bytes(), f.name
    assert thermal.write_measurements(xu2022.reconstruct(), tmp_path) == []


def test_decoupling_the_reconstruction_gives_table5(recon):
    k5, b5, _ = xu2022.published_targets()
    k, b = thermal.decouple(recon.offsets_mm(), recon.errors)
    assert np.abs(k - k5.ravel()).max() <= 0.05
    assert np.abs(b - b5.ravel()).max() <= 0.05
    first = recon.index.measurement.to_numpy() == 1
    assert np.all(recon.errors[first, 0] == 0.0)          # laser zeroed at the first target


def test_the_printed_models_fit_the_reconstruction_within_the_published_residuals(recon):
    models = printed.published("xu2022_models")
    c = xu2022_reconstruction.eq9_consistency(recon, models)
    assert c.k_residual.abs().max() <= 3.6                # Table 7, largest slope residual
    assert c.b_residual.abs().max() <= 0.8                # Table 7, largest intercept residual
    rms4 = np.sqrt(np.mean(c[c.experiment == 4].k_residual ** 2))
    assert 2.0 <= rms4 <= 3.2                             # Table 7: RMSE 2.6 um/m
    r8 = xu2022_reconstruction.eq8_residuals(recon, models)
    assert sorted(r8.position_mm.unique()) == [185, 205, 225, 445]
    assert r8.residual.abs().max() <= 4.3                 # Table 4, largest residual


def test_reconstruction_is_physically_plausible(recon):
    _, _, t1 = xu2022.published_targets()
    for _, r in t1.iterrows():
        air = recon.subset(int(r.experiment)).temperatures["T10"]
        assert abs(air.min() - r.ambient_min_C) <= 0.05 and abs(air.max() - r.ambient_max_C) <= 0.05
    heat = ["T6", "T7", "T11", "T12"]
    ends = recon.temperatures[heat].groupby(recon.index.experiment).agg(["first", "last"])
    for s in heat:                                        # heat sources warm up
        assert (ends[(s, "last")] > ends[(s, "first")]).all(), s
    hottest = recon.temperatures.groupby(recon.index.experiment).max().max().idxmax()
    assert hottest in ("T7", "T12")                       # the motor runs hottest
    assert np.all(np.diff(recon.index.time_min.to_numpy().reshape(4, 8)) > 0)


def test_noise_replicates_start_with_the_reconstruction_and_redraw_only_the_noise(recon):
    reps = xu2022.noise_replicates(2022, 4)
    assert len(reps) == 4 and reps.sensors == recon.sensors
    assert np.array_equal(reps.temperatures[0], recon.temperatures.to_numpy())
    assert np.array_equal(reps.errors[0], recon.errors)
    spread = reps.temperatures.std(axis=0).max(axis=0)           # per sensor
    t12 = reps.sensors.index("T12")
    assert spread[t12] == 0.0                                    # noise-free, read at 0.1 degC
    assert 0.0 < np.delete(spread, t12).max() < 0.05             # 0.005-0.01 degC noise
    assert np.all(reps.errors[:, recon.index.measurement == 1, 0] == 0.0)   # laser zeroing
    assert not np.array_equal(reps.errors[1], reps.errors[2])
    with pytest.raises(ValueError, match=r"n must be an integer >= 2, got 1"):
        xu2022.noise_replicates(2022, 1)


def test_fit_linear_is_linear_regression_batched():
    from sklearn.linear_model import LinearRegression

    x, y = RNG.normal(size=(3, 20, 4)), RNG.normal(size=(3, 20, 2))
    c = thermal.fit_linear(x, y)
    c1 = thermal.fit_linear(x, y[..., 0])
    for r in range(3):
        m = LinearRegression().fit(x[r], y[r])
        assert np.allclose(c[r, 0], m.intercept_) and np.allclose(c[r, 1:].T, m.coef_)
        assert np.allclose(c1[r], c[r, :, 0])
        assert np.allclose(thermal.predict_linear(c, x)[r], m.predict(x[r]))
    assert np.allclose(thermal.predict_linear(c1, x), thermal.predict_linear(c, x)[..., 0])
    res = RNG.normal(size=(3, 5, 7))
    bm = thermal.batch_metrics(res)
    for r in range(3):
        assert {k: v[r] for k, v in bm.items()} == pytest.approx(thermal.metrics(res[r]))


def test_replicate_split_on_replicate_0_is_the_notebooks_split(recon):
    """Replicate 0 is the reconstruction itself: the batched fits give evaluate_split's
    coefficients and metrics (MLR), and the SVR with fixed hyperparameters what
    StandardisedSVR gives on the same inputs."""
    fixed = {"point": ["T1", "T11", "T12"], "k": ["T1", "T6", "T12"], "b": ["T2", "T7", "T11"]}
    params = {"k": {"kernel": "linear", "C": 10.0, "epsilon": 0.1},
              "b": {"kernel": "rbf", "C": 10.0, "gamma": 0.1, "epsilon": 0.1}}
    reps = xu2022.noise_replicates(2022, 3)
    f = thermal.replicate_split(reps, train=[1, 2, 3], test=[4], inputs=fixed, svr_params=params)
    assert len(f) == 3 and f.iloc[1:].std().max() > 0
    r = thermal.evaluate_split(recon, train=[1, 2, 3], test=[4], kinds=("mlr",), sensors=fixed)
    for (method, target), row in r.table.set_index(["method", "target"]).iterrows():
        for m in ("rmse", "max_residual", "mae"):
            # the table holds METRIC_DIGITS = 6 significant digits
            assert f[(method, target, m)].iloc[0] == pytest.approx(row[m], rel=5e-6)
            assert row[m] == float(f"{f[(method, target, m)].iloc[0]:.6g}")
    eq9 = thermal.eq9_table(r.models["decoupled_mlr"], fixed)
    for _, c in eq9.iterrows():
        assert f[("eq9", c.target, c.term)].iloc[0] == pytest.approx(c.coefficient, rel=1e-9)
    eq8 = thermal.eq8_table(r.models["point_by_point_mlr"], fixed["point"], recon.positions_mm)
    assert f[("eq8", "445", "T11")].iloc[0] == pytest.approx(eq8.T11.iloc[-1], rel=1e-9)
    resid = r.measured - r.predictions["point_by_point_mlr"]
    assert f[("point_by_point_mlr", "largest residual at", "185")].iloc[0] == \
        pytest.approx(np.abs(resid[:, 0]).max())
    assert f[("decoupled_mlr", "residual of the error", "lowest")].iloc[0] == \
        pytest.approx((r.measured - r.predictions["decoupled_mlr"]).min())
    assert f[("test", "largest |error|", "")].iloc[0] == np.abs(recon.subset(4).errors).max()
    tr, te = recon.subset([1, 2, 3]), recon.subset(4)
    k, b = thermal.decouple(tr.offsets_mm(), tr.errors)
    xtr, xte = thermal.design(tr, fixed, "decoupled"), thermal.design(te, fixed, "decoupled")
    (xk, xb), (tk, tb) = (xtr[:, :3], xtr[:, 3:]), (xte[:, :3], xte[:, 3:])
    kp = thermal.StandardisedSVR(**params["k"]).fit(xk, k).predict(tk)
    bp = thermal.StandardisedSVR(**params["b"]).fit(xb, b).predict(tb)
    want = thermal.metrics(te.errors - thermal.compose(kp, bp, te.offsets_mm()))
    for m, v in want.items():
        assert f[("decoupled_svr", "thermal positioning error", m)].iloc[0] == \
            pytest.approx(v, rel=1e-9)
    with pytest.raises(ValueError, match=r"no sensor\(s\) \['T99'\]"):
        thermal.replicate_split(reps, train=[1, 2, 3], test=[4], inputs={**fixed, "k": ["T99"]})


def test_a_rounding_level_change_of_the_inputs_leaves_a_split_bit_identical(recon):
    """Another CPU's BLAS kernel changes the inputs by rounding; libsvm solved to
    SVR_SOLVER_TOL and the tables held to METRIC_DIGITS make the split's tables the same
    bytes, and its predictions agree far below what a figure draws (xu2022.PLOT_DECIMALS).
    At the former tol 1e-6, with the scores as they came, such a change moved them by up to
    3e-5 relative."""
    rng = np.random.default_rng(0)
    t = recon.temperatures
    nudged = thermal.ThermalData(recon.index, t * (1 + 2e-16 * rng.choice([-1, 1], t.shape)),
                                 recon.errors, recon.positions_mm, recon.feeds)
    assert not nudged.temperatures.equals(t)
    fixed = {"point": ["T1", "T11", "T12"], "k": ["T1", "T6", "T12"], "b": ["T2", "T7", "T11"]}
    a, b = (thermal.evaluate_split(d, train=[1, 2, 3], test=[4], sensors=fixed)
            for d in (recon, nudged))
    pd.testing.assert_frame_equal(a.table, b.table, check_exact=True)
    for m, pred in a.predictions.items():
        assert np.abs(pred - b.predictions[m]).max() < 1e-8                  # um
    assert thermal.svr_hyperparameters(a.models["decoupled_svr"]).equals(
        thermal.svr_hyperparameters(b.models["decoupled_svr"]))


def test_write_measurements_asks_before_overwriting_and_writes_nothing_when_refused(good_dir):
    def state():
        return {f.name: (f.read_bytes(), f.stat().st_mtime_ns) for f in good_dir.iterdir()}

    asked = []
    assert thermal.write_measurements(thermal.read_measurements(good_dir), good_dir,
                                      before_overwrite=asked.append) == [] and asked == []

    def refuse(files):
        asked.append(files)
        raise RuntimeError("refused")

    before = state()
    other = xu2022.reconstruct(seed=7)   # other noise, the same feeds: experiments.csv unchanged
    with pytest.raises(RuntimeError, match="refused"):
        thermal.write_measurements(other, good_dir, before_overwrite=refuse)
    assert asked == [[good_dir / "temperatures.csv", good_dir / "errors.csv"]]
    assert state() == before
    (good_dir / "errors.csv").unlink()                  # a missing file is not asked about
    assert thermal.write_measurements(other, good_dir, before_overwrite=asked.append) == \
        [good_dir / "temperatures.csv", good_dir / "errors.csv"]
    assert asked[-1] == [good_dir / "temperatures.csv"]


def test_published_inputs_decoupled_beats_point_by_point_on_the_paper_split(recon):
    fixed = {"point": ["T1", "T11", "T12"], "k": ["T1", "T6", "T12"], "b": ["T2", "T7", "T11"]}
    r = thermal.evaluate_split(recon, train=[1, 2, 3], test=[4], kinds=("mlr",), sensors=fixed)
    t = r.table.set_index(["method", "target"]).rmse
    assert t[("decoupled_mlr", "thermal positioning error")] < 1.0
    assert t[("decoupled_mlr", "thermal positioning error")] < \
        t[("point_by_point_mlr", "thermal positioning error")]
    assert r.inputs == fixed and len(r.position_selections) == 14


# ------------------------------------------------------------------ the notebook on a reader's data

def test_notebook_refuses_a_malformed_data_dir_and_leaves_it_alone(good_dir, tmp_path):
    _edit(good_dir / "errors.csv", lambda df: df.rename(columns={"error_um": "error_mm"}))
    before = {f.name: f.read_bytes() for f in good_dir.iterdir()}
    with pytest.raises(pm.PapermillExecutionError, match="error_mm"):
        pm.execute_notebook(str(NOTEBOOKS / "04_xu2022_thermal_mlr_svr.ipynb"),
                            str(tmp_path / "nb.ipynb"), cwd=str(NOTEBOOKS),
                            parameters={"data_dir": str(good_dir),
                                        "output_dir": str(tmp_path / "out")},
                            kernel_name="python3", progress_bar=False)
    assert {f.name: f.read_bytes() for f in good_dir.iterdir()} == before


# ------------------------------------------------------------------ scikit-learn conformance

@pytest.mark.parametrize("estimator", [
    thermal.StandardisedSVR(),
    thermal.PointByPointRegressor(),
    thermal.GroupedSVR(grid=[{"kernel": ["linear"], "C": [0.1, 1.0], "epsilon": [0.1]}]),
], ids=lambda e: type(e).__name__)
def test_estimators_pass_scikit_learns_checks(estimator):
    from sklearn.utils.estimator_checks import check_estimator

    failed = check_estimator(estimator, on_fail=None)
    bad = [(r["check_name"], str(r["exception"])[:200]) for r in failed
           if r["status"] == "failed"]
    assert not bad, bad


def test_decoupled_regressor_composes_with_grid_search_and_group_kfold():
    from sklearn.base import clone
    from sklearn.model_selection import GridSearchCV, GroupKFold, cross_val_score

    d = _synthetic()
    inputs = {"k": ["T1", "T2"], "b": ["T3"]}
    x = thermal.design(d, inputs, "decoupled")
    model = thermal.DecoupledRegressor(d.offsets_mm(), [0, 1], [2])
    assert clone(model).get_params()["k_columns"] == [0, 1]       # parameters kept unchanged
    assert not hasattr(model, "k_estimator_")                     # fitted state only after fit
    scores = cross_val_score(model, x, d.errors, groups=d.groups, cv=GroupKFold(4),
                             scoring="neg_root_mean_squared_error")
    assert scores.shape == (4,) and np.all(-scores < 1e-8)        # exact linear relations
    search = GridSearchCV(model, {"b_columns": [[2], [1]]}, cv=GroupKFold(4),
                          scoring="neg_root_mean_squared_error").fit(x, d.errors, groups=d.groups)
    assert search.best_params_ == {"b_columns": [2]}              # b is linear in T3's rise
    with pytest.raises(ValueError, match=r"y must be \(n, 5\)"):
        model.fit(x, d.errors[:, :3])


def test_svr_through_the_decoupled_regressor_gets_the_groups():
    d = _synthetic()
    tr = d.subset([1, 2, 3])
    m = thermal.decoupled(tr, {"k": ["T1", "T2"], "b": ["T3"]}, kind="svr")
    direct = thermal.svr_search(tr.temperatures[["T1", "T2"]].to_numpy(),
                                thermal.decouple(tr.offsets_mm(), tr.errors)[0], groups=tr.groups)
    assert m.k_estimator_.search_.best_params_ == direct.best_params_
    assert m.k_estimator_.search_.n_splits_ == 3                  # one fold per experiment
    hp = thermal.svr_hyperparameters(m)
    assert list(hp.target) == ["k", "b"] and (hp.candidates == 40).all()
    with pytest.raises(ValueError, match="unknown model kind 'gp'"):
        thermal.decoupled(tr, {"k": ["T1"], "b": ["T3"]}, kind="gp")


def test_the_calibration_reads_its_targets_from_the_published_metrics():
    """The residuals the reconstruction was calibrated to come from data/papers, not from
    numbers typed into the code: Table 7's RMSE and largest residual of k and b, Table 4's
    largest residual."""
    metrics = xu2022.published_metrics()
    res = xu2022_reconstruction.published_residuals(metrics)
    row = metrics.set_index(["method", "target"])
    assert res["rmse_k"] == float(row.loc[("decoupled_mlr", "slope k"), "rmse"])
    assert res["max_b"] == float(row.loc[("decoupled_mlr", "intercept b"), "max_residual"])
    assert res["max_eq8"] == float(row.loc[("point_by_point_mlr", "thermal positioning error"),
                                           "max_residual"])
    margins = xu2022_reconstruction.CALIBRATION_MARGINS
    assert all(res[f"max_{k}"] > margins[k] for k in ("k", "b"))
