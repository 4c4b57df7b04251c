"""Notebook 03's circle question (``papers.guo2016_measurement``) against a ballbar worked by hand.

The hand model: Guo's chain reads ``Ex = dx(x) + dx(y) - y (S_xy + ez(x)) + ...`` (Eqs. 6-8); on
an XY circle of radius R about the middle of the travels (half travel T), with no Abbe arm
(z = 0, no tool offsets), a bar reads the radial part of the error:

* a scale term ``dx(x)[1] = c`` (x error ``c x / T``): ``c R cos^2(t) / T``;
  ``dy(y)[1]``: ``c R sin^2(t) / T``; after the centre and bar length,
  ``+-c R cos(2t) / (2 T)``: the difference seen, the mean scale absorbed;
* the squareness and X's constant yaw (x error ``-y a``): ``-a R sin(2t) / 2``, the same
  column: one combination;
* X's yaw varying along x (``ez(x)[1] = c``: x error ``-y c x / T``): ``-c R^2 sin(t) cos^2(t)
  / T``, whose third harmonic nothing else has: seen alone.

The rank and the null space of those columns are redone here with numpy's SVD.
"""

import numpy as np
import pytest

from mtaccuracy import errors
from mtaccuracy.measure import instruments, motions
from mtaccuracy.papers import guo2016
from mtaccuracy.papers import guo2016_measurement as gm
from mtaccuracy.papers.parameters import ParameterError

R, T, NP = 80.0, 200.0, 24


@pytest.fixture(scope="module")
def circle():
    model = motions.motion_model(gm.circle_machine(travel_mm=T), degree=1)
    return instruments.circle(model, plane="XY", radius=R, at=dict(D1=0.0, D2=0.0, D3=0.0),
                              sigma=0.2, n_points=NP, directions=("ccw",))


def _hand_columns(theta):
    """The four columns of the worked model (readings per unit: mm per mm, mm per rad)."""
    c, s = np.cos(theta), np.sin(theta)
    return {"dx(x)[1]": R * c * c / T, "dy(y)[1]": R * s * s / T, "S_xy": -R * s * c,
            "ez(x)[0]": -R * s * c, "ez(x)[1]": -R * R * s * c * c / T}


def _project(cols, theta):
    N = np.c_[np.cos(theta), np.sin(theta), np.ones_like(theta)]
    return cols - N @ np.linalg.lstsq(N, cols, rcond=None)[0]


def test_the_exact_readings_are_the_hand_model(circle):
    model = circle.model
    theta = 2 * np.pi * np.arange(NP) / NP
    hand = _hand_columns(theta)
    # the largest displacement of the tool ball (mm): c R / T, a R, c R**2 / T
    for p, size, d in (("dx(x)[1]", 2e-3, 2e-3 * R / T), ("S_xy", 2e-5, 2e-5 * R),
                       ("ez(x)[1]", 3e-5, 3e-5 * R * R / T)):
        eps = np.zeros(model.n_params)
        eps[model.names.index(p)] = size
        got = circle.readings(eps)                                      # um, exact chain
        want = 1e3 * size * hand[p]
        # the circle is centred on the axes' zeros (the middle of the travels), so the hand
        # model is the raw reading; a displacement d (mm) changes the bar's length R by at
        # most d**2 / (2 R) beyond first order
        gap = np.abs(got - want).max()
        assert gap <= 1e3 * d * d / (2 * R) * 1.01 + 1e-12
        assert np.abs(want).max() > 1e4 * gap                 # and the model is not trivially 0


def test_statuses_follow_from_an_svd_of_the_hand_columns(circle):
    theta = 2 * np.pi * np.arange(NP) / NP
    hand = _hand_columns(theta)
    names = list(hand)
    P = _project(np.column_stack([hand[p] for p in names]), theta)
    P /= np.linalg.norm(P, axis=0)
    _, s, vt = np.linalg.svd(P)
    rank = int(np.sum(s > 1e-9 * s[0]))
    null = vt[rank:]
    assert rank == 3                                   # cos 2t, sin 2t, the third harmonic
    in_null = np.abs(null).max(axis=0) > 1e-9
    expect = {p: "combination" if in_null[j] else "seen" for j, p in enumerate(names)}
    table = gm.circle_table(circle, prior_sd=np.full(circle.model.n_params, 1e-5))
    got = table[table.parameter.isin(names)].set_index("parameter").structure.to_dict()
    assert got == expect
    assert expect == {"dx(x)[1]": "combination", "dy(y)[1]": "combination",
                      "S_xy": "combination", "ez(x)[0]": "combination", "ez(x)[1]": "seen"}
    # every other term has no effect beyond the nuisances here: blind
    rest = table[~table.parameter.isin(names) & (table.parameter != "")]
    assert set(rest.structure) == {"blind"}
    comb = table.set_index("parameter").structure_combination
    assert comb["dx(x)[1]"] == "dx(x)[1] + dy(y)[1]"            # the mean scale is unseen
    assert comb["S_xy"] == "ez(x)[0] - S_xy"


