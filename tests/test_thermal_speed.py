"""The SVR search at the size limits (issue 22): what makes it fast must not change its results.

* A fold's fit that a smaller C already determines (no dual variable reached C) is taken from
  it (:class:`thermal.UnboundedFits`): the model is the one libsvm gives for the larger C, to
  its tolerance, and the search chooses what scikit-learn's plain ``GridSearchCV`` over every
  fit chooses (on the reconstruction: the same candidate and bit-identical predictions).
* The bounded grid (:func:`thermal.bounded_grid`) leaves out exactly the C with C x n above
  :data:`thermal.SVR_MAX_CN`, and none at the paper's size.
* Threads give the same numbers as one thread.
* ``progress`` is called with the steps; silent by default.

Times are shown by ``make bench``, never asserted here.
"""

import joblib
import numpy as np
import pandas as pd
import pytest
from sklearn import config_context
from sklearn.model_selection import GridSearchCV, GroupKFold, ParameterGrid

from mtaccuracy import thermal
from mtaccuracy.papers import xu2022

PAPER_INPUTS = {"point": ["T1", "T11", "T12"], "k": ["T1", "T6", "T12"],
                "b": ["T2", "T7", "T11"]}


def _linear(n=24, noise=0.02, seed=0):
    """Nearly linear data in three groups: with epsilon 0.1 no sample needs a large C."""
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(n, 2))
    return x, x @ [1.0, -2.0] + 0.5 + rng.normal(0, noise, n), np.repeat([1, 2, 3], n // 3)


def _plain_search(x, y, groups, grid):
    """The search before issue 22: scikit-learn's GridSearchCV fitting every candidate."""
    search = GridSearchCV(thermal.StandardisedSVR(), grid, cv=GroupKFold(len(set(groups))),
                          scoring="neg_root_mean_squared_error", refit=thermal.canonical_best)
    with config_context(assume_finite=True, skip_parameter_validation=True):
        return search.fit(x, y, groups=groups)


def test_a_larger_c_reuses_an_unbounded_fit_and_it_is_libsvms_model_for_that_c():
    x, y, _ = _linear()
    fits = thermal.UnboundedFits()
    small = thermal.StandardisedSVR(kernel="linear", C=10.0, epsilon=0.1).fit(
        x, y, unbounded_fits=fits)
    assert np.abs(small.svr_.dual_coef_).max() < 10.0             # no dual variable at C
    for c in (100.0, 1e4):
        reused = thermal.StandardisedSVR(kernel="linear", C=c, epsilon=0.1).fit(
            x, y, unbounded_fits=fits)
        fresh = thermal.StandardisedSVR(kernel="linear", C=c, epsilon=0.1).fit(x, y)
        assert reused.svr_.C == c and reused.svr_.support_ is small.svr_.support_
        assert np.abs(fresh.svr_.dual_coef_).max() < 10.0         # libsvm: the same optimum
        assert np.allclose(reused.predict(x), fresh.predict(x), rtol=0,
                           atol=1e-4 * np.ptp(y))                 # to libsvm's tolerance
    assert fits.reused == 2


def test_nothing_is_reused_from_a_bounded_fit_other_data_or_a_thin_tube():
    x, y, _ = _linear(noise=1.0)
    fits = thermal.UnboundedFits()
    tight = thermal.StandardisedSVR(kernel="linear", C=0.01, epsilon=0.1).fit(
        x, y, unbounded_fits=fits)
    assert np.abs(tight.svr_.dual_coef_).max() == 0.01            # samples at the bound C
    thermal.StandardisedSVR(kernel="linear", C=1.0, epsilon=0.1).fit(x, y, unbounded_fits=fits)
    assert fits.reused == 0
    xs, ys, _ = _linear()
    thermal.StandardisedSVR(kernel="linear", C=10.0, epsilon=0.1).fit(xs, ys, unbounded_fits=fits)
    thermal.StandardisedSVR(kernel="linear", C=100.0, epsilon=0.1).fit(xs[1:], ys[1:],
                                                                       unbounded_fits=fits)
    thermal.StandardisedSVR(kernel="rbf", C=100.0, epsilon=0.1).fit(xs, ys, unbounded_fits=fits)
    assert fits.reused == 0                                        # other data, other kernel
    # epsilon below tol / 2: alpha and alpha* may both be non-zero, |dual_coef_| proves nothing
    thin = thermal.StandardisedSVR(kernel="linear", C=10.0, epsilon=1e-7, tol=1e-6)
    thin.fit(xs, ys, unbounded_fits=fits)
    thermal.StandardisedSVR(kernel="linear", C=100.0, epsilon=1e-7, tol=1e-6).fit(
        xs, ys, unbounded_fits=fits)
    assert fits.reused == 0


def test_the_search_with_reuse_chooses_what_fitting_every_candidate_chooses():
    x, y, groups = _linear()
    grid = [{"kernel": ["linear", "rbf"], "C": [0.1, 1.0, 10.0, 100.0], "epsilon": [0.01, 0.1]}]
    ours = thermal.svr_search(x, y, groups=groups, grid=grid)
    plain = _plain_search(x, y, groups, grid)
    assert ours.reused_fits_ > 0
    assert ours.cv_results_["params"] == plain.cv_results_["params"]
    assert ours.best_params_ == plain.best_params_
    a, b = ours.cv_results_["mean_test_score"], plain.cv_results_["mean_test_score"]
    assert np.allclose(a, b, rtol=1e-5, atol=0)                   # reused: libsvm's tolerance
    assert np.array_equal(ours.best_estimator_.predict(x), plain.best_estimator_.predict(x))


def test_on_the_reconstruction_the_search_is_the_one_before_issue_22():
    """The notebook's split: the same candidates, choices and held-out predictions, bit for
    bit, as scikit-learn's plain GridSearchCV over every fit of the full grid."""
    data = thermal.read_measurements(xu2022.DATA)
    tr, te = data.subset([1, 2, 3]), data.subset([4])
    k, b = thermal.decouple(tr.offsets_mm(), tr.errors)
    x_tr = thermal.design(tr, PAPER_INPUTS, "decoupled")
    x_te = thermal.design(te, PAPER_INPUTS, "decoupled")
    for cols, y in ((slice(0, 3), k), (slice(3, 6), b)):
        ours = thermal.svr_search(x_tr[:, cols], y, groups=tr.groups)
        plain = _plain_search(x_tr[:, cols], y, tr.groups, thermal.SVR_GRID)
        assert len(ours.cv_results_["params"]) == 40               # the full grid at 24 rows
        assert ours.best_params_ == plain.best_params_
        assert ours.cv_results_["mean_test_score"][ours.best_index_] == \
            plain.cv_results_["mean_test_score"][plain.best_index_]
        assert np.array_equal(ours.predict(x_te[:, cols]), plain.predict(x_te[:, cols]))
        assert np.allclose(ours.cv_results_["mean_test_score"],
                           plain.cv_results_["mean_test_score"], rtol=1e-6, atol=0)


def test_the_bounded_grid_leaves_out_exactly_the_c_above_the_bound():
    def cs(grid):
        return sorted({p["C"] for p in ParameterGrid(grid)})

    assert thermal.bounded_grid(thermal.SVR_GRID, 24) == thermal.SVR_GRID     # the paper
    assert len(list(ParameterGrid(thermal.bounded_grid(thermal.SVR_GRID, 30)))) == 40
    assert cs(thermal.bounded_grid(thermal.SVR_GRID, 31)) == [0.01, 0.1, 1.0, 10.0, 100.0]
    at_limit = thermal.bounded_grid(thermal.SVR_GRID, 900)
    assert cs(at_limit) == [0.01, 0.1, 1.0, 10.0]
    assert len(list(ParameterGrid(at_limit))) == 8 + 18
    assert thermal.bounded_grid(thermal.SVR_GRID, 10**6, max_cn=np.inf) == thermal.SVR_GRID
    one = {"kernel": ["rbf"], "gamma": [0.1]}                     # default C = 1
    assert thermal.bounded_grid(one, 100, max_cn=100) == [one]
    with pytest.raises(ValueError, match="no SVR candidate has C x n_samples <= 100"):
        thermal.bounded_grid(one, 101, max_cn=100)
    # the search applies it to every grid, and the hyperparameter table counts what was tried
    x, y, groups = _linear(n=36)
    s = thermal.svr_search(x, y, groups=groups, grid=[{"kernel": ["linear"],
                                                       "C": [1.0, 10.0, 1000.0],
                                                       "epsilon": [0.1]}], max_cn=400)
    assert [p["C"] for p in s.cv_results_["params"]] == [1.0, 10.0]


def test_threads_give_the_same_numbers_as_one_thread():
    x, y, groups = _linear(noise=0.3, n=30)
    one = thermal.svr_search(x, y, groups=groups)
    with joblib.parallel_config(n_jobs=2):
        two = thermal.svr_search(x, y, groups=groups)
    assert two.best_params_ == one.best_params_
    assert np.array_equal(two.cv_results_["mean_test_score"], one.cv_results_["mean_test_score"])
    assert two.reused_fits_ == one.reused_fits_


def _small_data(n_exp=3, n_meas=8, seed=1):
    rng = np.random.default_rng(seed)
    t = np.arange(n_meas, dtype=float)
    temps, errors, index = [], [], []
    x = np.linspace(0.0, 200.0, 5)
    for e in range(1, n_exp + 1):
        heat = 1.0 - np.exp(-t[:, None] / rng.uniform(2, 6, size=4))
        temp = 20.0 + heat * rng.uniform(1, 5, size=4) + rng.normal(0, 0.05, (n_meas, 4))
        k = 2.0 * (temp[:, 0] - 20) - (temp[:, 1] - 20)
        b = 3.0 * (temp[:, 2] - temp[0, 2])
        errors.append(k[:, None] * x / 1000 + b[:, None] + rng.normal(0, 0.1, (n_meas, 5)))
        temps.append(temp)
        index += [(e, j + 1, 10.0 * j) for j in range(n_meas)]
    return thermal.ThermalData(pd.DataFrame(index, columns=["experiment", "measurement",
                                                            "time_min"]),
                               pd.DataFrame(np.vstack(temps), columns=["T1", "T2", "T3", "T4"]),
                               np.vstack(errors), x + 100.0)


def test_progress_reports_each_step_and_the_default_is_silent(capsys):
    data = _small_data()
    said = []
    r = thermal.evaluate_split(data, train=[1, 2], test=[3], n_clusters=2, progress=said.append)
    quiet = thermal.evaluate_split(data, train=[1, 2], test=[3], n_clusters=2)
    assert capsys.readouterr().out == ""
    assert r.table.equals(quiet.table)                              # progress changes nothing
    assert said[:5] == [f"sensitive points: {i} of 5 positions" for i in range(1, 6)]
    n = len(r.models["decoupled_svr"].k_estimator_.search_.cv_results_["params"])
    assert said[5:] == ["point_by_point_mlr", "decoupled_mlr",
                        *(f"decoupled_svr, {t}: {i} of {n} candidates"
                          for t in "kb" for i in (2, 4, 6, 8, 10, 16, 22, 28, 34, 40))]

    said.clear()
    thermal.leave_one_experiment_out(data, n_clusters=2, reuse=[quiet], progress=said.append)
    assert said[-1] == "held out 3 (3 of 3): reused"
    assert "held out 1 (1 of 3): decoupled_svr, b: 40 of 40 candidates" in said
    assert "held out 2 (2 of 3): sensitive points: 5 of 5 positions" in said
    assert len(said) == 2 * (5 + 2 + 20) + 1
