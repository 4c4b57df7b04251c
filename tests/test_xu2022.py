"""Notebook 04's paper module (Xu et al. 2022): regenerating the reconstruction as a command of
its own, the figures' captions, and an audit check: can one partition of the sensors produce the
printed per-position sensitive points (Table 3) under the paper's rule of Section 1.1?"""

import itertools
import json
import shutil
import string
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from mtaccuracy import thermal
from mtaccuracy.papers import parameters, printed, xu2022, xu2022_reconstruction
from mtaccuracy.papers.figure import Caption

SENSORS = [f"T{i}" for i in range(1, 13)]


def _table3():
    t3 = printed.published("xu2022_table3_sensitive_points", ["position_mm", "sensors"])
    return t3.position_mm.astype(float).tolist(), [s.split() for s in t3.sensors]


def _fits_by_hand(rows, labels):
    """Independent formulation: a row fits when the set of its sensors' labels is every label."""
    n = len(rows[0])
    return [sorted({labels[s] for s in r}) == list(range(n)) and len(r) == n for r in rows]


def test_partition_fits_agrees_with_a_plain_enumeration():
    rng = np.random.default_rng(7)
    sensors = ["a", "b", "c", "d", "e", "f"]
    rows = [list(rng.choice(sensors, 3, replace=False)) for _ in range(5)]
    fits = xu2022.partition_fits(rows, sensors, 3)
    assert fits.shape == (3 ** 6, 5)
    for a, labels in enumerate(itertools.product(range(3), repeat=6)):
        # assignment a gives sensor s the label (a // 3**s) % 3: itertools varies the last fastest
        by_sensor = dict(zip(sensors, labels[::-1], strict=True))
        assert fits[a].tolist() == _fits_by_hand(rows, by_sensor)


def test_rows_made_from_one_partition_are_all_produced():
    clusters = [["T1", "T2", "T3", "T4", "T5", "T8", "T9", "T10"], ["T6", "T11"], ["T7", "T12"]]
    rows = [list(t) for t in itertools.product(*clusters)][::7]
    out = xu2022.table3_consistency(rows, SENSORS, 3)
    assert out["best"] == len(rows) and out["conflict"] == []
    assert out["best_assignments"] == 6 * out["best_partitions"] >= 6
    assert all(xu2022.rows_fitted_by(rows, clusters))
    assert not any(xu2022.rows_fitted_by(rows, [clusters[0] + clusters[1], clusters[2], []]))


def test_no_partition_produces_the_printed_table3():
    """Hand check: 285 mm {T1 T11 T12} puts T1, T11, T12 in three clusters; 225 mm {T1 T7 T11}
    then puts T7 in T12's; 245 mm {T4 T7 T12} needs T7 and T12 apart. Dropping 245 mm leaves
    T1 T2 T4 | T6 T11 | T7 T12 forced and T3 T5 T8 T9 T10 free: 3**5 partitions."""
    positions, rows = _table3()
    out = xu2022.table3_consistency(rows, SENSORS, 3)
    assert out["assignments"] == 3 ** 12
    assert out["best"] == len(rows) - 1 == 13
    assert out["best_partitions"] == 3 ** 5 and out["best_assignments"] == 6 * 3 ** 5
    missed = [p for p, m in zip(positions, out["missed"], strict=True) if m]
    assert missed == [245.0] and out["missed"][positions.index(245.0)] == out["best_assignments"]
    assert [positions[i] for i in out["conflict"]] == [225.0, 245.0, 285.0]
    assert out["best_partition"][0][:3] == ["T1", "T2", "T4"]
    assert any({"T6", "T11"} <= set(g) for g in out["best_partition"][1:])


def test_table6_partition_for_b_is_one_of_the_best():
    _, rows = _table3()
    b = [["T1", "T2", "T3", "T4", "T5", "T8", "T9", "T10"], ["T6", "T11"], ["T7", "T12"]]
    fitted = xu2022.rows_fitted_by(rows, b)
    assert sum(fitted) == 13 and fitted.index(False) == 3


@pytest.mark.parametrize("rows, match", [([["T1", "T2"]], "needs 3 different"),
                                         ([["T1", "T1", "T2"]], "needs 3 different"),
                                         ([["T1", "T2", "T99"]], "unknown")])
