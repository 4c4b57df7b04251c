"""The interactive explorer (``mtaccuracy.apps.explore``): what it computes, held to
independent formulations, its starting values read from the notebooks' declarations, and its
server held to 127.0.0.1.

The computations (``explore_model``) are plain functions: the indices at a pose against a
Monte Carlo regression on the exact chain, a finite-difference Jacobian and an analytic pose;
the dominant-error map against single-pose computations and to one batched Jacobian call; the
spindle transfer against the harmonics theory cancels; the thermal prediction against a
least-squares fit written out here.  The app is built in Python (no browser: see
``test_explore_browser.py``) to check that each tab starts from the notebooks' declarations, shows
the numbers the model computes, and shows the library's message for a bad topology.
"""

import html
import re
import signal
import socket

import numpy as np
import pandas as pd
import pytest

from mtaccuracy import sensitivity as S
from mtaccuracy.apps import explore_model as M
from mtaccuracy.compendium.notebook import ROOT
from mtaccuracy.machines.iso import iso_machine
from mtaccuracy.machines.topology import parse_topology
from mtaccuracy.papers import guo2016, rong, xu2022, yang2021, your_spindle, zheng2024

TOPOLOGY = "w C b X Y Z B t"      # notebook 06's swivel-head machine


@pytest.fixture(scope="module")
def setups():
    return {k: M.machine_setup(k) for k in [*M.MACHINES, TOPOLOGY]}


# ------------------------------------------------------------------------------------------
# Machines: setups and ranges
# ------------------------------------------------------------------------------------------

@pytest.fixture
def declare():
    """Change a notebook's declared defaults for one test (restored after it)."""
    saved = []

    def change(declared, **values):
        for name, value in values.items():
            saved.append((declared.param[name], declared.param[name].default))
            declared.param[name].default = value
    yield change
    for p, value in reversed(saved):
        p.default = value


def _half(setup) -> dict:
    return dict(zip(setup.names, M.error_half_ranges(setup), strict=True))


def test_the_machines_start_from_their_notebooks_declarations(declare):
    """Ranges, workspace, pose and tool offsets are read from each notebook's ``Parameters``
    when the machine is set up: a changed declaration changes them (nothing typed twice)."""
    declare(zheng2024.Parameters, position_range_um=4.0, angular_range_arcsec=2.5)
    z = M.machine_setup("ac_double_turntable")
    assert (z.position_um, z.angular_arcsec) == (4.0, 2.5) and z.machine.n_errors == 41
    assert _half(z)["d_xx"] == pytest.approx(4e-3) and _half(z)["e_xx"] == pytest.approx(
        2.5 * M.ARCSEC)
    # Rong: range_factor x the acceptance values of ranges_file (read here with pandas)
    declare(rong.Parameters, range_factor=3.0, workspace_mm=[800.0, 600.0, 400.0],
            tool_offset_mm=[0.0, 0.0, 50.0])
    r = M.machine_setup("horizontal_3axis")
    acc = pd.read_csv(ROOT / rong.Parameters.param["ranges_file"].default)
    scale = acc.unit.map({"um": 1e-3, "rad": 1.0, "um/m": 1e-6})
    assert _half(r) == pytest.approx(dict(zip(acc.symbol, 3.0 * acc.high * scale, strict=True)))
    assert [(a.low, a.high, a.default) for a in r.axes] == [(0, 800, 400), (0, 600, 300),
                                                            (0, 400, 200)]
    assert r.tool == {"tool_x": 0.0, "tool_y": 0.0, "tool_z": 50.0}
    # Guo: the half widths of [0, r] (the same variance), at the declared pose and grid
    declare(guo2016.Parameters, positioning_um=6.0, x_mm=50.0, workspace_mm=300.0)
    g = M.machine_setup("vertical_xyfz")
    assert [_half(g)[s] for s in ("dx(x)", "dy(x)", "ex(x)", "S_xy")] == pytest.approx(
        [3e-3, 2e-3, 1.6e-5, 0.95e-6])
    assert [(a.high, a.default) for a in g.axes] == [(300, 50), (300, 100), (300, 100)]
    assert all("notebook 0" in n for s in (z, r, g) for n in s.notes)


def test_the_spindle_and_thermal_tabs_start_from_notebooks_05_and_04():
    p = yang2021.Parameters.defaults()
    assert (M.YANG_POSITIONS, M.YANG_SAMPLES, M.YANG_A3) == (
        tuple(p["probe_positions"]), p["n_samples"], p["a3"])
    data, reconstructed = M.thermal_data()
    assert data.source == str(ROOT / xu2022.Parameters.param["data_dir"].default)
    # notebook 04's split on the reconstruction: the paper's (train 1 2 3, test 4), its inputs
    assert M.thermal_defaults(data, reconstructed) == {"train": [1, 2, 3], "test": 4,
                                                      "inputs": "published"}
    assert M.thermal_defaults(data, False)["inputs"] == "selected"


def test_the_range_sliders_scale_their_group_only(setups):
    s = setups["horizontal_3axis"]
    base = M.error_half_ranges(s)
    trans = s.translational
    moved = M.error_half_ranges(s, position_um=2 * s.position_um)
    assert np.allclose(moved[trans], 2 * base[trans]) and np.array_equal(moved[~trans],
                                                                         base[~trans])
    moved = M.error_half_ranges(s, angular_arcsec=s.angular_arcsec / 4)
    assert np.allclose(moved[~trans], base[~trans] / 4) and np.array_equal(moved[trans],
                                                                          base[trans])


