"""ISO 230-2:2014 evaluation: hand-worked cases, fault injection, invariants, refusals."""

import warnings
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from mtaccuracy.measure import iso230_2
from mtaccuracy.measure.files import BelowStandardWarning, MeasurementFileError

#: The hand-worked cases are smaller than the standard's test (warned, tested below).
pytestmark = pytest.mark.filterwarnings(
    "ignore::mtaccuracy.measure.files.BelowStandardWarning")
SQ2, SQ25 = np.sqrt(2.0), np.sqrt(2.5)


def frame(axis, readings):
    """readings: {target: (up cycles, down cycles)} -> the file's rows."""
    rows = [(axis, t, j + 1, d, x) for t, (up, down) in readings.items()
            for d, xs in (("+", up), ("-", down)) for j, x in enumerate(xs)]
    return pd.DataFrame(rows, columns=list(iso230_2.COLUMNS))


# 3 targets x 5 cycles, forward unlike backward.  By hand:
#   xbar_up = 3, 6, -3;  xbar_down = 0, 2, -8;  xbar = 1.5, 4, -5.5;  B_i = 3, 4, 5
#   s_up = sqrt(10/4), 0, sqrt(4/4);  s_down = sqrt(8/4), sqrt(4/4), sqrt(8/4)
#   R_i = max(2 s_up + 2 s_down + |B_i|, 4 s_up, 4 s_down)
#       = 2 sqrt2.5 + 2 sqrt2 + 3,  6,  2 + 2 sqrt2 + 5
#   A_up = (3 + 2 sqrt2.5) - (-3 - 2) ; A_down = (2 + 2) - (-8 - 2 sqrt2)
#   A = (3 + 2 sqrt2.5) - (-8 - 2 sqrt2)
CASE_3x5 = frame("X", {0.0: ([1, 2, 3, 4, 5], [0, 0, 0, 2, -2]),
                       100.0: ([6, 6, 6, 6, 6], [1, 3, 1, 3, 2]),
                       200.0: ([-2, -4, -2, -4, -3], [-6, -10, -8, -8, -8])})
HAND_3x5 = {"E": 14.0, "E_up": 9.0, "E_down": 10.0, "M": 9.5, "B": 5.0, "B_mean": 4.0,
            "R": 7 + 2 * SQ2, "R_up": 4 * SQ25, "R_down": 4 * SQ2,
            "A": 11 + 2 * SQ25 + 2 * SQ2, "A_up": 8 + 2 * SQ25, "A_down": 12 + 2 * SQ2}
TARGETS_3x5 = {"mean_up_um": [3, 6, -3], "mean_down_um": [0, 2, -8],
               "mean_um": [1.5, 4, -5.5], "B_i_um": [3, 4, 5],
               "s_up_um": [SQ25, 0, 1], "s_down_um": [SQ2, 1, SQ2],
               "R_i_um": [2 * SQ25 + 2 * SQ2 + 3, 6, 7 + 2 * SQ2]}

# 7 targets x 2 cycles: up (i, i + 2), down (-i - 1, -i + 1) at target i.  By hand:
#   xbar_up = i + 1, xbar_down = -i, xbar = 0.5, B_i = 2 i + 1, s = |a - b| / sqrt2 = sqrt2
#   E_up = E_down = 6, E = 7 - (-6) = 13, M = 0, B = 13, B_mean = 7,
#   R_up = R_down = 4 sqrt2, R = 4 sqrt2 + 13, A_up = A_down = 6 + 4 sqrt2, A = 13 + 4 sqrt2
CASE_7x2 = frame("Y", {100.0 * i: ([i, i + 2], [-i - 1, -i + 1]) for i in range(7)})
HAND_7x2 = {"E": 13.0, "E_up": 6.0, "E_down": 6.0, "M": 0.0, "B": 13.0, "B_mean": 7.0,
            "R": 13 + 4 * SQ2, "R_up": 4 * SQ2, "R_down": 4 * SQ2,
            "A": 13 + 4 * SQ2, "A_up": 6 + 4 * SQ2, "A_down": 6 + 4 * SQ2}


def agrees(values, hand):
    return all(np.isclose(values[q], hand[q], rtol=0, atol=1e-12) for q in hand)


@pytest.mark.parametrize("case, hand", [(CASE_3x5, HAND_3x5), (CASE_7x2, HAND_7x2)])
def test_hand_worked_axis_values(case, hand):
    res = iso230_2.evaluate_iso230_2(case)
    assert agrees(res.values, hand), res.values
    table = res.to_df()
    assert list(table.columns) == ["quantity", "value", "unit"]
    assert table["quantity"].tolist() == list(iso230_2.QUANTITIES)
    assert set(table["unit"]) == {"um"}