def test_bad_rows_are_refused(rows, match):
    with pytest.raises(ValueError, match=match):
        xu2022.partition_fits(rows, SENSORS, 3)


def test_too_many_assignments_are_refused():
    with pytest.raises(ValueError, match="assignments"):
        xu2022.partition_fits([["a", "b", "c"]], [f"s{i}" for i in range(20)], 3)


# ------------------------------------------------ regenerating data/thermal: a command of its own

DATA_FILES = ("temperatures.csv", "errors.csv", "experiments.csv", "provenance.json")


def _same_as_committed(folder: Path) -> bool:
    return all((folder / n).read_bytes() == (xu2022.DATA / n).read_bytes() for n in DATA_FILES)


@pytest.fixture
def committed_copy(tmp_path, monkeypatch):
    """A copy of data/thermal that :mod:`xu2022` takes for the committed folder.

    Patched where :func:`xu2022.regenerate` and :func:`xu2022.reconstruction_seed` read it
    (:mod:`xu2022.data`); ``xu2022.DATA`` stays the committed folder, which the tests compare
    the copy with."""
    copy = tmp_path / "data" / "thermal"
    shutil.copytree(xu2022.DATA, copy)
    monkeypatch.setattr(xu2022.data, "DATA", copy)
    return copy


def test_regenerate_writes_the_committed_files_byte_for_byte(tmp_path):
    fresh = tmp_path / "fresh"
    changed = xu2022.regenerate(fresh)
    assert sorted(p.name for p in changed) == ["errors.csv", "experiments.csv",
                                               "temperatures.csv"]
    assert _same_as_committed(fresh)                       # provenance.json included
    side = json.loads((fresh / "provenance.json").read_text(encoding="utf-8"))
    assert side["run"] == {"generator": "mtaccuracy.papers.xu2022_reconstruction",
                           "seed": xu2022_reconstruction.DEFAULT_SEED}
    assert xu2022.regenerate(fresh) == []                  # nothing changes: nothing is written


def test_regenerate_with_the_committed_seed_leaves_the_committed_folder_alone(committed_copy):
    before = {n: (committed_copy / n).stat().st_mtime_ns for n in DATA_FILES}
    assert xu2022.regenerate(committed_copy) == []
    assert {n: (committed_copy / n).stat().st_mtime_ns for n in DATA_FILES} == before


def test_regenerate_refuses_to_overwrite_an_edited_file_and_writes_nothing(committed_copy,
                                                                           capsys):
    errors = committed_copy / "errors.csv"
    edited = errors.read_text().replace("1,1,205,0.051", "1,1,205,0.052", 1)
    errors.write_text(edited)
    side = (committed_copy / "provenance.json").read_bytes()
    with pytest.raises(RuntimeError, match=r"errors\.csv: edited since the generator wrote it"):
        xu2022.regenerate(committed_copy)
    with pytest.raises(RuntimeError, match="nothing was written"):
        xu2022.regenerate(committed_copy, seed=7)
    assert errors.read_text() == edited
    assert (committed_copy / "provenance.json").read_bytes() == side
    assert xu2022.main(["regenerate", str(committed_copy), "--seed", "7"]) == 2
    assert "edited since the generator wrote it" in capsys.readouterr().err
    # elsewhere a file the generator would change is never overwritten either
    other = committed_copy.parent / "other"
    other.mkdir()
    (other / "errors.csv").write_text("mine\n")
    with pytest.raises(RuntimeError, match="edited since"):
        xu2022.regenerate(other)
    assert (other / "errors.csv").read_text() == "mine\n"


def test_regenerate_with_another_seed_and_back(committed_copy, capsys):
    changed = xu2022.regenerate(committed_copy, seed=7)
    assert {p.name for p in changed} == {"errors.csv", "temperatures.csv"}  # feeds are Table 1's
    assert xu2022.reconstruction_seed(committed_copy) == 7                    # as recorded
    assert thermal.read_measurements(committed_copy).errors == pytest.approx(
        xu2022.reconstruct(7).errors, abs=1e-9)
    assert xu2022.main(["regenerate", str(committed_copy)]) == 0
    assert "2 file(s) rewritten" in capsys.readouterr().out
    assert _same_as_committed(committed_copy)
    assert xu2022.reconstruction_seed(committed_copy) == xu2022_reconstruction.DEFAULT_SEED