def test_pose_ranges_come_from_the_travels_when_known(setups):
    z = setups["ac_double_turntable"]
    a = z.axis("A")
    assert (a.low, a.high) == pytest.approx((-130.0, 130.0)) and a.unit == "deg" and a.rotary
    assert z.axis("x").low == -400.0 and z.axis("C").high == pytest.approx(360.0)
    assert [a.default for a in setups["vertical_xyfz"].axes] == [100.0, 100.0, 100.0]
    with pytest.raises(ValueError, match="no axis 'q'"):
        z.axis("q")
    with pytest.raises(ValueError, match="unknown axis"):
        M.pose_of(z, {"w": 1.0})


# ------------------------------------------------------------------------------------------
# Indices at a pose
# ------------------------------------------------------------------------------------------

def test_indices_equal_an_analytic_case():
    """Guo's machine at x = y = z = 0 with no tool offset: no Abbe arm, so Px is
    dx(x) + dx(y) + dx(z) (positioning [0, 3] um, straightness [0, 4] um): indices 9/41,
    16/41, 16/41 and nothing else."""
    g = M.machine_setup("vertical_xyfz")
    r = M.indices_at_pose(g, dict(x=0.0, y=0.0, z=0.0))
    px = dict(zip(r.names, r.indices[:, 0], strict=True))
    want = {"dx(x)": 9 / 41, "dx(y)": 16 / 41, "dx(z)": 16 / 41}
    assert {k: v for k, v in px.items() if v > 1e-15} == pytest.approx(want, abs=1e-12)
    # one error obviously dominates when its group's range is 1000 times the other's
    r = M.indices_at_pose(g, dict(x=0.0, y=0.0, z=400.0), position_um=0.1, angular_arcsec=100)
    out, errs, index = M.top_errors(r)[0]   # two pitch errors with one arm: a tie, both shown
    assert out == "Px" and errs == ("ey(x)", "ey(y)") and index > 0.3, errs


def test_indices_equal_a_monte_carlo_regression_on_the_exact_chain(setups):
    """For independent inputs the index of e_i in a linear model is the squared correlation
    of y with e_i: estimated here from samples of the *exact* chain (uniform errors on the
    ranges), a route that shares nothing with the closed form but the machine."""
    s = setups["horizontal_3axis"]
    values = dict(x=600.0, y=150.0, z=420.0)
    r = M.indices_at_pose(s, values)
    half = M.error_half_ranges(s)
    rng = np.random.default_rng(7)
    e = rng.uniform(-half, half, (40_000, s.machine.n_errors))
    y = s.machine.pose_error(e, M.pose_of(s, values))[:, :3]
    ec, yc = e - e.mean(0), y - y.mean(0)
    rho2 = (ec.T @ yc) ** 2 / np.outer((ec**2).sum(0), (yc**2).sum(0))      # (d, 3)
    assert np.abs(rho2 - r.indices[:, :3]).max() < 0.02
    assert r.indices[:, :3].max() > 0.2              # not a flat case


def test_indices_equal_the_finite_difference_jacobian(setups):
    """The closed-form Jacobian against central differences of the exact chain
    (``machine.jacobian``), through the same share formula written out here."""
    for key in ("ac_double_turntable", TOPOLOGY):
        s = setups[key]
        values = {a.name: a.low + 0.37 * (a.high - a.low) for a in s.axes}
        r = M.indices_at_pose(s, values, position_um=7.0, angular_arcsec=4.0)
        sd = M.error_half_ranges(s, position_um=7.0, angular_arcsec=4.0) / np.sqrt(3)
        jac = s.machine.jacobian(M.pose_of(s, values), step=1e-6)[0]      # (6, d)
        v = jac**2 * sd**2
        ours = (v / v.sum(1, keepdims=True)).T
        assert np.abs(ours - r.indices)[:, r.first_order].max() < 1e-6


def test_indices_sum_to_one_only_where_there_is_a_first_order_term(setups):
    for key, s in setups.items():
        r = M.indices_at_pose(s)
        sums = r.indices.sum(0)
        assert np.allclose(sums[r.first_order], 1.0, atol=1e-12), key
        assert np.all(sums[~r.first_order] == 0.0), key
    # the swivel head at the centre of its travels: Vz has no first-order term (a unit
    # vector's change along itself is second order)
    r = M.indices_at_pose(setups[TOPOLOGY])
    assert list(np.array(r.outputs)[~r.first_order]) == ["Vz"]
    assert "Vz" not in [o for o, _, _ in M.top_errors(r)]


# ------------------------------------------------------------------------------------------
# Dominant-error map
# ------------------------------------------------------------------------------------------

