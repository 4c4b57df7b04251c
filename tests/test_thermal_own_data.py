"""A reader's own thermal measurements (issue 22): what is the paper's reconstruction is decided by
content, the split's defaults, the baselines and the one pooled RMSE.

The data come from the tests' own physical model (``tests/thermal_lab.py``: a ball screw heated by
its nut, conduction along the screw, the error its integrated expansion), not from the
project's generator.
"""

import shutil

import numpy as np
import pandas as pd
import pytest
import thermal_lab
from sklearn.linear_model import Ridge
from sklearn.model_selection import GroupKFold, cross_val_score

from mtaccuracy import thermal
from mtaccuracy.papers import parameters, xu2022, xu2022_reconstruction

COMMITTED = xu2022.DATA
LAB = dict(experiments=(11, 12, 13, 14, 15), n_measurements=19,
           positions_mm=np.arange(25) * 40.0)


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    folder = tmp_path_factory.mktemp("lab")
    sim = thermal_lab.write(folder, **LAB)
    return folder, sim, thermal.read_measurements(folder)


# ------------------------------------------------ the reconstruction, decided by content


def test_a_byte_identical_copy_of_the_reconstruction_anywhere_is_the_reconstruction(tmp_path):
    assert xu2022.reconstruction_seed(COMMITTED) == xu2022_reconstruction.DEFAULT_SEED
    copy = tmp_path / "somewhere" / "else"
    shutil.copytree(COMMITTED, copy)
    (copy / "provenance.json").unlink()                 # what the copy says of itself is not asked
    (copy / "README.md").unlink()                       # nor what else the folder holds
    assert xu2022.reconstruction_seed(copy) == xu2022_reconstruction.DEFAULT_SEED
    (copy / "experiments.csv").unlink()                 # optional file: its absence changes nothing
    assert xu2022.reconstruction_seed(copy) == xu2022_reconstruction.DEFAULT_SEED
    (copy / "errors.csv").unlink()                      # a required one: not the reconstruction
    assert xu2022.reconstruction_seed(copy) is None


def test_an_edited_copy_and_a_readers_data_are_not_the_reconstruction(tmp_path, lab):
    copy = tmp_path / "edited"
    shutil.copytree(COMMITTED, copy)
    text = (copy / "errors.csv").read_text()
    (copy / "errors.csv").write_text(text.replace("1,1,205,0.051", "1,1,205,0.052", 1))
    thermal.read_measurements(copy)                     # a valid dataset, only one reading changed
    assert xu2022.reconstruction_seed(copy) is None
    folder, _, _ = lab
    assert xu2022.reconstruction_seed(folder) is None
    # a folder named data/thermal is not enough either: the path never decides
    fake = tmp_path / "data" / "thermal"
    shutil.copytree(folder, fake)
    assert xu2022.reconstruction_seed(fake) is None


def test_the_same_numbers_in_other_bytes_are_not_the_reconstruction(tmp_path):
    """Content means the files' bytes: the same measurements written otherwise (another seed
    would differ anyway) are a reader's data, compared with nothing."""
    thermal.write_measurements(xu2022.reconstruct(), tmp_path, temperature_decimals=3)
    assert np.allclose(thermal.read_measurements(tmp_path).errors,
                       thermal.read_measurements(COMMITTED).errors)
    assert xu2022.reconstruction_seed(tmp_path) is None
    other = tmp_path / "seed7"
    thermal.write_measurements(xu2022.reconstruct(7), other)
    assert xu2022.reconstruction_seed(other) is None


# ------------------------------------------------ the split's defaults


def test_split_defaults_predict_the_last_experiment_from_all_others(lab):
    _, _, data = lab
    assert xu2022.resolve_split("04", data, train=[], test=0) == ([11, 12, 13, 14], 15)
    assert xu2022.resolve_split("04", data, train=[], test=12) == ([11, 13, 14, 15], 12)
    assert xu2022.resolve_split("04", data, train=[13, 11], test=15) == ([13, 11], 15)
    recon = thermal.read_measurements(COMMITTED)
    assert xu2022.resolve_split("04", recon, train=[], test=0) == ([1, 2, 3], 4)   # the paper's
    with pytest.raises(parameters.ParameterError, match=r"experiment\(s\) \[4\] are not in the "
                                                        r"data; they have \[11, 12, 13, 14, 15\]"):
        xu2022.resolve_split("04", data, train=[], test=4)
    with pytest.raises(parameters.ParameterError, match="also a training experiment"):
        xu2022.resolve_split("04", data, train=[11, 15], test=15)
    with pytest.raises(parameters.ParameterError, match="at least 2"):
        xu2022.resolve_split("04", data, train=[11], test=15)
    assert [xu2022.resolve_inputs("auto", p) for p in (True, False)] == ["published", "selected"]
    assert xu2022.resolve_inputs("published", False) == "published"


