import numpy as np
import pytest
from scipy import stats

from mtaccuracy import sensitivity as S
from mtaccuracy.machines import build

RNG = np.random.default_rng(1)


def test_spearman_matches_scipy_and_broadcasts():
    x, y = RNG.normal(size=(3, 40, 4)), RNG.normal(size=(3, 40, 2))
    y[..., 1] = np.exp(x[..., 0]) + 0.1 * y[..., 1]
    got = S.spearman(x, y)
    assert got.shape == (3, 4, 2)
    for r in range(3):
        ref = stats.spearmanr(np.c_[x[r], y[r]]).statistic[:4, 4:]
        assert np.allclose(got[r], ref)


def test_spearman_of_monotone_transform_is_one_and_handles_ties():
    x = RNG.uniform(size=(50, 1))
    assert S.spearman(x, -np.log(x))[0, 0] == pytest.approx(-1.0)
    t = np.array([[1.0], [1.0], [2.0], [3.0]])
    assert S.spearman(t, t**3)[0, 0] == pytest.approx(1.0)


def test_latin_hypercube_puts_one_point_in_every_stratum():
    b = np.array([[0.0, -1.0, 10.0], [1.0, 1.0, 20.0]])
    x = S.latin_hypercube(25, b, 3)
    u = (x - b[0]) / (b[1] - b[0])
    for j in range(3):
        assert sorted(np.floor(u[:, j] * 25).astype(int)) == list(range(25))


def test_latin_hypercube_refuses_bad_input():
    with pytest.raises(ValueError, match="n must be an integer >= 2"):
        S.latin_hypercube(-5, np.zeros((2, 3)), 0)
    with pytest.raises(ValueError, match="bounds must have shape"):
        S.latin_hypercube(5, np.zeros((3, 2)), 0)


def test_repeated_designs_are_deterministic_and_prefix_stable():
    b = np.array([[0.0, 0.0], [1.0, 1.0]])
    a = S.repeated_latin_hypercube(10, b, repeats=4, seed=7)
    assert np.array_equal(a, S.repeated_latin_hypercube(10, b, repeats=4, seed=7))
    assert np.array_equal(a[:2], S.repeated_latin_hypercube(10, b, repeats=2, seed=7))
    assert not np.array_equal(a[0], a[1])


def test_rank_and_weak_rule():
    assert S.rank_by_magnitude(np.array([0.1, -0.5, 0.3]), ["a", "b", "c"])[0] == ("b", -0.5)
    rho = np.array([[0.9, 0.8], [0.1, 0.7], [0.05, 0.02]])
    assert S.below_group_mean(rho).tolist() == [False, False, True]


def test_spearman_over_poses_equals_one_pose_at_a_time():
    m = build("vertical_xyfz")
    x = RNG.uniform(0, 1e-3, size=(60, 21)) * np.r_[np.ones(9), 0.03 * np.ones(12)]
    poses = {"x": np.zeros(3), "y": np.array([0.0, 100.0, 300.0]), "z": np.array([50.0, 0, 9])}
    got = S.spearman_over_poses(m, x, poses, chunk=2)
    for p in range(3):
        one = {k: v[p] for k, v in poses.items()}
        assert np.allclose(got[p], S.spearman(x, S.position_outputs(m.pose_error(x, one))))


def test_average_ranks_equal_scipy_with_and_without_ties():
    x = RNG.normal(size=(2, 30, 3))
    assert np.array_equal(S.average_ranks(x), stats.rankdata(x, axis=-2))
    t = np.round(x, 0)  # many ties
    assert np.array_equal(S.average_ranks(t), stats.rankdata(t, axis=-2))