@pytest.mark.parametrize("key", [*M.MACHINES, TOPOLOGY])
def test_the_map_equals_the_argmax_at_each_single_pose(setups, key):
    s = setups[key]
    values = {a.name: a.default for a in s.axes}
    d = M.dominant_map(s, values, steps=9)
    rng = np.random.default_rng(3)
    for i, j in [(0, 0), (8, 8), (4, 2), *rng.integers(0, 9, (5, 2)).tolist()]:
        at = dict(values, **{d.axes[0]: float(d.u[i]), d.axes[1]: float(d.v[j])})
        r = M.indices_at_pose(s, at)
        top = np.argmax(S.merge_ties(r.indices), axis=0)
        for k in range(len(r.outputs)):
            if r.first_order[k]:
                assert d.error[j, i, k] == top[k], (key, i, j, r.outputs[k])
                assert d.index[j, i, k] == pytest.approx(r.indices[top[k], k], rel=1e-9)
                assert d.index[j, i, k] == pytest.approx(r.indices[:, k].max(), rel=1e-9)
            else:
                assert d.error[j, i, k] == -1 and d.index[j, i, k] == 0.0


def test_the_map_is_one_batched_jacobian_call_and_not_trivial(setups, monkeypatch):
    s = M.machine_setup("ac_double_turntable")
    calls = []
    real = s.machine.jacobian

    def counted(pose):
        calls.append({k: np.shape(v) for k, v in pose.items()})
        return real(pose)
    monkeypatch.setattr(s.machine, "jacobian", counted)
    d = M.dominant_map(s, axes=("C", "A"), steps=25)
    assert len(calls) == 1 and calls[0]["C"] == (625,) and calls[0]["A"] == (625,)
    assert d.error.shape == (25, 25, 6) and np.allclose(d.u, np.linspace(0, 360, 25))
    assert len(np.unique(d.error[:, :, 0])) >= 3       # the map shows more than one error


def test_the_slider_update_returns_both(setups):
    s = setups["vertical_xyfz"]
    r, d = M.slider_update(s, dict(x=250.0), axes=("y", "z"), steps=5)
    assert r.indices.shape == (21, 6) and d.error.shape == (5, 5, 6) and d.axes == ("y", "z")
    assert np.array_equal(r.indices, M.indices_at_pose(s, dict(x=250.0)).indices)


# ------------------------------------------------------------------------------------------
# Typed topologies
# ------------------------------------------------------------------------------------------

@pytest.mark.parametrize("bad", ["w Q b t", "w X b X t", "b X Y t", ""])
def test_a_bad_topology_gives_the_library_message(bad):
    with pytest.raises(ValueError) as lib:
        iso_machine(bad)
    for build in (M.machine_setup, M.topology_setup):
        with pytest.raises(ValueError) as ours:
            build(bad)
        assert str(ours.value) == str(lib.value)
    # a machine's name typed as a topology is read as a topology (and refused)
    with pytest.raises(ValueError, match="unknown axis letter"):
        M.topology_setup("vertical_xyfz")


@pytest.fixture(scope="module")
def app():
    pytest.importorskip("panel")
    from mtaccuracy.apps import explore

    return explore.create_app()


def _shown_top(tab) -> dict:
    """The top-error table of the Machine tab as shown: output -> (errors, index)."""
    rows = re.findall(r'data-output="(\w+)" data-error="([^"]*)"(?: data-ties="\d+")? '
                      r'data-index="([^"]*)"',
                      tab.top.object)
    return {o: (html.unescape(e), float(v) if v else None) for o, e, v in rows}


def _check_machine_tab_shows_the_model(tab):
    """What the Machine tab shows equals the model's numbers at its controls' values."""
    kw = dict(position_um=tab.position_um, angular_arcsec=tab.angular_arcsec)
    res = M.indices_at_pose(tab.setup, tab.pose_values(), **kw)
    want = {o: (", ".join(e), round(v, 6)) for o, e, v in M.top_errors(res)}
    assert _shown_top(tab) == {o: want.get(o, ("", None)) for o in res.outputs}
    heat = tab.heat_src.data                              # error-major, NaN: no first-order term
    assert list(heat["error"][::len(res.outputs)]) == res.names
    assert np.array_equal(heat["index"], np.where(res.first_order, res.indices, np.nan).ravel(),
                          equal_nan=True)
    d = M.dominant_map(tab.setup, tab.pose_values(), axes=(tab.across, tab.up), **kw)
    k = d.outputs.index(tab.output)
    names = np.array([*d.names, "no first-order term"])    # -1: the last
    assert list(tab.map_src.data["error"]) == names[d.error[:, :, k].ravel()].tolist()
    assert np.array_equal(tab.map_src.data["index"], d.index[:, :, k].ravel())
    assert tab.dmap.title.text == f"Dominant error for {tab.output}"


def test_the_machine_tab_shows_the_model_and_the_library_message(app):
    tab = app.tabs["machine"]
    z = M.machine_setup("ac_double_turntable")
    assert (tab.setup.key, tab.pose_values()) == (z.key, {a.name: a.default for a in z.axes})
    assert (tab.position_um, tab.angular_arcsec) == (z.position_um, z.angular_arcsec)
    assert (tab.across, tab.up) == ("C", "A")          # notebook 06's two rotary axes
    _check_machine_tab_shows_the_model(tab)
    before = tab.setup.label
    tab.topology = "w C A b Y X Q t"
    with pytest.raises(ValueError) as lib:
        parse_topology("w C A b Y X Q t")
    shown = app.tabs["machine"].view()[0][2].object     # the error pane of the controls
    assert tab.error == str(lib.value) and html.escape(str(lib.value)) in shown
    assert "Traceback" not in shown and tab.setup.label == before
    tab.topology = TOPOLOGY                               # a good one replaces the machine
    assert tab.error == "" and tab.setup.machine.n_errors == 37 and tab.machine == M.TOPOLOGY
    assert [tab.pose.param[a].label for a in ("C", "x", "y", "z", "B")] == [
        "C (°)", "x (mm)", "y (mm)", "z (mm)", "B (°)"]
    assert _shown_top(tab)["Vz"] == ("", None)            # no first-order term at the centre
    _check_machine_tab_shows_the_model(tab)
    tab.pose.B = 30.0
    tab.param.update(output="Py", across="x", up="B", position_um=2.0)
    _check_machine_tab_shows_the_model(tab)
    tab.machine = "horizontal_3axis"                      # moving a slider changes what is shown
    shown = _shown_top(tab)
    tab.pose.x = 690.0
    assert _shown_top(tab) != shown
    _check_machine_tab_shows_the_model(tab)


