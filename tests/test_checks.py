"""sensitivity.checks: the closed-form atlas and its comparison with sampled indices."""

import numpy as np
import pytest
from scipy import stats

from mtaccuracy import sensitivity as S
from mtaccuracy.machines import build
from mtaccuracy.machines import iso as ISO
from mtaccuracy.machines import readers as R


def test_atlas_table_counts_key_poses_and_dominant_errors_break_ties_by_catalogue():
    # two poses, three errors, one output: indices from a hand-made Jacobian
    jac = np.array([[[1.0, 1.0, 0.5]], [[0.1, 2.0, 0.0]]])             # (P=2, q=1, d=3)
    var = np.ones(3)
    idx = S.indices_at_poses(jac, var=var)                            # (2, 3, 1)
    t = S.atlas_table(idx, names=["a", "b", "c"], outputs=["y"], key_share=0.2)
    assert list(t.symbol) == ["a", "b", "c"]
    assert np.allclose(t.key_share, [0.5, 1.0, 0.0])       # pose 0: 4/9, 4/9, 1/9; pose 1: b only
    assert np.isclose(t.max_index.iloc[1], 4 / 4.01)
    dom = S.dominant_errors(jac, var)
    assert dom[:, 0].tolist() == [0, 1]                               # a = b at pose 0: a first
    with pytest.raises(ValueError, match="key_share must be in"):
        S.atlas_table(idx, names=["a", "b", "c"], outputs=["y"], key_share=1.5)
    with pytest.raises(ValueError, match=r"indices must be \(P, 3, 2\)"):
        S.atlas_table(idx, names=["a", "b", "c"], outputs=["y", "z"], key_share=0.2)


def test_an_output_with_no_first_order_term_is_named_and_has_no_dominant_error():
    m = build("ac_double_turntable")
    sd = np.array([1e-3 if e.translational else 5e-6 for e in m.catalogue])
    pose = dict(x=10.0, y=20.0, z=30.0, A=0.0, C=0.4)   # tool along z: Vz second order
    jac = m.jacobian(pose)
    first = S.first_order_outputs(jac, sd**2)[0]
    assert first.tolist() == [True] * 5 + [False]
    assert S.dominant_errors(jac, sd**2)[0, 5] == -1


def test_sampling_agrees_with_the_closed_form_of_a_linear_model_within_the_allowance():
    jac = np.array([[2.0, 0.5, 1.0, -1.5], [0.3, 1.8, -0.7, 1.1]])
    bounds = np.vstack([-np.ones(4), np.ones(4)])
    checks = [S.sample_at_pose(lambda e: e @ jac.T, jac, bounds=bounds, n=2048, n_boot=100,
                               seed=7 + i) for i in range(2)]
    rows, summary, widen, m = S.compare_with_sampling(checks, names=list("abcd"),
                                                      outputs=["u", "v"])
    z = stats.norm.ppf
    assert m == 16 and widen == pytest.approx(z(1 - 0.025 / 16) / z(0.975))
    assert (summary.largest_ratio_to_allowed <= 1).all()
    assert np.allclose(summary.centred_remainder, 0, atol=1e-12)       # the model is linear
    assert len(rows) == 2 * 2 * 4
    # a closed form that is wrong is caught: swap two errors' indices
    bad = checks[0]
    bad.closed_form = bad.closed_form[[1, 0, 2, 3]]
    _, summary2, _, _ = S.compare_with_sampling([bad], names=list("abcd"), outputs=["u", "v"])
    assert (summary2.largest_ratio_to_allowed > 1).all()


def test_checks_take_keywords_after_the_data_and_refuse_bad_counts():
    jac = np.array([[1.0, 2.0]])
    bounds = np.vstack([-np.ones(2), np.ones(2)])
    with pytest.raises(TypeError):
        S.atlas_table(np.ones((1, 2, 1)), ["a", "b"], ["y"], 0.5)
    with pytest.raises(TypeError):
        S.sample_at_pose(lambda e: e @ jac.T, jac, bounds, 64, 10, 0)
    with pytest.raises(TypeError):
        S.compare_with_sampling([], ["a", "b"], ["y"])
    with pytest.raises(ValueError, match="n_boot must be an integer >= 1, got 0"):
        S.sample_at_pose(lambda e: e @ jac.T, jac, bounds=bounds, n=64, n_boot=0, seed=0)
    with pytest.raises(ValueError, match="n must be an integer >= 2, got 10.5"):
        S.sample_at_pose(lambda e: e @ jac.T, jac, bounds=bounds, n=10.5, n_boot=5, seed=0)
    with pytest.raises(ValueError, match=r"level must be in \(0, 1\)"):
        S.compare_with_sampling([], names=["a"], outputs=["y"], level=1.0)


def test_catalogue_table():
    m = ISO.iso_machine("w b X Y t")
    b = np.vstack([-np.ones(m.n_errors), np.ones(m.n_errors)]) * 1e-3
    t = R.catalogue_table(m, b)
    assert list(t.columns) == ["symbol", "kind", "axis", "enters", "component", "low", "high",
                               "unit"]
    row = t.set_index("symbol").loc["EC0Y"]
    assert row.enters == "squareness (tilts the direction)" and row.component == "C"
    assert row.high == pytest.approx(1000.0) and row.unit == "urad"
    assert t.set_index("symbol").loc["EXX", "high"] == pytest.approx(1.0)
    with pytest.raises(ValueError, match=r"bounds must be \(2, 13\)"):
        R.catalogue_table(m, b[:, :3])
