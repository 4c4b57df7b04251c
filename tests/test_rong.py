"""Notebook 02 (Rong et al.), issue 24: the ranking precision of the 90 % rule (ties broken in
catalogue order, the saved table in the rule's order), the ranges of Zheng 2024 as a second
defensible set, the study between two range sets, and the bracket scoring."""

import numpy as np
import pandas as pd
import pytest

from mtaccuracy import errors
from mtaccuracy import sensitivity as S
from mtaccuracy.compendium import reproduction, rong
from mtaccuracy.machines import build
from mtaccuracy.machines import horizontal_3axis as h3

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
    ks = S.key_errors(r[:, 0], NAMES, 0.9)
    assert ks.names[:2] == (NAMES[11], NAMES[10])
    assert NAMES[5] in ks.names and NAMES[7] not in ks.names   # catalogue order, not the 4e-10
    # unrounded, the rule would have taken dx(z): the case the ranking exists for
    assert NAMES[7] in S.key_errors(st[:, 0], NAMES, 0.9).names


def test_ranked_values_survive_the_saved_table(tmp_path):
    # what the rule ranks is what save_table writes: sorting the file gives the rule's order
    rng = np.random.default_rng(4)
    st = rng.uniform(0, 0.2, (D, 3))
    st[7] = st[5] + 3e-10                       # an exchangeable pair, split by noise
    r = rong.ranked(st)
    path = tmp_path / "t.csv"
    df = pd.DataFrame({"symbol": np.repeat([NAMES], 3, 0).ravel(),
                       "output": np.repeat([0, 1, 2], D), "ST": r.T.ravel()})
    reproduction.save_table(df, path)
    back = pd.read_csv(path)
    for k in range(3):
        d = back[back.output == k].sort_values("ST", ascending=False, kind="stable")
        ks = S.key_errors(r[:, k], NAMES, 0.9)
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
    ua, _ = S.base_samples(n, D + 3, "sobol", seed)
    return ua


def test_range_path_ends_match_an_independent_grid_formulation():
    # the workspace-pooled indices by brute force: mean of squared Jacobians over a dense pose grid
    hz = rong.half_widths_from_ranges(MACHINE.catalogue, 0.015, 10 * ARCSEC)
    path = rong.range_path_study(MACHINE, BORROWED, hz, [0.0, 1.0], unit_rows=_unit_rows(),
                                 workspace_mm=WORKSPACE, tool=TOOL, threshold=0.9)
    g = [np.linspace(0, v, 9)[:-1] + v / 16 for v in WORKSPACE]        # 8 midpoints per axis
    pts = [c.ravel() for c in np.meshgrid(*g, indexing="ij")]
    jac = MACHINE.first_order_jacobian(dict(zip("xyz", pts, strict=True), **TOOL))[:, :3]
    for h, row in zip((BORROWED, hz), path.itertuples(), strict=True):
        v = (jac ** 2).mean(0) * (h ** 2 / 3)                          # (3, D): E[J^2] var
        st = (v / v.sum(1, keepdims=True)).T
        sets = S.key_errors_by_output(rong.ranked(st, 4), NAMES, ["Ex", "Ey", "Ez"], 0.9)
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
    _, st = h3.linear_sobol_indices(MACHINE, np.vstack([-BORROWED, BORROWED]), pose=TOOL,
                                    pose_bounds=BOX)
    r = rong.ranked(st)
    i, j = NAMES.index("dx(y)"), NAMES.index("dx(z)")
    assert r[i, 0] == r[j, 0] > 0
    sets = S.key_errors_by_output(r, NAMES, ["Ex", "Ey", "Ez"], 0.9)
    assert "dx(y)" in sets["Ex"].names and "dx(z)" not in sets["Ex"].names
    assert "dy(x)" in sets["Ey"].names and "dy(z)" not in sets["Ey"].names