def test_the_spindle_tab_starts_from_notebook_05_and_shows_the_model(app):
    tab = app.tabs["spindle"]
    p = yang2021.Parameters.defaults()
    assert (tab.probe2, tab.probe3, tab.probe4) == M.YANG_DEG[1:]
    assert (tab.max_harmonic, tab.a3) == (p["worst_k"], p["a3"])
    assert tab.amplified_above == your_spindle.Parameters.defaults()["amplified_above"]
    tab.layout = "four probes equally spaced"             # a preset sets the angles
    assert (tab.probe2, tab.probe3, tab.probe4) == (90.0, 180.0, 270.0)
    summary = tab.plots()[0][0].object
    assert "Cancelled by the layout: <b>3, 5, 7, 9, 11, 13, 15, 17, 19</b>" in summary
    tab.param.update(probe2=100.0, weights="eq5", a3=1.0, max_harmonic=30)
    assert tab.layout == "custom"                         # an angle moved: no preset
    t = M.probe_transfer([0, 100, 180, 270], max_harmonic=30, weights="eq5", a3=1.0,
                         amplified_above=tab.amplified_above)
    worst = t.q_least_squares[np.isfinite(t.q_least_squares)].max()
    summary = tab.plots()[0][0].object
    assert f"Worst q_k: least squares {worst:.3f}" in summary
    shown = ", ".join(f"{v:.4f}" for v in np.round(t.weights, 4) + 0.0)
    assert "(a_0..a_3 in Yang et al.): " + shown in summary
    tab.probe2 = 180.0                                    # two probes at one angle
    with pytest.raises(ValueError) as lib:
        M.probe_transfer([0, 180, 180, 270])
    assert html.escape(str(lib.value)) in tab.plots().object
    tab.layout = tab.param.layout.objects[0]             # back to notebook 05's layout
    assert (tab.probe2, tab.probe3, tab.probe4) == M.YANG_DEG[1:]


def test_the_thermal_tab_starts_from_notebook_04_and_shows_the_model(app, thermal_data):
    """Outside a server the fit runs at once (no event loop): the view shows its result."""
    tab = app.tabs["thermal"]
    assert (tab.train, tab.test, tab.inputs, tab.kind) == ([1, 2, 3], 4, "published", "mlr")
    summary = tab.plots()[0].object
    want = M.thermal_prediction(thermal_data, train=[1, 2, 3], test=4)
    assert f'data-rmse="{want.rmse:.6f}"' in summary and f"RMSE {want.rmse:.3f} µm" in summary
    assert xu2022.RECONSTRUCTED_LABEL in summary and (tab.status, tab.busy) == ("done", False)
    tab.param.update(train=[2, 4], test=1, inputs="selected")
    want = M.thermal_prediction(thermal_data, train=[2, 4], test=1, inputs="selected")
    summary = tab.plots()[0].object
    assert f'data-rmse="{want.rmse:.6f}"' in summary
    assert f"k from {', '.join(want.inputs['k'])}" in summary
    tab.test = 2
    tab.train = [2]
    assert "is also a training experiment" in tab.plots().object and not tab.busy


# ------------------------------------------------------------------------------------------
# Spindle
# ------------------------------------------------------------------------------------------

@pytest.mark.parametrize("n", [3, 4, 5, 6])
def test_equally_spaced_probes_cancel_exactly_k_equal_to_plus_minus_one_mod_n(n):
    """n probes equally spaced read exp(i k phi_l) as a motion (cos, sin) exactly when
    k = +-1 mod n (the DFT of the layout): no estimator recovers those harmonics."""
    t = M.probe_transfer(np.arange(n) * 360.0 / n, max_harmonic=30)
    theory = (t.harmonics % n == 1) | (t.harmonics % n == n - 1)
    assert np.array_equal(t.cancelled, theory)
    assert np.all(np.isinf(t.q_least_squares[theory]))
    assert np.all(np.isfinite(t.q_least_squares[~theory]))
    assert np.all(t.gain_weighted[theory] == 0)


def test_eq5_weights_on_the_symmetric_layout_cancel_k_2_mod_4_when_a3_is_1():
    """Eq. 15 gives a1 = a3 and a2 = 1 on 0, 90, 180, 270 deg, so Lambda_k = (1 + (-1)^k)
    (1 + a3 i^k): with a3 = 1 the weights also cancel k = 2 mod 4, which least squares
    recovers (notebook 05's rank check)."""
    t = M.probe_transfer([0, 90, 180, 270], max_harmonic=20, weights="eq5", a3=1.0)
    assert np.allclose(t.weights, [1, 1, 1, 1])
    assert list(t.harmonics[t.cancelled_by_weights]) == [2, 6, 10, 14, 18]
    assert np.all(np.isfinite(t.q_least_squares[t.cancelled_by_weights]))