def test_the_reconstruction_in_memory_is_the_committed_one():
    read = thermal.read_measurements(xu2022.DATA)
    made = xu2022.reconstruct()
    assert made.sensors == read.sensors and made.feeds == read.feeds
    assert np.array_equal(made.errors, read.errors)
    assert np.allclose(made.temperatures.to_numpy(), read.temperatures.to_numpy(), rtol=0,
                       atol=1e-12)


def test_the_data_origin_says_what_a_run_does_with_its_data():
    assert "read only: compared with the paper" in xu2022.data_origin("data/thermal", 2022, 2022)
    other = xu2022.data_origin("data/thermal", 2022, 7)
    assert "seed 7, built in memory (nothing written" in other
    assert "regenerate FOLDER --seed 7" in other
    mine = xu2022.data_origin("/my/lab", None, 7)
    assert mine.startswith("/my/lab: your measurements, read only; not the paper's reconstruction")


def test_the_declaration_refuses_a_split_that_contradicts_itself():
    with pytest.raises(parameters.ParameterError, match="at least 2 experiments"):
        parameters.check(xu2022.Parameters, {"train_experiments": [1]})
    with pytest.raises(parameters.ParameterError, match="also a training experiment"):
        parameters.check(xu2022.Parameters, {"train_experiments": [1, 2], "test_experiment": 2})
    assert parameters.check(xu2022.Parameters, {"train_experiments": [1, 2],
                                                "test_experiment": 4}).test_experiment == 4


# ------------------------------------------------ the figures' captions


def _stated_numbers(caption) -> list[str]:
    """The numbers a caption's text states itself (not in a field), apart from the paper's
    numbering of its figures, tables, equations and sections (1 to 17)."""
    text = "".join(literal for literal, _, _, _ in string.Formatter().parse(caption.text))
    words = [w.strip(",.;:()") for w in text.split()]
    return [w for w in words if any(ch.isdigit() for ch in w)
            and w not in {str(i) for i in range(1, 18)}]


def test_captions_follow_the_book_order_and_state_no_number_the_run_did_not_compute():
    assert list(xu2022.FIGURES)[:3] == ["fig03_ambient_temperature", "fig05_error_vs_position",
                                        "fig06_error_vs_time"]
    assert list(xu2022.FIGURES)[-2:] == ["beyond_leave_one_experiment_out",
                                         "beyond_selection_vs_baselines"]
    assert xu2022.FIGURES["fig11_point_by_point_prediction"] is xu2022.FIG11
    assert xu2022.FIGURES["fig09_error_other_experiments"].rows == (
        "Table 5", "Eq. 8", "Section 3.2: largest error*")
    for c in xu2022.FIGURES.values():
        assert "{data}" in c.text and not _stated_numbers(c), (c.name, _stated_numbers(c))
    assert _stated_numbers(Caption("x", "Fig. 5", "about −6.0 µm at {at} mm (Table 4: "
                                          "1.6 µm, Fig. 11)")) == ["−6.0", "1.6"]


def test_the_data_fields_of_the_reconstruction():
    data = thermal.read_measurements(xu2022.DATA)
    f = xu2022.data_fields(data, train=[1, 2, 3], test=4, air="T10")
    assert f["measurements"] == "eight measurements" and f["times"] == "0 to 161 min"
    assert f["experiments"] == "four warm-up experiments"
    assert f["feeds"] == ", feeds 2000 to 8000 mm/min" and f["first_feed"] == " (2000 mm/min)"
    assert f["positions"] == "14 target positions 185 to 445 mm"
    assert f["first_extreme"] == "−6.0 µm at 445 mm"
    assert f["drift"] == "3.2 to 4.1 µm" and f["zeroed"] == "0.8"
    assert f["others"] == "2 to 4" and f["others_feeds"] == " (4000, 6000, 8000 mm/min)"
    assert f["farthest"] == ("Experiment 2 drifts furthest (−13.9 µm at 445 mm); experiment 4, "
                             "the one predicted in Figs. 11 to 17, reaches −7.6 µm.")
    assert f["warmest"] == "T7, T6 and T12" and f["steadiest"] == "T9, T8 and T2"
    assert f["train"] == "1 to 3" and f["test"] == "4"
    fig5 = xu2022.caption("fig05_error_vs_position", True, **f)
    assert "experiment 1 (2000 mm/min)" in fig5.text and "concerns experiment 4" in fig5.text
    assert "Reconstructed data" in fig5.text and fig5.rows == xu2022.FIGURES[fig5.name].rows
    mine = xu2022.caption("fig05_error_vs_position", False, **f)
    assert "Reconstructed" not in mine.text and "not the paper's reconstruction" in mine.text


