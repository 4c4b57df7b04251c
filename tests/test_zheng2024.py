"""Notebook 01 (Zheng et al. 2024) after the second audit (issue 24): the two readings of
Eq. 24, Section 3.2's group shares, the sampling scatter and Table 3's printed arithmetic."""

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pandas as pd
import pytest

from mtaccuracy.machines import build
from mtaccuracy.papers import printed, zheng2024
from mtaccuracy.sensitivity import linear_indices

COMP = ["Px", "Py", "Pz", "Vx", "Vy", "Vz"]


def _series(r):
    return pd.DataFrame({"n": [100, 200, 500, 1000][:len(r)], "R_percent": r})


@pytest.mark.parametrize("r, larger, smaller", [
    ([np.nan, 20.0, 2.0, 1.0], 500, 200),      # one big step, then small ones
    ([np.nan, 2.0, 5.0, 1.0], 1000, 500),      # a late excursion above 3 %
    ([np.nan, 1.0, 1.0, 1.0], 200, 100),       # converged from the start
    ([np.nan, 1.0, 1.0, 9.0], np.nan, np.nan),  # the last step fails: never converged
])
def test_converged_at_gives_r_to_either_size(r, larger, smaller):
    g = _series(r)
    for assign, want in (("larger", larger), ("smaller", smaller)):
        got = zheng2024.converged_at(g, assign=assign)
        assert (np.isnan(got) and np.isnan(want)) or got == want, (assign, got, want)


def test_converged_at_refuses_an_unknown_assignment():
    with pytest.raises(ValueError, match="assign"):
        zheng2024.converged_at(_series([np.nan, 1.0]), assign="middle")


def test_group_shares_count_the_groups_of_table1():
    machine = build("ac_double_turntable")
    cat = machine.catalogue
    d = zheng2024.group_shares(np.full((6, 41), 1 / 41), cat, COMP)
    n_trans = sum(e.translational for e in cat)
    n_rot = sum(e.axis in ("A", "C") for e in cat)
    assert np.allclose(d.translational, n_trans / 41) and np.allclose(d.angular, 1 - n_trans / 41)
    assert np.allclose(d.rotary_axes, n_rot / 41) and np.allclose(d.linear_axes, 1 - n_rot / 41)
    assert np.allclose(d.pige_mean, 1 / 41) and np.allclose(d.pdge_mean, 1 / 41)
    # Table 1: 30 error motions (PDGEs), 11 PIGEs (8 location, 3 squareness); 20 rotary-axis errors
    assert sum(e.kind == "error motion" for e in cat) == 30 and n_rot == 20
    one = np.zeros((6, 41))
    one[:, [e.symbol for e in cat].index("b_CA")] = 1.0      # an angular PIGE of the C axis
    d1 = zheng2024.group_shares(one, cat, COMP)
    assert (d1.angular == 1).all() and (d1.rotary_axes == 1).all()
    assert np.allclose(d1.pige_mean, 1 / 11) and (d1.pdge_mean == 0).all()


def test_diagonal_test_points_span_the_travel_box_through_its_centre():
    tp = zheng2024.diagonal_test_points(5, "zero")
    assert len(tp["x"]) == 20 and np.allclose(tp["x"][tp["fraction"] == 0.5], 0.0)
    assert tp["x"].min() == -400 and tp["y"].max() == 425 and np.all(tp["A"] == 0)
    # "sweep": A and C move with the same fraction of their travel as x, y, z
    sweep = zheng2024.diagonal_test_points(3, "sweep")
    assert np.allclose(sweep["A"], np.deg2rad(-130 + 260 * sweep["fraction"]))
    assert np.allclose(sweep["C"], 2 * np.pi * sweep["fraction"])
    with pytest.raises(ValueError, match="allowed: sweep, zero"):
        zheng2024.diagonal_test_points(5, "random")
    with pytest.raises(ValueError, match=r"n_per_diagonal must be an integer >= 2, got 1"):
        zheng2024.diagonal_test_points(1)


def test_only_angular_errors_move_the_tool_axis():
    """Section 3.2's attitude statement holds at every pose of a rigid-body model."""
    machine = build("ac_double_turntable")
    rng = np.random.default_rng(3)
    poses = {"x": rng.uniform(-400, 400, 4), "y": rng.uniform(-425, 425, 4),
             "z": rng.uniform(-275, 275, 4), "A": rng.uniform(-2.2, 2.2, 4),
             "C": rng.uniform(0, 6.2, 4)}
    sd = np.array([5e-3 if e.translational else 1.6e-5 for e in machine.catalogue])
    s = linear_indices(machine.jacobian(poses), sd=sd)
    for p in s.swapaxes(-1, -2):                       # components x errors, as Table 2
        d = zheng2024.group_shares(p, machine.catalogue, COMP)
        assert (d.translational[3:] < 1e-12).all()
        assert (d.translational[:3] > 0.05).all()      # but they do move the tool tip