def test_equal_spearman_coefficients_are_equal_to_the_bit():
    """Rank sums are exact, so coefficients that are equal in exact arithmetic are equal in
    floating point and the ranking breaks the tie by catalogue order."""
    n = 500
    r = RNG.permutation(n).astype(float)
    y = RNG.normal(size=(n, 1))
    yr = stats.rankdata(y[:, 0])
    # two columns whose centred ranks against y give numerators of equal magnitude, opposite sign
    x = np.c_[yr, n + 1 - yr, r]
    rho = S.spearman(x, y)[:, 0]
    assert rho[0] == 1.0 and rho[1] == -1.0
    ranked = S.rank_by_magnitude(rho, ["a", "b", "c"])
    assert [s for s, _ in ranked[:2]] == ["a", "b"]
    assert S.rank_by_magnitude(-rho, ["a", "b", "c"])[0][0] == "a"



def test_rank_positions_and_intervals():
    rho = np.array([[0.1, -0.9], [-0.5, 0.2], [0.5, 0.0]])  # |rho| tie 0.5: catalogue order
    assert S.rank_positions(rho).tolist() == [[3, 1], [1, 2], [2, 3]]
    rep = np.stack([rho, rho[[2, 1, 0]], rho])  # (3, 3, 2)
    lo, hi = S.rank_intervals(rep, level=0.5)
    assert lo[:, 0].tolist() == [1, 1, 2] and hi[:, 1].tolist() == [3, 2, 3]
    with pytest.raises(ValueError, match="at least 2 designs"):
        S.rank_intervals(rho[None])
    with pytest.raises(ValueError, match="level must be in"):
        S.rank_intervals(rep, level=1.0)


def _models(x):
    u = (x - x.min(axis=0)) / np.ptp(x, axis=0)
    return np.c_[u[:, 0], u @ np.arange(1.0, 7.0), np.exp(3 * u[:, 0]) * u[:, 1],
                 np.abs(u[:, 2] - 0.5), np.sin(6 * u[:, :3]).sum(axis=1)]


def test_sum_of_squared_spearman_is_bounded_for_independent_inputs():
    """Bessel: the population sum is <= 1 for any model of independent inputs (= 1 for a
    rank-linear one); a sample of n adds about d / n and spreads by about 2 / sqrt(n).  The
    sample R^2 of the rank regression is <= 1 exactly and approaches the sum of squares."""
    n, d = 4000, 6
    allowance = d / n + 4 / np.sqrt(n)
    x = S.latin_hypercube(n, np.c_[np.zeros(d), np.ones(d)].T, 5)
    y = _models(x)
    ss = S.sum_of_squares(S.spearman(x, y))
    assert 1.0 <= ss[0] <= 1 + 3 * d / n  # y = x0: equality, plus the others' noise
    assert np.all(ss <= 1 + allowance)
    assert ss[3] < 0.05  # |x2 - 0.5|: no monotone trend, nearly nothing
    r2 = S.rank_r_squared(x, y)
    assert np.all(r2 <= 1 + 1e-12) and np.allclose(r2, ss, atol=allowance)


def test_sum_of_squares_holds_for_the_vertical_machine_at_any_pose():
    """The Guo et al. machine at 12 random poses (Abbe arms up to 500 mm): every component's
    sum over the 21 errors stays within the sampling allowance of the bound 1."""
    m = build("vertical_xyfz")
    scale = np.r_[[3e-3] * 3, [4e-3] * 6, [3.2e-5] * 9, [1.9e-6] * 3]
    n = 8000
    x = S.latin_hypercube(n, np.c_[np.zeros(21), scale].T, 8)
    rng = np.random.default_rng(9)
    poses = {"x": np.zeros(12), **{k: rng.uniform(-500, 500, 12) for k in ("y", "z")},
             **{k: rng.uniform(-200, 200, 12) for k in ("D1", "D2", "D3")}}
    ss = S.sum_of_squares(S.spearman_over_poses(m, x, poses))  # (12, 4)
    assert ss.shape == (12, 4)
    assert np.all(ss <= 1 + 21 / n + 4 / np.sqrt(n))
    assert ss[:, :3].min() > 0.8  # each component is nearly rank-linear in the errors