def test_the_yang_layout_and_the_gauss_markov_bound():
    ang = M.YANG_DEG
    assert ang == pytest.approx([0.0, 39.375, 182.8125, 326.25])
    for rule in ("optimal", "eq5"):
        t = M.probe_transfer(ang, max_harmonic=40, weights=rule)
        assert not t.cancelled.any()
        ok = np.isfinite(t.q_weighted)
        # least squares is the best linear unbiased estimator: never above any weights
        assert np.all(t.q_least_squares[ok] <= t.q_weighted[ok] * (1 + 1e-9))
        assert np.array_equal(t.amplified_weighted, np.isfinite(t.q_weighted)
                              & (t.q_weighted > 3.0))
    # the paper's Eq. 5 weights amplify more than the weights searched for the band
    assert M.probe_transfer(ang, weights="eq5").q_weighted.max() > \
        M.probe_transfer(ang, weights="optimal").q_weighted.max()


def test_bad_layouts_are_refused_with_the_library_message():
    with pytest.raises(ValueError, match="same angle"):
        M.probe_transfer([0, 90, 90, 200])
    with pytest.raises(ValueError, match="at least 3"):
        M.probe_transfer([0, 90])
    with pytest.raises(ValueError, match="coincident or opposite"):
        M.probe_transfer([0, 30, 210, 300], weights="eq5")
    with pytest.raises(ValueError, match="four probes"):
        M.probe_transfer([0, 100, 200], weights="eq5")


# ------------------------------------------------------------------------------------------
# Thermal
# ------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def thermal_data():
    data, reconstructed = M.thermal_data()
    assert reconstructed           # the committed data/thermal is the paper's reconstruction
    return data


@pytest.mark.parametrize("train, test", [([1, 2, 3], 4), ([2, 4], 1)])
def test_the_mlr_prediction_equals_a_direct_least_squares_fit(thermal_data, train, test):
    """Eq. 9 written out: per training measurement a straight line through the errors
    (slope k in um/m, intercept b), k regressed on the absolute temperatures of T1, T6, T12,
    b on the rises (from each experiment's first measurement) of T2, T7, T11, by plain
    least squares; the test experiment's errors composed from the predicted k, b."""
    d = thermal_data
    got = M.thermal_prediction(d, train=train, test=test)
    x = d.positions_mm - d.positions_mm[0]
    temps = d.temperatures
    first = temps.groupby(d.index.experiment).transform("first")
    rises = temps - first
    exp = d.index.experiment.to_numpy()
    tr, te = np.isin(exp, train), exp == test
    kb = np.array([np.polyfit(x, row, 1) for row in d.errors[tr]])       # (n, 2): um/mm, um
    design_k = np.c_[np.ones(tr.sum()), temps[["T1", "T6", "T12"]].to_numpy()[tr]]
    design_b = np.c_[np.ones(tr.sum()), rises[["T2", "T7", "T11"]].to_numpy()[tr]]
    ck = np.linalg.lstsq(design_k, kb[:, 0] * 1000, rcond=None)[0]
    cb = np.linalg.lstsq(design_b, kb[:, 1], rcond=None)[0]
    k = np.c_[np.ones(te.sum()), temps[["T1", "T6", "T12"]].to_numpy()[te]] @ ck
    b = np.c_[np.ones(te.sum()), rises[["T2", "T7", "T11"]].to_numpy()[te]] @ cb
    want = k[:, None] * x[None, :] / 1000 + b[:, None]
    assert got.inputs == {"k": ["T1", "T6", "T12"], "b": ["T2", "T7", "T11"]}  # the paper's
    assert np.allclose(got.predicted, want, atol=1e-8)
    assert np.array_equal(got.measured, d.errors[te])
    assert got.rmse == pytest.approx(np.sqrt(np.mean((d.errors[te] - want) ** 2)), rel=1e-9)
    assert got.rmse_uncompensated == pytest.approx(np.sqrt(np.mean(d.errors[te] ** 2)))
    assert got.rmse < got.rmse_uncompensated


def test_thermal_splits_are_checked(thermal_data):
    with pytest.raises(ValueError, match="also a training experiment"):
        M.thermal_prediction(thermal_data, train=[1, 2], test=2)
    with pytest.raises(ValueError, match="no training experiment"):
        M.thermal_prediction(thermal_data, train=[], test=2)
    with pytest.raises(ValueError, match=r"unknown experiment\(s\) \[9\]"):   # the library's
        M.thermal_prediction(thermal_data, train=[1, 2], test=9)
    with pytest.raises(ValueError, match="needs at least 2 training experiments"):
        M.thermal_prediction(thermal_data, train=[1], test=4, kind="svr")
    with pytest.raises(ValueError, match="inputs must be"):
        M.thermal_prediction(thermal_data, train=[1, 2], test=4, inputs="mine")