def test_relative_scatter():
    exact = np.array([[0.1, 0.2, 0.01], [0.06, 0.3, 0.04]])
    assert zheng2024.relative_scatter(exact, exact) == 0
    est = exact * np.array([[1.1, 0.9, 5.0], [1.1, 0.9, 5.0]])  # small entries left out
    assert zheng2024.relative_scatter(est, exact) == pytest.approx(0.1)
    with pytest.raises(ValueError, match="no exact index"):
        zheng2024.relative_scatter(exact, exact, threshold=0.5)


def test_bars_figure_draws_published_values_only_when_given():
    import matplotlib.pyplot as plt

    names = [f"e{i}" for i in range(41)]
    st = {m: np.full((6, 41), 1 / 41) for m in ("PCE", "MCS", "LHS")}
    t2 = pd.DataFrame({"comp": ["Px"], "symbol": ["e3"], "pce": [0.1]})
    for table, n_marks in ((None, 0), (t2, 1)):
        fig = zheng2024.bars_figure(st, comps=["Px", "Py"], all_comps=COMP, names=names,
                                    t2=table, key_threshold=0.05, title="t",
                                    published_colour="k")
        assert len(fig.axes[0].collections) == n_marks
        plt.close(fig)


def test_table3_printed_arithmetic():
    """Table 3's total is the sum of its parts, and the abstract's reductions follow from it."""
    t3 = printed.published("zheng2024_table3_timing").set_index("method")
    facts = printed.published("zheng2024_facts").set_index("quantity").value
    tot = t3.total_time_s.astype(float)
    parts = float(t3.model_time_s["PCE"]) + float(t3.index_time_s["PCE"])
    assert parts == pytest.approx(tot["PCE"])
    for m, key in (("MCS", "time_reduction_vs_mcs"), ("LHS", "time_reduction_vs_lhs")):
        assert round(100 * (1 - tot["PCE"] / tot[m]), 1) == float(facts[key])


def test_table_indices_are_the_library_indices_laid_out_as_table_2():
    machine = build("ac_double_turntable")
    sd = np.array([5e-3 if e.translational else 1.6e-5 for e in machine.catalogue])
    jac = machine.jacobian({"x": [10.0, 80.0], "y": 40.0, "z": 60.0, "A": 0.6, "C": 1.1})
    tab = zheng2024.table_indices(jac, sd=sd)
    assert tab.shape == (2, 6, 41)
    assert np.allclose(tab.sum(-1), 1.0)                   # a component's row sums to 1
    # the same numbers as the library's (errors, components) array, transposed
    assert np.array_equal(tab, linear_indices(jac, sd=sd).transpose(0, 2, 1))
    # by hand, for one entry: J^2 sd^2 over the component's sum
    j = jac[1, 3] ** 2 * sd**2
    assert tab[1, 3, 7] == pytest.approx(j[7] / j.sum(), rel=1e-13)


def test_pce_fit_quality_lists_each_component_in_order():
    from types import SimpleNamespace

    fits = {k: SimpleNamespace(coef=np.ones(k + 1), n_candidates=100 + k, loo=10.0 ** -k)
            for k in (1, 0)}                              # any key order: rows follow comps
    d = zheng2024.pce_fit_quality(fits, ["Px", "Py"])
    assert list(d.columns) == ["component", "terms_kept", "basis_size", "corrected_LOO"]
    assert d.component.tolist() == ["Px", "Py"] and d.terms_kept.tolist() == [1, 2]
    assert d.basis_size.tolist() == [100, 101] and d.corrected_LOO.tolist() == [1.0, 0.1]


def test_key_relative_difference_is_relative_to_the_sampled_value():
    names = ["a", "b", "c"]
    pce = np.array([[0.5, 0.3, 0.2], [0.1, 0.1, 0.8]])
    st = {"PCE": pce, "MCS": pce.copy(), "LHS": pce.copy()}
    keys = {("Px", "a"), ("Py", "c")}
    assert zheng2024.key_relative_difference(st, keys=keys, comps=["Px", "Py"], names=names) == 0
    st["LHS"][1, 2] = 0.64                                 # 0.8 / 0.64 - 1 = 25 %
    st["MCS"][0, 0] = 0.55                                 # |0.5 / 0.55 - 1| = 9.1 %
    st["MCS"][0, 1] = 0.01                                 # not a key error: left out
    got = zheng2024.key_relative_difference(st, keys=keys, comps=["Px", "Py"], names=names)
    assert got == pytest.approx(0.25, rel=1e-12)
    got = zheng2024.key_relative_difference(st, keys=keys, comps=["Px", "Py"], names=names,
                                            against=("MCS",))
    assert got == pytest.approx(0.05 / 0.55, rel=1e-12)
    with pytest.raises(ValueError, match="at least one key error"):
        zheng2024.key_relative_difference(st, keys=set(), comps=["Px", "Py"], names=names)


