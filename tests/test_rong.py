"""Notebook 02 (Rong et al.), issue 24: the ranking precision of the 90 % rule (ties broken in
catalogue order, the saved table in the rule's order), the ranges of Zheng 2024 as a second
defensible set, the study between two range sets, and the bracket scoring; the closed-form
indices of the linearised model, the study's models and the tool lengths; issue 32: the sweep
grids (one rule for the parameter check and the sweep), the declared parameters' checks and the
figures' captions."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from mtaccuracy import errors
from mtaccuracy import sensitivity as S
from mtaccuracy.compendium import reproduction
from mtaccuracy.machines import build
from mtaccuracy.papers import parameters, rong

ROOT = Path(__file__).resolve().parents[1]

MACHINE = build("horizontal_3axis", layout="z/xy")
NAMES = MACHINE.error_names
D = MACHINE.n_errors
TOOL = {"tool_x": 0.0, "tool_y": 0.0, "tool_z": 0.0}
WORKSPACE = [700.0, 600.0, 500.0]
BOX = {a: (0.0, v) for a, v in zip("xyz", WORKSPACE, strict=True)}
ARCSEC = errors.UNIT_SCALE["arcsec"]
KIND = {e.symbol: e.kind for e in MACHINE.catalogue}
# 2 x the acceptance values of data/rong (mm, rad): positioning, straightness, angular, squareness
BORROWED = np.array([{"positioning": 0.0075, "straightness": 0.01, "angular": 8e-5,
                      "squareness": 4.75e-6}[KIND[s]] for s in NAMES])


def test_ranked_ties_sampling_noise_in_catalogue_order_keeps_real_differences():
    # dx(y) (index 5) and dx(z) (index 7) as a Sobol' estimate gives them: 4e-10 apart
    st = np.zeros((D, 1))
    st[[5, 7], 0] = 0.060000000104, 0.060000000471
    st[11, 0] = 0.45
    st[10, 0] = 0.45 - 2e-6                     # a real difference of 2e-6 stays one
    r = rong.ranked(st)
    assert r[5, 0] == r[7, 0] and r[11, 0] > r[10, 0]
    ks = S.key_errors(r[:, 0], names=NAMES, threshold=0.9)
    assert ks.names[:2] == (NAMES[11], NAMES[10])
    assert NAMES[5] in ks.names and NAMES[7] not in ks.names   # catalogue order, not the 4e-10
    # unrounded, the rule would have taken dx(z): the case the ranking exists for
    assert NAMES[7] in S.key_errors(st[:, 0], names=NAMES, threshold=0.9).names


def test_ranked_values_survive_the_saved_table(tmp_path):
    # what the rule ranks is what save_table writes: sorting the file gives the rule's order
    rng = np.random.default_rng(4)
    st = rng.uniform(0, 0.2, (D, 3))
    st[7] = st[5] + 3e-10                       # an exchangeable pair, split by noise
    r = rong.ranked(st)
    path = tmp_path / "t.csv"
    df = pd.DataFrame({"symbol": np.repeat([NAMES], 3, 0).ravel(),
                       "output": np.repeat([0, 1, 2], D), "ST": r.T.ravel()})
    reproduction.write_table(df, path)
    back = pd.read_csv(path)
    for k in range(3):
        d = back[back.output == k].sort_values("ST", ascending=False, kind="stable")
        ks = S.key_errors(r[:, k], names=NAMES, threshold=0.9)
        assert tuple(d.symbol[:ks.n_key]) == ks.names
        assert np.array_equal(d.ST.to_numpy(), np.sort(r[:, k])[::-1])


def test_half_widths_from_ranges_split_translational_and_angular():
    h = rong.half_widths_from_ranges(MACHINE.catalogue, 0.015, 10 * ARCSEC)
    assert h.shape == (D,)
    for s, v in zip(NAMES, h, strict=True):
        want = 0.015 if KIND[s] in ("positioning", "straightness") else 10 * ARCSEC
        assert v == want, s                     # squareness is angular, as in Zheng 2024
    with pytest.raises(ValueError, match="> 0"):
        rong.half_widths_from_ranges(MACHINE.catalogue, 0.0, ARCSEC)


def _unit_rows(n=512, seed=3):
    ua, _ = S.base_samples(n, D + 3, method="sobol", seed=seed)
    return ua


def test_range_path_ends_match_an_independent_grid_formulation():
    # the workspace-pooled indices by brute force: mean of squared Jacobians over a dense pose grid
    hz = rong.half_widths_from_ranges(MACHINE.catalogue, 0.015, 10 * ARCSEC)
    path = rong.range_path_study(MACHINE, BORROWED, hz, [0.0, 1.0], unit_rows=_unit_rows(),
                                 workspace_mm=WORKSPACE, tool=TOOL, threshold=0.9)
    g = [np.linspace(0, v, 9)[:-1] + v / 16 for v in WORKSPACE]        # 8 midpoints per axis
    pts = [c.ravel() for c in np.meshgrid(*g, indexing="ij")]
    jac = MACHINE.jacobian(dict(zip("xyz", pts, strict=True), **TOOL))[:, :3]
    for h, row in zip((BORROWED, hz), path.itertuples(), strict=True):
        v = (jac ** 2).mean(0) * (h ** 2 / 3)                          # (3, D): E[J^2] var
        st = (v / v.sum(1, keepdims=True)).T
        sets = S.key_errors_by_output(rong.ranked(st, 4), names=NAMES, outputs=["Ex", "Ey", "Ez"],
                                      threshold=0.9)
        u = S.union_key_set(sets, NAMES)
        assert row.n_key == len(u)
    # the two sourced ends of notebook 02: 7 and 17 key errors
    assert list(path.n_key) == [7, 17]
    assert path.simplification_rate.tolist() == pytest.approx([14 / 21, 4 / 21])


def test_range_path_scale_free_and_reduced_model_consistent():
    hz = rong.half_widths_from_ranges(MACHINE.catalogue, 0.015, 10 * ARCSEC)
    kw = dict(unit_rows=_unit_rows(), workspace_mm=WORKSPACE, tool=TOOL, threshold=0.9)
    a = rong.range_path_study(MACHINE, BORROWED, hz, [0.0, 0.5, 1.0], **kw)
    b = rong.range_path_study(MACHINE, 3 * BORROWED, 3 * hz, [0.0, 0.5, 1.0], **kw)
    # a common factor on every range changes no count and no ratio; the millimetres scale by it
    assert list(a.n_key) == list(b.n_key) and list(a.key_errors) == list(b.key_errors)
    assert b.residual_relative[:2].to_numpy() == pytest.approx(
        a.residual_relative[:2].to_numpy(), rel=1e-3)
    assert b.full_maxabs_mm.to_numpy() == pytest.approx(3 * a.full_maxabs_mm.to_numpy(), rel=1e-3)
    # at Zheng's ranges every error that moves the tip is key: only the second-order residual is
    # left, which grows with the factor (relative to a first-order full model)
    assert a.residual_relative.iloc[-1] < 1e-3 < a.residual_relative.iloc[0]
    assert b.residual_relative.iloc[-1] == pytest.approx(3 * a.residual_relative.iloc[-1], rel=0.02)
    # the geometric midpoint: half-widths sqrt(a b)
    c = rong.range_path_study(MACHINE, np.sqrt(BORROWED * hz), hz, [0.0], **kw)
    assert c.n_key[0] == a.n_key[1] and c.key_errors[0] == a.key_errors[1]


def test_range_path_refuses_bad_inputs():
    kw = dict(unit_rows=_unit_rows(64), workspace_mm=WORKSPACE, tool=TOOL, threshold=0.9)
    with pytest.raises(ValueError, match="positive"):
        rong.range_path_study(MACHINE, BORROWED, -BORROWED, [0.0], **kw)
    with pytest.raises(ValueError, match="unit_rows"):
        rong.range_path_study(MACHINE, BORROWED, BORROWED, [0.0],
                              **{**kw, "unit_rows": _unit_rows(64)[:, :D]})


def test_exact_indices_tie_exchangeable_pairs_and_ranked_keeps_the_catalogue_member():
    _, st = rong.linear_sobol_indices(MACHINE, np.vstack([-BORROWED, BORROWED]), pose=TOOL,
                                      pose_bounds=BOX)
    r = rong.ranked(st)
    i, j = NAMES.index("dx(y)"), NAMES.index("dx(z)")
    assert r[i, 0] == r[j, 0] > 0
    sets = S.key_errors_by_output(r, names=NAMES, outputs=["Ex", "Ey", "Ez"], threshold=0.9)
    assert "dx(y)" in sets["Ex"].names and "dx(z)" not in sets["Ex"].names
    assert "dy(x)" in sets["Ey"].names and "dy(z)" not in sets["Ey"].names


def test_linear_indices_are_exact_shares_of_variance():
    b = np.vstack([-BORROWED, BORROWED])
    s1, st = rong.linear_sobol_indices(MACHINE, b, pose=dict(x=700.0, y=600.0, z=500.0))
    assert np.allclose(s1, st) and np.allclose(st.sum(0), 1.0)
    c = MACHINE.jacobian(dict(x=700.0, y=600.0, z=500.0))[0][:3]
    v = c**2 * BORROWED**2 / 3
    assert np.allclose(st, (v / v.sum(1, keepdims=True)).T)
    # pose uniform in a box: total >= first order, both sum as they must
    s1, st = rong.linear_sobol_indices(MACHINE, b, pose_bounds=BOX)
    assert np.all(st >= s1 - 1e-15) and np.allclose(st.sum(0), 1.0) and np.all(s1.sum(0) < 1)
    # exact: the coefficients are affine in the pose, c = c0 + sum_k g_k (p_k - centre_k), so
    # E[c^2] = c0^2 + sum_k g_k^2 L_k^2 / 12 for a uniform pose
    centre, lengths = dict(x=350.0, y=300.0, z=250.0), dict(x=700.0, y=600.0, z=500.0)
    c0 = MACHINE.jacobian(centre)[0][:3]
    ec2 = c0**2
    for k in "xyz":
        def coef(pose):
            return MACHINE.jacobian(pose)[0]
        g = coef(dict(centre, **{k: centre[k] + 100.0}))[:3] - c0
        back = coef(dict(centre, **{k: centre[k] - 250.0}))[:3] - c0
        assert np.allclose(back, -2.5 * g, atol=1e-5)  # affine in the pose
        ec2 = ec2 + (g / 100.0) ** 2 * lengths[k] ** 2 / 12
    v = ec2 * BORROWED**2 / 3
    assert np.allclose(st, (v / v.sum(1, keepdims=True)).T, atol=1e-9)
    assert np.allclose(s1, (c0**2 * BORROWED**2 / 3 / v.sum(1, keepdims=True)).T, atol=1e-9)


def test_linear_indices_at_poses_equal_one_pose_at_a_time_and_tie_exactly():
    b = np.vstack([-BORROWED, BORROWED])
    poses = dict(x=np.array([0.0, 175.0, 700.0]), y=np.array([0.0, 450.0, 600.0]),
                 z=np.array([0.0, 125.0, 500.0]))
    many = rong.linear_indices_at_poses(MACHINE, b, poses=poses)
    assert many.shape == (3, 21, 3)
    for i in range(3):
        _, st = rong.linear_sobol_indices(MACHINE, b, pose={k: v[i] for k, v in poses.items()})
        assert np.allclose(many[i], st, rtol=1e-14, atol=0)
    # exchangeable errors (coefficient +-1, same range) get the same index to the bit
    assert many[1, NAMES.index("dx(y)"), 0] == many[1, NAMES.index("dx(z)"), 0]
    assert many[1, NAMES.index("dz(x)"), 2] == many[1, NAMES.index("dz(y)"), 2]


def test_a_coincidental_tie_is_broken_by_catalogue_order():
    """At z = 125 mm the Abbe term of ey(z) (125 mm x 80 urad = 10 um) equals the straightness
    range of dx(y) and dx(z): three tied indices in Ex, of which the 90 % rule needs one.  The
    tie is decided by catalogue order (dx(y) first), not by the last bit of the arithmetic."""
    b = np.vstack([-BORROWED, BORROWED])
    st = rong.linear_indices_at_poses(MACHINE, b, poses=dict(x=175.0, y=450.0, z=125.0))[0]
    j = [NAMES.index(s) for s in ("ey(z)", "dx(y)", "dx(z)")]
    assert np.ptp(st[j, 0]) < 1e-15 * st[j, 0].max()  # equal up to rounding
    keys = S.key_errors_by_output(S.merge_ties(st), names=NAMES, outputs=["Ex", "Ey", "Ez"],
                                  threshold=0.9)
    assert keys["Ex"].names == ("ez(x)", "ez(z)", "dx(y)")
    # whichever of the three the rounding favours, the answer is the same
    for winner in j:
        nudged = st.copy()
        nudged[winner, 0] *= 1 + 4e-16
        again = S.key_errors_by_output(S.merge_ties(nudged), names=NAMES,
                                       outputs=["Ex", "Ey", "Ez"], threshold=0.9)
        assert again["Ex"].names == keys["Ex"].names


def test_tool_length_sweep_is_batched_and_gives_the_last_tool_axis_an_arm():
    """Batched over tool lengths: bitwise equal to one case at a time; the variance is the
    pooled one (S_T = share of it); a tool of length L along -z gives the roll ex(y) of the
    Y headstock the coefficient +L in Ey at every pose (eps x s = e_x x (0, 0, -L)), while
    ez(y) (about the spindle axis) still cannot move the tip."""
    b = np.vstack([-BORROWED, BORROWED])
    box = dict(x=(0, 700), y=(0, 600), z=(0, 500))
    lengths = np.array([0.0, 50.0, 200.0])
    tools = rong.tool_length_offsets(lengths, base=(0.0, 0.0, 0.0))
    assert np.array_equal(tools["tool_z"], -lengths) and np.all(tools["tool_x"] == 0)
    s1, st, v = rong.linear_sobol_indices_batch(MACHINE, b, poses=dict(tools), pose_bounds=box)
    assert s1.shape == st.shape == (3, 21, 3) and v.shape == (3, 3)
    for i in range(3):
        one = {k: t[i] for k, t in tools.items()}
        one_s1, one_st = rong.linear_sobol_indices(MACHINE, b, pose=one, pose_bounds=box)
        assert np.array_equal(one_s1, s1[i]) and np.array_equal(one_st, st[i])
    j_ex, j_ez = NAMES.index("ex(y)"), NAMES.index("ez(y)")
    var_angle = BORROWED[j_ex] ** 2 / 3
    assert np.allclose(st[:, j_ex, 1], lengths**2 * var_angle / v[:, 1], rtol=1e-12)
    assert st[0, j_ex, 1] == 0 and st[2, j_ex, 1] > 0.1
    assert np.all(st[:, j_ez] == 0)
    # the variance is that of the first-order model with the pose uniform in the box
    rng = np.random.default_rng(1)
    n = 200_000
    p = {k: rng.uniform(lo, hi, n) for k, (lo, hi) in box.items()}
    c = MACHINE.jacobian(dict(p, tool_x=0.0, tool_y=0.0, tool_z=-200.0))[:, :3]
    e = rng.uniform(-1, 1, (n, 21)) * BORROWED
    y = np.einsum("nqj,nj->nq", c, e)
    assert np.allclose(y.var(0), v[2], rtol=0.02)
    with pytest.raises(ValueError, match=">= 0"):
        rong.tool_length_offsets([-5.0])
    with pytest.raises(ValueError, match="different lengths"):
        rong.linear_sobol_indices_batch(MACHINE, b, poses=dict(tools, tool_x=np.zeros(2)),
                                        pose_bounds=box)
    with pytest.raises(ValueError, match="one pose"):
        rong.linear_sobol_indices(MACHINE, b, pose=dict(tools), pose_bounds=box)


def test_linear_indices_refuse_bad_ranges_and_poses():
    with pytest.raises(ValueError, match="high > low"):
        rong.linear_sobol_indices(MACHINE, np.zeros((2, 21)), pose=TOOL)
    with pytest.raises(ValueError, match="lacks axis"):
        rong.linear_sobol_indices(MACHINE, np.vstack([-BORROWED, BORROWED]), pose=dict(x=0.0))
    with pytest.raises(TypeError):             # keyword-only after the data
        rong.linear_sobol_indices(MACHINE, np.vstack([-BORROWED, BORROWED]), TOOL)


def test_the_study_models_are_the_machines_position_error_with_the_pose_as_inputs():
    rng = np.random.default_rng(8)
    e = rng.uniform(-1, 1, (6, D)) * BORROWED
    xyz = rng.uniform(0, 500, (6, 3))
    tool = dict(tool_x=1.0, tool_y=-2.0, tool_z=-50.0)
    want = MACHINE.position_error(e, dict(x=xyz[:, 0], y=xyz[:, 1], z=xyz[:, 2], **tool))
    assert np.array_equal(rong.errors_and_pose_model(MACHINE, tool)(np.c_[e, xyz]), want)
    assert np.array_equal(rong.errors_at_poses_model(MACHINE, xyz, tool)(e), want)


def test_range_bracket_figure_draws_the_path_its_ends_and_the_published_values():
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path = pd.DataFrame({"t": [0.0, 0.5, 1.0], "n_key_Ex": [4, 5, 6], "n_key_Ey": [3, 3, 5],
                         "n_key_Ez": [2, 4, 4], "n_key": [8, 11, 17],
                         "residual_relative": [0.25, 0.1, 0.0]})
    fig = rong.range_bracket_figure(path, outputs=["Ex", "Ey", "Ez"], n_key_pub=12,
                                    n_kept_by_rate=11, rate_pub=48.0, residual_mm_pub=0.05,
                                    full_mm_pub=0.25, residual_pct_text="15", threshold=0.9,
                                    published_colour="r", reproduced_colour="g")
    try:
        ax0, ax1 = fig.axes
        lines0 = {ln.get_label(): ln for ln in ax0.get_lines()}
        assert np.array_equal(lines0["union"].get_ydata(), path.n_key)
        assert np.array_equal(lines0["Ey"].get_ydata(), path.n_key_Ey)
        # the two sourced sets are the path's ends, annotated with their counts
        ends = lines0["the two sourced sets"]
        assert list(ends.get_xdata()) == [0.0, 1.0] and list(ends.get_ydata()) == [8, 17]
        assert [a.get_text() for a in ax0.texts] == ["8", "17"]
        assert list(lines0["published: 12"].get_ydata()) == [12, 12]
        assert list(lines0["implied by the published 48 %: 11"].get_ydata()) == [11, 11]
        lines1 = {ln.get_label(): ln for ln in ax1.get_lines()}
        assert np.allclose(lines1["ours"].get_ydata(), [25.0, 10.0, 0.0])   # in %
        assert np.allclose(lines1["published 0.05 / 0.25 mm"].get_ydata(), 20.0)  # 0.05 / 0.25
        assert np.allclose(lines1["text: within 15 %"].get_ydata(), 15.0)
        assert "90% rule" in fig._suptitle.get_text()
    finally:
        plt.close(fig)


def test_the_sweep_grids_are_the_notebooks_arange_and_never_pass_the_last_value():
    # the defaults: what the notebook swept before the grids were shared with the check
    assert np.array_equal(rong.threshold_grid([0.8, 0.99, 0.01]),
                          np.round(np.arange(0.8, 0.99 + 0.005, 0.01), 10))
    assert np.array_equal(rong.tool_length_grid([0.0, 300.0, 25.0]),
                          np.round(np.arange(0.0, 312.5, 25.0), 9))
    assert len(rong.threshold_grid([0.5, 0.99, 0.01])) == 50
    assert list(rong.threshold_grid([0.9, 0.9, 0.05])) == [0.9]
    # a step that does not divide the span: arange would pass last (0.8, 0.92, 1.04 > 1)
    assert list(rong.threshold_grid([0.8, 0.99, 0.12])) == [0.8, 0.92]
    assert list(rong.tool_length_grid([0.0, 100.0, 35.0])) == [0.0, 35.0, 70.0]
    assert len(rong.tool_length_grid([0.0, 995.0, 5.0])) == rong.MAX_SWEEP


@pytest.mark.parametrize("grid, value, message", [
    (rong.threshold_grid, [0.9, 0.5, 0.01], r"0 < first <= last < 1, step > 0"),
    (rong.threshold_grid, [0.0, 0.5, 0.01], r"0 < first <= last < 1, step > 0"),
    (rong.threshold_grid, [0.01, 0.99, 0.001], "gives 981 thresholds; at most 200"),
    (rong.tool_length_grid, [300.0, 0.0, 10.0], "first <= last and step > 0"),
    (rong.tool_length_grid, [0.0, 300.0, 0.0], "first <= last and step > 0"),
    (rong.tool_length_grid, [0.0, 300.0, 1.0], "gives 301 tool lengths; at most 200"),
])
def test_the_sweep_grids_refuse_with_a_clear_message(grid, value, message):
    with pytest.raises(ValueError, match=message):
        grid(value)


GOOD = dict(workspace_mm=[800, 700, 600], tool_offset_mm=[0, 0, 100],
            sweep_thresholds=[0.5, 0.99, 0.01], tool_lengths_mm=[0, 300, 10], n_plot=100,
            n_base=1000)


def test_the_declared_parameters_accept_the_defaults_and_good_values():
    assert parameters.check(rong.Parameters, {}).n_base == 8192
    filled = parameters.check(rong.Parameters, GOOD)
    assert len(rong.threshold_grid(filled.sweep_thresholds)) == 50


@pytest.mark.parametrize("change, message", [
    (dict(workspace_mm=[800, 700]), "workspace_mm"),
    (dict(sweep_thresholds=[0.9, 0.5, 0.01]), r"0 < first <= last < 1, step > 0"),
    (dict(tool_lengths_mm=[0, 300, 1]), "gives 301 tool lengths; at most 200"),
    (dict(tool_lengths_mm=[300, 0, 10]), "first <= last and step > 0"),
    (dict(n_plot=2000), "n_plot = 2000 must be at most n_base = 1000"),
    (dict(sweep_thresholds=[0.01, 0.99, 0.001]), "gives 981 thresholds; at most 200"),
])
def test_the_declared_parameters_refuse_what_the_notebook_cannot_run(change, message):
    with pytest.raises(parameters.ParameterError, match=message) as err:
        parameters.check(rong.Parameters, {**GOOD, **change})
    assert str(err.value).startswith("02_rong_sobol_21_errors: ")


def test_leading_errors_name_the_largest_indices_by_kind_with_their_ties():
    sob = pd.DataFrame({"output": ["Ey"] * 6 + ["Ex"],
                        "symbol": ["dy(x)", "dy(z)", "ez(z)", "ex(z)", "dy(y)", "S_yz", "ez(x)"],
                        "kind": ["straightness"] * 2 + ["angular"] * 2 + ["positioning",
                                                                          "squareness", "angular"],
                        "ST": [0.054407, 0.054407, 0.568732, 0.29016, 0.030604, 0.001, 0.9]})
    assert rong.leading_errors(sob, "Ey") == (
        "the angular errors ez(z), ex(z) (ST 0.57, 0.29), then the straightness errors dy(x), "
        "dy(z) (ST 0.054, 0.054)")                      # dy(z) ties with the third: named too
    assert rong.leading_errors(sob, "Ey", n=1) == "the angular error ez(z) (ST 0.57)"
    assert rong.leading_errors(sob, "Ex", n=3) == "the angular error ez(x) (ST 0.9)"


def test_the_captions_name_every_figure_in_the_books_order_and_fill_every_field():
    names = list(rong.FIGURES)
    assert names[:6] == ["fig02_ex_sobol_indices", "fig03_ey_sobol_indices",
                         "fig04_ez_sobol_indices", "fig05_ex_prediction", "fig06_ey_prediction",
                         "fig07_ez_prediction"]
    assert rong.FIGURES["fig_range_bracket"] is rong.RANGE_BRACKET
    assert rong.FIGURES["fig_tool_offset_key_errors"] is rong.TOOL_LENGTH
    assert {p.stem for p in (ROOT / "figures" / rong.Parameters.stem).glob("*.png")} == set(names)
    filled = rong.FIGURES["fig_pose_dependence"].format(
        n_poses=125, g=5, threshold=90.0, n_min=4, n_max=13, n_pooled=7, n_key_pub=12,
        published_share=4.8)
    assert "125 poses of a 5 × 5 × 5 grid" in filled.text and "12 occurs at 5 %" in filled.text
    assert "{" not in filled.text and filled.label == "Beyond the paper"