def test_selected_inputs_come_from_the_training_data_only(thermal_data):
    """The sensitive points are selected on the training experiments alone: the same training
    set gives the same inputs whatever experiment is predicted."""
    a = M.thermal_prediction(thermal_data, train=[1, 2], test=3, inputs="selected")
    b = M.thermal_prediction(thermal_data, train=[1, 2], test=4, inputs="selected")
    assert a.inputs == b.inputs and all(len(v) == 3 for v in a.inputs.values())
    assert a.measured.shape != b.measured.shape or not np.array_equal(a.measured, b.measured)


# ------------------------------------------------------------------------------------------
# The server: 127.0.0.1 only
# ------------------------------------------------------------------------------------------

@pytest.mark.parametrize("address", ["0.0.0.0", "", "::", "localhost", "192.168.1.10",
                                     "127.0.0.2"])
def test_the_server_refuses_any_address_but_loopback(address):
    from mtaccuracy.apps import explore

    with pytest.raises(ValueError, match="127.0.0.1 only"):
        explore.check_address(address)
    with pytest.raises(ValueError, match="127.0.0.1 only"):
        explore.serve(address=address)


def test_the_command_refuses_a_bad_port_in_one_line(capsys):
    from mtaccuracy.apps import explore

    assert explore.main(["--port", "70000"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "0..65535" in err
    assert explore.main(["--token", "short"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "a token is 16 to 128 letters" in err


def test_the_token_or_its_cookie_is_required():
    from mtaccuracy.apps import explore_server as ES

    class Request:                                    # what Bokeh's handlers offer
        def __init__(self, args=None, cookies=None):
            self.args, self.cookies, self.set = args or {}, cookies or {}, {}

        def get_argument(self, name, default=None):
            return self.args.get(name, default)

        def get_cookie(self, name):
            return self.cookies.get(name)

        def set_cookie(self, name, value, **kw):
            self.set[name] = (value, kw)

    token = ES.new_token()
    assert token != ES.new_token() and ES.TOKEN_PATTERN.fullmatch(token)
    auth = ES.TokenAuth(token, 5006)
    first = Request(args={"token": token})
    assert auth.get_user(first) == "reader"
    assert first.set["mtaccuracy_explore_5006"][0] == token
    assert auth.get_user(Request(cookies={"mtaccuracy_explore_5006": token})) == "reader"
    for bad in (Request(), Request(args={"token": token[:-1] + "x"}),
                Request(cookies={"mtaccuracy_explore_5007": token}),
                Request(cookies={"mtaccuracy_explore_5006": token + "x"})):
        assert auth.get_user(bad) is None
    for bad in ("short", "a" * 129, "has space in it 123", "é" * 20, 12345678901234567):
        with pytest.raises(ValueError, match="16 to 128"):
            ES.checked_token(bad)


def test_sessions_are_capped():
    pytest.importorskip("panel")
    from bokeh.document import Document
    from panel.io.state import set_curdoc

    from mtaccuracy.apps import explore_server as ES

    built, docs = [], [Document() for _ in range(5)]
    cap = ES.SessionCap(2)
    app = cap.gate(lambda: built.append(1) or "app", lambda: "too many")
    shown = []
    for doc in docs[:4]:
        with set_curdoc(doc):
            shown.append(app())
    assert shown == ["app", "app", "too many", "too many"] and len(built) == 2
    for callback in docs[0].session_destroyed_callbacks:   # what Bokeh calls at the end
        callback(None)
    with set_curdoc(docs[4]):
        assert app() == "app"                         # a session ended: room for one


def test_the_server_listens_on_loopback_with_restricted_websocket_origins(monkeypatch):
    from bokeh.settings import settings
    from tornado.httpclient import AsyncHTTPClient

    from mtaccuracy.apps import explore

    monkeypatch.setenv("BOKEH_ALLOW_WS_ORIGIN", "evil.example:80")   # must not replace ours
    previous = signal.getsignal(signal.SIGINT)
    server, url = explore.serve(port=0)
    try:
        signal.signal(signal.SIGINT, previous)         # pn.serve installs its own handler
        port = server.port
        base, token = url.split("?token=")
        assert base == f"http://127.0.0.1:{port}/" and server.address == "127.0.0.1"
        assert len(token) == 32 and server._tornado.auth_provider.token == token
        assert server._tornado.websocket_origins == {f"127.0.0.1:{port}", f"localhost:{port}"}
        assert settings.allowed_ws_origin() == []     # Bokeh uses the server's own list
        with socket.create_connection(("127.0.0.1", port), timeout=5):
            pass                                       # listening on the loopback address
        server.start()

        async def get(path, **headers):
            return await AsyncHTTPClient().fetch(base + path, raise_error=False,
                                                 follow_redirects=False, headers=headers)
        no, bad = (server.io_loop.run_sync(lambda p=p: get(p), timeout=30)
                   for p in ("", "?token=" + "x" * 32))
        assert no.code == bad.code == 302 and "token-required" in no.headers["Location"]
        page = server.io_loop.run_sync(lambda: get(f"?token={token}"), timeout=60)
        assert page.code == 200 and b"mtaccuracy explorer" in page.body
        cookie = page.headers["Set-Cookie"]
        assert f"mtaccuracy_explore_{port}={token}" in cookie and "HttpOnly" in cookie
        assert "SameSite=Strict" in cookie
    finally:
        server.unlisten()
        server.stop()
        signal.signal(signal.SIGINT, previous)


# ------------------------------------------------------------------------------------------
# Issue 35: bounds on the server, every tie, typed poses, CSV export
# ------------------------------------------------------------------------------------------

@pytest.mark.parametrize("value, why", [
    (None, "is empty"), ("", "is empty"), ("12", "must be a number"), (True, "must be a number"),
    (float("nan"), "NaN"), (float("1e999"), "infinite"), (-float("inf"), "infinite"),
    (101.0, "out of bounds"), (2.5, "whole number")])
def test_a_refused_value_names_the_control_and_its_bounds(value, why):
    with pytest.raises(ValueError, match=why) as err:
        M.checked_number(value, "the highest harmonic", low=3, high=100, integer=True)
    assert "the highest harmonic" in str(err.value) and "3 to 100" in str(err.value)
    assert M.checked_number(np.int64(7), "k", low=3, high=100, integer=True) == 7
    assert M.checked_number(359.99, "a", low=0, high=360, high_open=True) == 359.99
    with pytest.raises(ValueError, match="out of bounds"):
        M.checked_number(360, "a", low=0, high=360, high_open=True)


def test_the_model_refuses_every_out_of_bounds_input_before_any_work(setups, monkeypatch):
    from mtaccuracy import spindle as SP

    def forbidden(*a, **k):
        raise AssertionError("work done on a refused input")
    monkeypatch.setattr(SP, "noise_amplification", forbidden)
    with pytest.raises(ValueError, match="the highest harmonic = 20000 is out of bounds"):
        M.probe_transfer([0, 90, 180, 270], max_harmonic=20000)
    with pytest.raises(ValueError, match="probe 2 angle = 1e\\+09 is out of bounds"):
        M.probe_transfer([0, 1e9, 180, 270])
    for bad in (None, float("nan"), float("1e999")):
        with pytest.raises(ValueError, match="probe 3 angle"):
            M.probe_transfer([0, 90, bad, 270])
    with pytest.raises(ValueError, match="a3"):
        M.probe_transfer([0, 90, 180, 270], weights="eq5", a3=float("nan"))
    z = setups["ac_double_turntable"]
    monkeypatch.setattr(type(z.machine), "jacobian", forbidden)
    for values, kw, what in (({"x": 1e9}, {}, "axis x"), ({"A": float("nan")}, {}, "axis A"),
                             ({"y": None}, {}, "axis y is empty"),
                             ({}, {"position_um": float("1e999")}, "position-error"),
                             ({}, {"angular_arcsec": 0.0}, "angular-error")):
        with pytest.raises(ValueError, match=what):
            M.slider_update(z, values, **kw)
    with pytest.raises(ValueError, match="grid steps"):
        M.dominant_map(z, steps=10_000)
    with pytest.raises(ValueError, match="at most 80 characters"):
        M.topology_setup("w " + "X " * 10_000 + "t")


def test_probes_are_numbered_from_1_as_in_the_controls():
    with pytest.raises(ValueError, match="probes 2 and 3 are at the same angle"):
        M.probe_transfer([0, 90, 90, 200])
    with pytest.raises(ValueError, match="probes 1 and 4 are at the same angle"):
        M.probe_transfer([0, 90, 200, 0.0])
    with pytest.raises(ValueError, match="probes 2 and 3 are coincident or opposite.*probe 3"):
        M.probe_transfer([0, 30, 210, 300], weights="eq5")


def _planar_indices(arms, sd) -> M.PoseIndices:
    """A tip Px = sum_i arm_i * e_i (pitch errors e_i on Abbe arms arm_i, mm): closed form."""
    jac = np.array(arms, dtype=float)[None, None, :]                       # (1, 1, d)
    idx = S.linear_indices(jac, sd=np.asarray(sd, dtype=float))[0]        # (d, 1)
    return M.PoseIndices(idx, np.array([True]), [f"e{i + 1}" for i in range(len(arms))], ["Px"])


def test_every_tied_error_is_shown_and_only_ties():
    """Arms 0.1 + 0.2 and 0.3 mm are equal but for rounding (5.6e-17): a tie; an arm
    1e-7 longer is a real difference (2e-7 of the index), not a tie; catalogue order."""
    arm = 0.1 + 0.2
    assert arm != 0.3                                       # rounding makes them differ
    r = _planar_indices([0.3, 0.1, arm, 0.3 * (1 - 1e-7), 0.3], sd=[1.0] * 5)
    (out, errs, index), = M.top_errors(r)
    assert (out, errs) == ("Px", ("e1", "e3", "e5"))
    assert index == pytest.approx(0.09 / (4 * 0.09 + 0.01 - 0.18e-7), rel=1e-12)
    # the same model with e3's range 1e-6 larger: it alone is the top
    r = _planar_indices([0.3, 0.1, arm, 0.3 * (1 - 1e-7), 0.3], sd=[1, 1, 1 + 1e-6, 1, 1])
    assert M.top_errors(r)[0][1] == ("e3",)


#: The eight errors tied at 0.125 for Vx at test point 2 (issue 35), in catalogue order.
VX_TIES = ("e_xx", "e_xy", "e_xz", "e_xa", "e_yc", "S_yz", "a_AM", "b_CA")


def test_vx_at_test_point_2_shows_its_eight_ties(setups):
    """The issue's case: notebook 01's test point 2, Vx: eight errors at 0.125."""
    z = setups["ac_double_turntable"]
    r = M.indices_at_pose(z, dict(x=-200.0, y=-212.5, z=-137.5, A=-65.0, C=90.0))
    top = {o: (e, v) for o, e, v in M.top_errors(r)}
    assert top["Vx"][0] == VX_TIES == tuple(sorted(VX_TIES, key=z.names.index))  # catalogue
    assert top["Vx"][1] == pytest.approx(0.125, abs=1e-12)
    table = M.top_errors_table(r)
    assert (table.output == "Vx").sum() == 8 and len(table) == sum(len(e) for e, _ in top.values())


def test_the_csv_exports_round_trip_at_full_precision(setups):
    import io

    r = M.indices_at_pose(setups["vertical_xyfz"], dict(x=10.0, y=20.0, z=300.0))
    for frame in (M.top_errors_table(r), M.indices_table(r)):
        back = pd.read_csv(io.StringIO(M.to_csv(frame)))
        pd.testing.assert_frame_equal(back, frame, check_exact=True, check_dtype=False)
    assert list(M.indices_table(r).columns) == ["error", *r.outputs]
    t = M.probe_transfer(np.arange(4) * 90.0, max_harmonic=12)
    back = pd.read_csv(io.StringIO(M.to_csv(M.probe_table(t))))
    assert np.array_equal(back.q_weighted, t.q_weighted)                  # inf: cancelled
    assert back.k.tolist() == list(range(2, 13)) and back.cancelled_by_layout.dtype == bool


def test_the_thermal_csv_is_the_prediction_shown(thermal_data):
    r = M.thermal_prediction(thermal_data, train=[1, 2, 3], test=4)
    table = M.thermal_table(r)
    n, p = r.measured.shape
    assert len(table) == n * p
    assert np.array_equal(table.residual_um.to_numpy().reshape(n, p), r.measured - r.predicted)
    assert np.array_equal(table.position_mm.to_numpy()[:p], r.positions_mm)


def _widgets(view, cls, name=None):
    import panel as pn

    return [w for w in view.select(getattr(pn.widgets, cls)) if name is None or w.name == name]


def test_crafted_messages_are_refused_by_the_server_with_a_message(caplog):
    """What the page sends goes through Panel's _process_events, as a websocket message."""
    from mtaccuracy.apps import explore

    app = explore.create_app()
    spindle, machine = app.tabs["spindle"], app.tabs["machine"]
    sv, mv = spindle.view(), machine.view()
    k = _widgets(sv, "IntSlider", "highest harmonic")[0]
    angle = _widgets(sv, "FloatInput")[0]                                 # probe 2's box
    before = (spindle.max_harmonic, spindle.probe2)
    with caplog.at_level("ERROR"):
        k._process_events({"value": 20000})
        assert "highest harmonic = 20000 is out of bounds" in spindle.refused
        for bad, why in ((None, "empty"), (float("1e999"), "infinite"), (float("nan"), "NaN"),
                         (1e9, "out of bounds")):
            angle._process_events({"value": bad})
            assert "probe 2 angle" in spindle.refused and why in spindle.refused
        assert (spindle.max_harmonic, spindle.probe2) == before
        angle._process_events({"value": 123.4})                            # a good one
        assert spindle.probe2 == 123.4 and spindle.refused == ""
        y = _widgets(mv, "FloatInput")[1]                                  # axis y's box
        y._process_events({"value": -1e9})
        assert "axis y" in machine.refused and machine.pose.y != -1e9
        _widgets(mv, "Select", "output")[0]._process_events({"value": "<script>"})
        assert "is not one of" in machine.refused and machine.output in machine.setup.outputs
        _widgets(mv, "TextInput")[0]._process_events({"value": "X" * 100_000})
        assert "at most 80 characters" in machine.refused
        radio = _widgets(sv, "RadioButtonGroup")[0]
        radio._process_events({"active": 7})
        assert "is not a choice" in spindle.refused
    assert not [r for r in caplog.records if r.levelname == "ERROR"], caplog.text


def test_a_typed_pose_reaches_what_a_slider_cannot():
    """Test point 2's y = -212.5 mm is off the 1 mm steps of the slider: typed, it is shown."""
    from mtaccuracy.apps import explore

    app = explore.create_app()
    tab = app.tabs["machine"]
    mv = tab.view()
    boxes = {w.css_classes[0]: w for w in _widgets(mv, "FloatInput")}
    sliders = {w.css_classes[0]: w for w in _widgets(mv, "FloatSlider") if w.css_classes}
    for a in tab.setup.axes:                                # the same bounds as the slider
        box, slider = boxes[f"pose-{a.name}-input"], sliders[f"pose-{a.name}"]
        assert (box.start, box.end) == (slider.start, slider.end) == (a.low, a.high)
    for name, value in dict(x=-200.0, y=-212.5, z=-137.5, A=-65.0, C=90.0).items():
        boxes[f"pose-{name}-input"]._process_events({"value": value})
    assert tab.pose_values()["y"] == -212.5 and sliders["pose-y"].value == -212.5
    shown = _shown_top(tab)
    assert shown["Vx"][0] == ", ".join(VX_TIES)
    assert "(8 tied)" in tab.top.object
    _check_machine_tab_shows_the_model(tab)
    csv = [w for w in _widgets(mv, "FileDownload") if w.filename == "top_errors.csv"][0]
    back = pd.read_csv(csv.callback())
    assert back[back.output == "Vx"].error.tolist() == shown["Vx"][0].split(", ")