def test_published_relative_difference_takes_the_larger_of_the_two_columns():
    t2 = pd.DataFrame({"pce": [0.10, 0.20, 0.30], "mcs": [0.10, 0.25, 0.30],
                       "lhs": [0.11, 0.20, 0.30]})
    rel, worst = zheng2024.published_relative_difference(t2)
    assert rel.to_numpy() == pytest.approx([1 - 0.10 / 0.11, 0.2, 0.0], rel=1e-12)
    assert worst == 1
    rel, worst = zheng2024.published_relative_difference(t2.iloc[[2]])   # all equal: first row
    assert worst == 0 and rel.max() == 0


def test_fig7_texts_give_both_readings_of_eq_24():
    assert zheng2024.both_sizes("from 500", "not reached") == (
        "from 500 (R at the larger size), not reached (at the smaller)")
    idx = pd.MultiIndex.from_tuples([(m, rd, "d_xc") for m in ("LHS", "MCS")
                                     for rd in zheng2024.READINGS],
                                    names=["method", "reading", "symbol"])
    txt = pd.DataFrame({"R at the larger size": ["from 1", "from 2", "from 500", "from 1000"],
                        "R at the smaller size": ["x", "y", "from 200", "not reached"]}, idx)
    assert zheng2024.convergence_text(txt, method="MCS", symbol="d_xc") == (
        "base samples: from 500 (R at the larger size), from 200 (at the smaller); "
        "model runs: from 1000 (R at the larger size), not reached (at the smaller)")
    idx = pd.MultiIndex.from_tuples([("MCS", rd, s) for rd in zheng2024.READINGS
                                     for s in ("d_xc", "d_yc")])
    r = pd.DataFrame({1000: [12.0, 3.04, 1.0, 2.0], 2000: [4.0, 8.96, np.nan, 5.52]}, idx)
    assert zheng2024.fluctuation_text(r, method="MCS") == (
        "base samples: 3.0 to 12.0 % (R at the larger size), 4.0 to 9.0 % (at the smaller); "
        "model runs: 1.0 to 2.0 % (R at the larger size), 5.5 to 5.5 % (at the smaller)")


#: Every field of the captions, as notebook 01 fills them (values of the committed run).
CAPTION_FIELDS = dict(
    n_points=20, n_per_diagonal=5, rms_mean=0.0361, rms_single=0.0046, n_pce=1000,
    n_reference=100000, key_threshold=0.05, where="test point 2 (x=-200.0 mm)", gap_pce=2e-6,
    gap_mcs=9e-4, gap_lhs=9e-4, pce_largest=2000, r_base="0.9 to 7.5 %", r_runs="10.3 to 66.7 %",
    n_ishigami=300, n_g=1000, err_legendre=5e-6, err_hermite=0.24, n_below=10, err_g=0.11,
    validation_g=0.31, warned="triggers a warning", loo_last=0.015, terms_last=120, terms_best=4,
    sd_text="1.7 µm, 8.4 µrad", sigma=0.5, tool=100.0, shrink=100.0, n_tests=33, rank=10)


def test_figures_follow_the_book_and_state_only_numbers_the_run_fills_in():
    import string

    assert list(zheng2024.FIGURES) == [
        "fig04_indices_per_test_point", "fig05_position_total_sobol",
        "fig06_attitude_total_sobol", "fig07_convergence", "pce_benchmarks",
        "beyond_key_errors_by_test"]
    # the captions declared beside the functions that draw them are the chapter's
    assert zheng2024.FIGURES["fig04_indices_per_test_point"] is zheng2024.FIG04
    assert zheng2024.FIGURES["fig05_position_total_sobol"] is zheng2024.FIG05
    assert zheng2024.FIGURES["fig06_attitude_total_sobol"] is zheng2024.FIG06
    # the scorecard rows each figure is scored with (the notebook's former FIGURE_ROWS)
    assert zheng2024.FIG04.rows == ("Section 3.2",)
    assert zheng2024.FIG05.rows == zheng2024.FIG06.rows == ("Section 3.3",)
    for caption in zheng2024.FIGURES.values():
        fields = {f for _, f, _, _ in string.Formatter().parse(caption.text) if f}
        assert fields <= set(CAPTION_FIELDS), (caption.name, fields - set(CAPTION_FIELDS))
        text = caption.format(**CAPTION_FIELDS).text
        assert "{" not in text and "}" not in text
    fig05 = zheng2024.FIG05.format(**CAPTION_FIELDS)
    assert "sparse PCE (1000 samples), MCS and LHS (100,000 base samples each)" in fig05.text
    assert fig05.name == zheng2024.FIG05.name and fig05.rows == zheng2024.FIG05.rows


def test_parameters_cell_is_within_the_line_length():
    cell = zheng2024.Parameters.cell()
    assert len(cell.splitlines()) == len(zheng2024.Parameters.names())
    assert max(len(line) for line in cell.splitlines()) <= 100