def test_the_model_figure_fields_name_the_paper_only_with_its_tables():
    t = pd.DataFrame([{"method": m, "target": tg, "rmse": r, "max_residual": 2 * r, "mae": r,
                       "unit": "um"}
                      for m, r in zip(xu2022.METHODS, (2.9, 0.61, 0.62), strict=True)
                      for tg in (xu2022.ERROR, "slope k", "intercept b")])

    class Search:
        def __init__(self, kernel):
            self.best_params_ = {"svr__kernel": kernel, "svr__C": 1.0, "svr__epsilon": 0.1}
            self.cv_results_ = {"mean_test_score": np.array([-1.0]), "params": [{}]}
            self.best_index_ = 0

    class Svr:
        k_estimator_ = type("K", (), {"search_": Search("linear"), "tie_rtol": 1e-3})()
        b_estimator_ = type("B", (), {"search_": Search("rbf"), "tie_rtol": 1e-3})()

    paper = xu2022.published_inputs()
    measured = np.array([[1.0, 2.0], [3.0, -1.0]])
    split = type("Split", (), {"table": t, "models": {"decoupled_svr": Svr()}, "inputs": paper,
                               "measured": measured,
                               "predictions": {m: measured * 0.5 for m in xu2022.METHODS}})()
    f = xu2022.model_fields(split, paper, xu2022.published_metrics())
    assert f["points"] == "the paper's sensitive points T1, T11 and T12"
    assert f["kernels"] == "a linear kernel for k and an RBF kernel for b"
    assert f["pbp_rmse"] == "2.90" and f["pbp_paper"] == " (Table 4: 1.6 µm)"
    assert f["mlr_kb_paper"] == " (Table 7: 3.6 µm/m and 0.8 µm)"
    assert f["mlr_lo"] == "−0.5" and f["mlr_hi"] == "1.5"
    mine = xu2022.model_fields(split, {**paper, "point": ["T2", "T3", "T4"]})
    assert mine["pbp_paper"] == "" and mine["points"].endswith("selected on the training "
                                                               "experiments")


def test_the_leave_one_out_and_baseline_fields():
    idx = pd.MultiIndex.from_product([["published", "selected"], [1, 2]],
                                     names=["inputs", "held_out"])
    wide = pd.DataFrame({"decoupled MLR beats point-by-point": [True, True, False, True],
                         "decoupled SVR beats point-by-point": [True, True, False, False]},
                        index=idx)
    f = xu2022.loeo_fields(wide, ["published", "selected"])
    assert f["panels"].endswith("on each training set (right)")
    assert f["wins"] == ("With the paper's points, decoupled MLR beats point-by-point in 2 of 2 "
                         "splits and decoupled SVR in 2; with re-selected points, decoupled MLR "
                         "beats point-by-point in 1 of 2 splits and decoupled SVR in 0.")
    assert xu2022.loeo_fields(wide, ["selected"])["panels"].startswith("with points re-selected")
    pooled = pd.DataFrame({"rmse": [5.0, 1.9, 3.0, 4.97, 2.87]},
                          index=["uncompensated", "ridge_all_sensors",
                                 "point_by_point_mlr (selected)", "decoupled_mlr (selected)",
                                 "decoupled_svr (selected)"])
    g = xu2022.pooled_fields(pooled, 9)
    assert g == {"all_sensors": "nine sensors", "with_points": "with re-selected points",
                 "pooled": "uncompensated 5.00; ridge 1.90; with re-selected points: "
                           "point-by-point 3.00, decoupled MLR 4.97, decoupled SVR 2.87"}
