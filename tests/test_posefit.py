"""The shared pose search (issue 15 item 4): one function for notebook 01's smooth linear
indices and notebook 03's piecewise-constant Spearman coefficients."""

import numpy as np
import pytest

from mtaccuracy import sensitivity as S
from mtaccuracy.machines import build
from mtaccuracy.machines.ac_double_turntable import TRAVELS
from mtaccuracy.papers.zheng2024 import fit_pose_to_indices


def _toy(pose):
    """A smooth statistic of two axes: (B, 2, 3)."""
    a, b = np.asarray(pose["a"], dtype=float), np.asarray(pose["b"], dtype=float)
    return np.stack([np.stack([a, b, a * b], -1), np.stack([a ** 2, np.sin(b), a - b], -1)], 1)


def test_least_squares_recovers_a_known_pose():
    truth = {"a": np.array([1.3]), "b": np.array([-0.4])}
    entries = (np.array([0, 0, 1, 1]), np.array([0, 2, 1, 2]))
    published = _toy(truth)[(slice(None), *entries)][0]
    fits = S.fit_pose(_toy, published, entries, starts=[[0.5, 0.5], [2.0, -1.0]],
                      free=["a", "b"], bounds=([-3, -3], [3, 3]))
    assert list(fits.columns) == ["a", "b", "misfit", "status"]
    assert np.allclose(fits[["a", "b"]], [[1.3, -0.4]] * 2, atol=1e-8)
    assert (fits.misfit < 1e-10).all() and (fits.status > 0).all()


def test_fixed_axes_and_powell_on_a_piecewise_constant_statistic():
    def steps(pose):               # rounds like a rank statistic: flat almost everywhere
        return np.round(_toy(pose), 1)
    entries = (np.array([0, 1]), np.array([0, 2]))
    published = steps({"a": np.array([1.0]), "b": np.array([0.0])})[(slice(None), *entries)][0]
    fit = S.fit_pose(steps, published, entries, starts=[[0.6]], free=["a"], fixed={"b": 0.0},
                     method="powell", options=dict(xtol=1e-3)).iloc[0]
    assert fit.misfit == 0.0 and abs(fit.a - 1.0) < 0.1


def test_screening_is_the_rms_of_the_residuals_at_the_entries():
    poses = {"a": np.linspace(-1, 1, 5), "b": np.zeros(5)}
    entries = (np.array([0, 1]), np.array([1, 0]))
    rms, full = S.screen_poses(_toy, [0.0, 0.25], entries, poses=poses)
    assert full.shape == (5, 2, 3)
    want = np.sqrt(((np.c_[np.zeros(5), poses["a"] ** 2] - [0.0, 0.25]) ** 2).mean(1))
    assert np.allclose(rms, want)
    assert np.argmin(rms) in (1, 3)                         # |a| = 0.5: a^2 = 0.25


def test_bad_input_is_refused_with_a_clear_message():
    entries = (np.array([0]), np.array([0]))
    with pytest.raises(ValueError, match=r"starts must have 2 columns"):
        S.fit_pose(_toy, [1.0], entries, starts=[[0.0]], free=["a", "b"])
    with pytest.raises(ValueError, match="method must be 'least_squares' or 'powell'"):
        S.fit_pose(_toy, [1.0], entries, starts=[[0.0, 0.0]], free=["a", "b"],
                   method="nelder-mead")
    with pytest.raises(ValueError, match=r"both free and fixed: \['b'\]"):
        S.pose_residuals(_toy, [1.0], entries, free=["a", "b"], fixed={"b": 0.0})
    with pytest.raises(ValueError, match="must match published"):
        S.pose_residuals(_toy, [1.0, 2.0], entries, free=["a", "b"])
    with pytest.raises(ValueError, match="max_nfev must be an integer >= 1, got 0"):
        S.fit_pose(_toy, [1.0], entries, starts=[[0.0, 0.0]], free=["a", "b"], max_nfev=0)


def test_pose_searches_take_keywords_after_the_problem():
    entries = (np.array([0]), np.array([0]))
    poses = {"a": np.zeros(2), "b": np.zeros(2)}
    with pytest.raises(TypeError):
        S.fit_pose(_toy, [1.0], entries, [[0.0, 0.0]], ["a", "b"])
    with pytest.raises(TypeError):
        S.pose_residuals(_toy, [1.0], entries, ["a", "b"])
    with pytest.raises(TypeError):
        S.screen_poses(_toy, [1.0], entries, poses)
    with pytest.raises(TypeError):
        S.least_squares_starts(lambda v: v, [[0.0]], [-1.0], [1.0], [1.0])


def test_notebook_01s_search_is_the_shared_one():
    """fit_pose_to_indices (the AC turntable's linear indices) equals fit_pose with that
    statistic, C folded into [0, 2 pi)."""
    m = build("ac_double_turntable")
    sd = np.array([5e-3 if e.translational else 1.6e-5 for e in m.catalogue])
    pose = {"x": np.array([80.0]), "y": np.array([40.0]), "z": np.array([60.0]),
            "A": np.array([0.6]), "C": np.array([1.1])}
    rows, cols = np.array([0, 1, 2, 3, 4]), np.array([0, 5, 10, 20, 30])

    def stat(p):
        return S.linear_indices(m.jacobian(p), sd=sd).swapaxes(-1, -2)   # (P, 6, 41)

    target = stat(pose)[0][rows, cols]
    start = [[70.0, 50.0, 50.0, 0.5, 1.0 + 2 * np.pi]]
    a = fit_pose_to_indices(m, sd, target, rows=rows, cols=cols, starts=start)
    travel = [TRAVELS[a] if a != "C" else (-np.inf, np.inf) for a in "xyzAC"]
    b = S.fit_pose(stat, target, (rows, cols), starts=start, free=("x", "y", "z", "A", "C"),
                   bounds=tuple(np.array(v) for v in zip(*travel, strict=True)),
                   scale=np.array([100.0, 100.0, 100.0, 1.0, 1.0]))
    assert 0 <= a.C.iloc[0] < 2 * np.pi
    assert a.misfit.iloc[0] == b.misfit.iloc[0]
    assert np.isclose(a.C.iloc[0], np.mod(b.C.iloc[0], 2 * np.pi))