def test_a_tiny_prior_hides_the_squareness_at_the_bound_derived(circle):
    # S_xy's column beyond the nuisances is -R/2 sin 2t (um/rad: 1e3 R / 2); with ez(x)[0]
    # known (tiny prior), S_xy is seen iff s**2 = prior**2 ||col||**2 / sigma**2 >= 99, blind iff
    # the data remove at most 1 % of its variance, s**2 / (1 + s**2) <= 0.01 (s**2 <= 1/99:
    # a factor 1/99 of the critical prior), learned in part in between
    model = circle.model
    theta = 2 * np.pi * np.arange(NP) / NP
    norm = np.linalg.norm(1e3 * R / 2 * np.sin(2 * theta))
    critical = np.sqrt(99.0) * 0.2 / norm
    for factor, want in ((0.5, "combination"), (2.0, "seen"), (0.7 / 99, "blind"),
                         (1.4 / 99, "combination")):
        prior = np.full(model.n_params, 1e-12)
        prior[model.names.index("S_xy")] = factor * critical
        table = gm.circle_table(circle, prior_sd=prior).set_index("parameter")
        assert table.at_ranges["S_xy"] == want


def test_visible_peak_is_the_harmonic_amplitude(circle):
    peak = gm.visible_peak(circle, parameters=["S_xy", "dx(x)[1]", "dx(x)[0]"])
    assert peak["S_xy"] == pytest.approx(1e3 * R / 2, rel=1e-9)          # um per rad
    assert peak["dx(x)[1]"] == pytest.approx(1e3 * R / (2 * T), rel=1e-9)  # um per mm
    assert peak["dx(x)[0]"] < 1e-9                                      # the zero: the centre
    with pytest.raises(ValueError, match="unknown parameters.*nope"):
        gm.visible_peak(circle, parameters=["nope"])


def test_priors_are_the_ranges_widths_and_bad_input_is_refused(circle):
    model = circle.model
    cat = model.machine.catalogue
    ranges = {"positioning": (0.0, 3.0), "straightness": (0.0, 4.0),
              "angular": (0.0, 3.2e-5), "squareness": (0.0, 1.9)}
    bounds = errors.uniform_bounds(cat, ranges)
    prior = model.prior_sd(bounds)
    j = model.names.index("dx(x)[1]")
    assert prior[j] == pytest.approx(3e-3 / np.sqrt(12))               # mm
    assert prior[model.names.index("S_xy")] == pytest.approx(1.9e-6 / np.sqrt(12))
    with pytest.raises(ValueError, match=r"bounds must be \(2, 21\)"):
        model.prior_sd(np.asarray(bounds).T)
    with pytest.raises(ValueError, match="prior_sd must be"):
        gm.circle_table(circle, prior_sd=prior[:-1])
    with pytest.raises(ValueError, match="travel_mm must be a finite number > 0"):
        gm.circle_machine(travel_mm=0.0)
    m = gm.circle_machine(travel_mm=50.0, centre=(100.0, 0.0, -20.0))
    assert m.travels == {"x": (50.0, 150.0), "y": (-50.0, 50.0), "z": (-70.0, 30.0)}


def test_the_table_lists_every_error_and_term_and_says_why_a_term_is_missing(circle):
    table = gm.circle_table(circle, prior_sd=np.full(circle.model.n_params, 1e-5))
    assert len(table) == 21 * 2 and list(table.symbol.unique()) == circle.model.machine.error_names
    missing = table[table.parameter == ""].set_index(["symbol", "degree"])
    assert "squareness" in missing.structure_combination[("dy(x)", 1)]  # a slope
    assert "constant" in missing.structure_combination[("S_xy", 1)]
    assert set(missing.structure) == {"n/a"}


def test_a_circle_outside_the_travels_is_refused_before_any_work():
    p = guo2016.Parameters(circle_radius_mm=300.0, circle_travel_mm=250.0)
    with pytest.raises(ParameterError, match="circle_travel_mm"):
        p.check()
    guo2016.Parameters().check()