def test_a_list_parameter_with_an_empty_default_refuses_text_elements():
    with pytest.raises(parameters.ParameterError, match="train_experiments.*must be instances of "
                                                        "<class 'int'>"):
        parameters.check(xu2022.Parameters, {"train_experiments": [1, "x"]})
    with pytest.raises(parameters.ParameterError, match=r"0 is outside \[1, inf\]"):
        parameters.check(xu2022.Parameters, {"train_experiments": [0, 12]})
    assert parameters.check(xu2022.Parameters,
                            {"train_experiments": [11, 12]}).train_experiments == [11, 12]


# ------------------------------------------------ one RMSE, pooled


def test_pooled_metrics_equal_the_metrics_of_all_residuals_at_once():
    rng = np.random.default_rng(3)
    parts = [rng.normal(size=(n, 7)) * s for n, s in ((3, 1.0), (11, 4.0), (5, 0.2))]
    rows = pd.DataFrame([{"model": "m", **thermal.metrics(r), "n_residuals": r.size}
                         for r in parts])
    pooled = thermal.pool_metrics(rows, ["model"]).iloc[0]
    want = thermal.metrics(np.concatenate([r.ravel() for r in parts]))
    for k, v in want.items():
        assert pooled[k] == pytest.approx(v, rel=1e-12)
    # not the mean of the per-part RMSEs, which weighs a short experiment like a long one
    assert pooled.rmse != pytest.approx(rows.rmse.mean(), rel=1e-3)


def test_the_pooled_rmse_scorer_is_not_the_per_position_average(lab):
    _, _, data = lab
    y = data.errors
    pred = np.zeros_like(y)
    pred[:, 0] = y[:, 0]                                     # perfect at one position only
    pooled = thermal.metrics(y - pred)["rmse"]
    per_position = np.mean(np.sqrt(np.mean((y - pred) ** 2, axis=0)))
    assert pooled != pytest.approx(per_position, rel=1e-3)
    model = thermal.DecoupledRegressor(data.offsets_mm(), [0, 1], [2])
    x = thermal.design(data, {"k": data.sensors[:2], "b": data.sensors[2:3]}, "decoupled")
    scores = cross_val_score(model, x, y, groups=data.groups, cv=GroupKFold(5),
                             scoring=thermal.POOLED_RMSE_SCORER)
    for (tr, te), s in zip(GroupKFold(5).split(x, y, data.groups), scores, strict=True):
        fit = thermal.DecoupledRegressor(data.offsets_mm(), [0, 1], [2]).fit(x[tr], y[tr])
        assert -s == pytest.approx(thermal.metrics(y[te] - fit.predict(x[te]))["rmse"], rel=1e-12)


# ------------------------------------------------ the ridge baseline


def test_grouped_ridge_chooses_the_penalty_by_held_out_experiments_and_breaks_ties_up():
    rng = np.random.default_rng(0)
    groups = np.repeat(np.arange(4), 10)
    x = rng.normal(size=(40, 5))
    y = x @ np.array([1.0, -2.0, 0.0, 0.5, 0.0]) + 0.01 * rng.normal(size=40)
    m = thermal.GroupedRidge().fit(x, y, groups=groups)
    assert m.alpha_ <= 1.0                                   # a clean linear law: little shrinkage
    assert np.allclose(m.predict(x), y, atol=0.1)
    # the chosen penalty is the one a hand-written grouped search finds
    best = {}
    for a in thermal.RIDGE_ALPHAS:
        sq = []
        for tr, te in GroupKFold(4).split(x, y, groups):
            mu, sd = x[tr].mean(0), x[tr].std(0)
            r = Ridge(alpha=a).fit((x[tr] - mu) / sd, y[tr])
            sq.append(np.sqrt(np.mean((y[te] - r.predict((x[te] - mu) / sd)) ** 2)))
        best[a] = np.mean(sq)
    lo = min(best.values())
    assert m.alpha_ == max(a for a, v in best.items() if v <= lo * (1 + thermal.RIDGE_TIE_RTOL))
    # a constant target: every penalty gives the same model, the largest wins the tie
    flat = thermal.GroupedRidge().fit(x, np.full(40, 3.0), groups=groups)
    assert flat.alpha_ == max(thermal.RIDGE_ALPHAS)
    with pytest.raises(ValueError, match="at least 2 training experiments"):
        thermal.GroupedRidge().fit(x, y, groups=np.zeros(40))
