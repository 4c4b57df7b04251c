"""Notebook 01 (Zheng et al. 2024) after the second audit (issue 24): the two readings of
Eq. 24, Section 3.2's group shares, the sampling scatter and Table 3's printed arithmetic."""

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pandas as pd
import pytest

from mtaccuracy.compendium import reproduction, zheng2024
from mtaccuracy.machines import build
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
    s = linear_indices(machine.jacobian(poses), sd)
    for p in s:
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
        fig = zheng2024.bars_figure(st, ["Px", "Py"], COMP, names, table, 0.05, "t", "k")
        assert len(fig.axes[0].collections) == n_marks
        plt.close(fig)


def test_table3_printed_arithmetic():
    """Table 3's total is the sum of its parts, and the abstract's reductions follow from it."""
    t3 = reproduction.published("zheng2024_table3_timing").set_index("method")
    facts = reproduction.published("zheng2024_facts").set_index("quantity").value
    tot = t3.total_time_s.astype(float)
    parts = float(t3.model_time_s["PCE"]) + float(t3.index_time_s["PCE"])
    assert parts == pytest.approx(tot["PCE"])
    for m, key in (("MCS", "time_reduction_vs_mcs"), ("LHS", "time_reduction_vs_lhs")):
        assert round(100 * (1 - tot["PCE"] / tot[m]), 1) == float(facts[key])