def test_hand_worked_per_target_table():
    t = iso230_2.evaluate_iso230_2(CASE_3x5.sample(frac=1, random_state=3)).per_target()
    assert t["target_mm"].tolist() == [0.0, 100.0, 200.0]
    assert t["n_up"].tolist() == [5, 5, 5] and t["n_down"].tolist() == [5, 5, 5]
    for column, want in TARGETS_3x5.items():
        np.testing.assert_allclose(t[column], want, rtol=0, atol=1e-12, err_msg=column)
    np.testing.assert_allclose(t["R_up_um"], 4 * t["s_up_um"], rtol=0, atol=1e-12)


@pytest.mark.parametrize("case, hand", [(CASE_3x5, HAND_3x5), (CASE_7x2, HAND_7x2)])
def test_faulty_evaluators_fail_the_hand_worked_cases(case, hand):
    """Two faults found in an open evaluator: forward and backward data swapped, and a
    target's cycle sum divided by the number of targets.  Evaluating the swapped data is what
    the first computes; scaling every deviation by n/m gives the second's means."""
    data = iso230_2.evaluate_iso230_2  # the evaluator under test
    good = iso230_2._from_frame(case)
    swapped = data(replace(good, up=~good.up)).values
    n = good.cycle.max()
    m = np.unique(good.target_mm).size
    by_targets = data(replace(good, deviation_um=good.deviation_um * n / m)).values
    assert agrees(data(good).values, hand)
    assert not agrees(swapped, hand)
    assert not agrees(by_targets, hand)


def test_invariants_on_random_readings():
    rng = np.random.default_rng(230)
    readings = {t: (rng.normal(2.0, 1.0, 5).tolist(), rng.normal(-1.0, 1.5, 5).tolist())
                for t in np.linspace(0, 900, 11)}
    base = iso230_2.evaluate_iso230_2(frame("Z", readings))
    df = frame("Z", readings)
    shifted = iso230_2.evaluate_iso230_2(df.assign(deviation_um=df.deviation_um + 7.25))
    np.testing.assert_allclose(shifted.mean, base.mean + 7.25, rtol=0, atol=1e-12)
    for q in ("E", "E_up", "E_down", "M", "B", "B_mean", "R", "R_up", "R_down", "A", "A_up",
              "A_down"):
        assert shifted.values[q] == pytest.approx(base.values[q], abs=1e-12), q
    swap = iso230_2.evaluate_iso230_2(df.assign(direction=df.direction.map({"+": "-",
                                                                            "-": "+"})))
    pt, ps = base.per_target(), swap.per_target()
    np.testing.assert_allclose(ps["B_i_um"], -pt["B_i_um"], rtol=0, atol=1e-12)
    np.testing.assert_allclose(ps["R_i_um"], pt["R_i_um"], rtol=0, atol=1e-12)
    for a, b in (("R", "R"), ("R_up", "R_down"), ("E", "E"), ("A", "A"), ("B", "B")):
        assert swap.values[a] == pytest.approx(base.values[b], abs=1e-12)
    assert swap.values["B_mean"] == pytest.approx(-base.values["B_mean"], abs=1e-12)


def test_cycles_may_differ_between_directions():
    # up 3 cycles (0, 3, 6: mean 3, s 3), down 2 (1, 3: mean 2, s sqrt2)
    df = frame("X", {0.0: ([0, 3, 6], [1, 3]), 50.0: ([0, 3, 6], [1, 3])})
    t = iso230_2.evaluate_iso230_2(df).per_target()
    assert t["n_up"].tolist() == [3, 3] and t["n_down"].tolist() == [2, 2]
    np.testing.assert_allclose(t[["mean_up_um", "mean_down_um", "s_up_um", "s_down_um"]]
                               .to_numpy()[0], [3, 2, 3, SQ2], rtol=0, atol=1e-12)


def test_a_test_smaller_than_the_standards_is_warned():
    with pytest.warns(BelowStandardWarning, match="3 targets over 200 mm, 5 to 5 cycles"):
        iso230_2.evaluate_iso230_2(CASE_3x5)
    with pytest.warns(BelowStandardWarning, match="asks for 5 targets here"):
        iso230_2.evaluate_iso230_2(CASE_7x2)                 # 7 targets, 2 cycles
    many = frame("X", {100.0 * i: ([0, 1, 2, 3, 4], [1, 2, 3, 4, 5]) for i in range(10)})
    with pytest.warns(BelowStandardWarning, match="asks for 5 targets here"):
        iso230_2.evaluate_iso230_2(many.query("target_mm < 400"))   # 4 over 300 mm
    with pytest.warns(BelowStandardWarning, match="asks for 8 targets here"):
        iso230_2.evaluate_iso230_2(frame("X", {200.0 * i: ([0, 1, 2, 3, 4], [1, 2, 3, 4, 5])
                                               for i in range(9)})     # 7 over 1600 mm
                                    .query("target_mm not in [600.0, 800.0]"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        iso230_2.evaluate_iso230_2(many)                    # 10 targets over 900 mm, 5 cycles


def _write(tmp_path, lines):
    p = tmp_path / "laser.csv"
    p.write_text("\n".join(lines) + "\n")
    return p


def _good_lines():
    return ["axis,target_mm,cycle,direction,deviation_um"] + [
        f"X,{t},{j},{d},{(t + j) % 7 - 3}" for t in (0, 100, 200) for j in (1, 2, 3)
        for d in "+-"]


def test_reader_reads_a_good_file(tmp_path):
    data = iso230_2.read_iso230_2(_write(tmp_path, _good_lines()))
    assert data.axis == "X" and data.up.sum() == 9 and data.cycle.max() == 3


@pytest.mark.parametrize("edit, line, words", [
    (lambda ls: [ls[0].replace("cycle", "run")] + ls[1:], 1, "missing column(s) ['cycle']"),
    (lambda ls: ls[:3] + [ls[3].replace(",+,", ",up,")] + ls[4:], 4, "here '+'?"),
    (lambda ls: ls[:5] + [ls[5].rsplit(",", 1)[0] + ",1,5"] + ls[6:], 6, "fields"),
    (lambda ls: ls[:2] + [ls[2].rsplit(",", 1)[0] + ",n/a"] + ls[3:], 3, "not a number"),
    (lambda ls: ls[:4] + [ls[4].replace(",2,", ",1.5,")] + ls[5:], 5, "number the cycles"),
    (lambda ls: ls[:6] + [ls[5]] + ls[7:], 7, "again (first on line 6)"),
    (lambda ls: [ln for ln in ls if not (ln.startswith("X,100,") and ",-," in ln)], 8,
     "0 reading(s) in direction '-'"),
    (lambda ls: [ln for ln in ls if not ln.startswith(("X,200,2,+", "X,200,3,+"))], 14,
     "1 reading(s) in direction '+'"),
    (lambda ls: ls[:9] + [ls[9].replace("X,", "Y,", 1)] + ls[10:], 10, "one axis per file")])
def test_reader_refuses_with_line_and_fix(tmp_path, edit, line, words):
    with pytest.raises(MeasurementFileError) as info:
        iso230_2.read_iso230_2(_write(tmp_path, edit(_good_lines())))
    assert info.value.line == line, str(info.value)
    assert words in str(info.value) and "laser.csv" in str(info.value)


def test_reader_lists_every_problem_at_once(tmp_path):
    ls = _good_lines()
    ls[3] = ls[3].replace(",+,", ",?,")
    ls[12] = ls[12].rsplit(",", 1)[0] + ",abc"
    with pytest.raises(MeasurementFileError) as info:
        iso230_2.read_iso230_2(_write(tmp_path, ls))
    assert [p[0] for p in info.value.problems] == [4, 13]


@pytest.mark.parametrize("content, words", [(b"", "empty"), (b"\xff\xfe,", "UTF-8"),
                                            (b"axis,target_mm,cycle,direction,deviation_um\n",
                                             "no data rows")])
def test_reader_refuses_empty_and_binary_files(tmp_path, content, words):
    p = tmp_path / "laser.csv"
    p.write_bytes(content)
    with pytest.raises(MeasurementFileError, match=words):
        iso230_2.read_iso230_2(p)
    with pytest.raises(MeasurementFileError, match="not found"):
        iso230_2.read_iso230_2(tmp_path / "missing.csv")


def _examples():
    import importlib.util
    from pathlib import Path
    path = Path(__file__).resolve().parents[1] / "data" / "measure" / "make_examples.py"
    spec = importlib.util.spec_from_file_location("make_examples", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module, path.parent


def test_the_committed_example_is_the_generators_and_recovers_its_truth():
    gen, folder = _examples()
    assert (folder / "positioning_X.csv").read_text() == gen.texts()["positioning_X.csv"]
    res = iso230_2.evaluate_iso230_2(folder / "positioning_X.csv")
    noise = gen.POSITIONING["noise_um"]
    # B_i = mean_up - mean_down: the drift cancels, the noise leaves var 2 noise^2 / 5 each
    se = np.sqrt(2 * noise ** 2 / gen.CYCLES / gen.TARGETS_MM.size)
    assert abs(res.values["B_mean"] + gen.POSITIONING["backlash_um"]) < 3 * se
    t = res.targets_mm
    for k, up in ((0, True), (1, False)):
        truth = np.mean([gen.positioning_truth(t, up, j) for j in range(1, gen.CYCLES + 1)],
                        axis=0)
        assert np.abs(res.mean[:, k] - truth).max() < 4 * noise / np.sqrt(gen.CYCLES)
