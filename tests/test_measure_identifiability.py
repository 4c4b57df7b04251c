"""Identifiability of a test plan (mtaccuracy.measure.identifiability), on models of our own.

The physical model, written here: an XY(Z) stage with axis scales ``EXX``, ``EYY``, ``EZZ``
(mm/mm) and the squareness ``EC0Y`` (rad) of Y to X; the actual position of a command
``(x, y, z)`` is ``(x (1 + EXX) - y EC0Y, y (1 + EYY), z (1 + EZZ))``.  A ballbar circle of
radius R about a centre misplaced by ``(cx, cy)`` with a bar-length error ``dL`` reads, um,
``1000 (|p_actual - c| - R - dL)``, linearised ``1000 R (EXX cos^2 + EYY sin^2 - EC0Y sin cos)
- 1000 (cx cos + cy sin + dL)``; a laser along an axis reads ``1000 x EXX`` plus its zero.
"""

import numpy as np
import pytest

from mtaccuracy.measure.design import Design, combine
from mtaccuracy.measure.identifiability import (
    identifiability,
    identifiability_table,
    next_test,
    plan_tests,
)

ERRORS = ("EXX", "EYY", "EC0Y", "EZZ")
R = 150.0          # mm
PRIOR = np.full(4, 1e-4)   # mm/mm and rad


def circle(n=360, sigma=0.05, radius=R):
    th = 2 * np.pi * np.arange(n) / n
    c, s = np.cos(th), np.sin(th)
    A = 1000 * radius * np.c_[c * c, s * s, -s * c, 0 * c]
    N = -1000 * np.c_[c, s, np.ones(n)]
    return Design("circle", A, N, sigma, ERRORS, ("cx mm", "cy mm", "dL mm"),
                  tuple(f"circle {k}" for k in range(n)))


def laser(axis, n=21, sigma=0.2):
    x = np.linspace(-200.0, 200.0, n)
    A = np.zeros((n, 4))
    A[:, {"x": 0, "y": 1, "z": 3}[axis]] = 1000 * x
    return Design(f"laser {axis}", A, np.ones((n, 1)), sigma, ERRORS, ("zero um",),
                  tuple(f"laser {axis} {k}" for k in range(n)))


def test_circle_sees_squareness_and_scale_difference_not_mean_scale_nor_z():
    r = identifiability(circle(), prior_sd=PRIOR)
    df = r.to_df().set_index("symbol")
    assert df.status.to_dict() == {"EXX": "combination", "EYY": "combination",
                                   "EC0Y": "seen", "EZZ": "blind"}
    # the invisible move: EXX and EYY up together (the bar length absorbs it)
    assert df.combination["EXX"] == df.combination["EYY"] == "EXX + EYY"
    assert df.combination["EC0Y"] == df.combination["EZZ"] == ""
    assert r.rank == 2
    # analytic: cos^2 and sin^2 leave +-cos(2 th)/2 beside the nuisances, -sin cos is
    # -sin(2 th)/2; each has sum of squares n/8 over the circle
    s_sq = 1000 * R * 1e-4 / 0.05 * np.sqrt(360 / 8)
    np.testing.assert_allclose(r.singular_values[:2], [np.sqrt(2) * s_sq, s_sq], rtol=1e-12)
    np.testing.assert_allclose(r.condition_number, np.sqrt(2), rtol=1e-12)
    np.testing.assert_allclose(df.posterior_sd["EC0Y"], 1e-4 / np.sqrt(1 + s_sq**2), rtol=1e-12)
    np.testing.assert_allclose(df.posterior_sd["EZZ"], 1e-4, rtol=1e-12)
    np.testing.assert_allclose(df.unseen_share.to_numpy(), [0.5, 0.5, 0, 1], atol=1e-12)
    o = r.observability
    sv = np.array([np.sqrt(2) * s_sq, s_sq])
    np.testing.assert_allclose([o["O1"], o["O2"], o["O3"], o["O4"], o["O5"]],
                               [np.sqrt(sv.prod()) / np.sqrt(360), 1 / np.sqrt(2), s_sq,
                                s_sq**2 / sv[0], 1 / np.sum(1 / sv)], rtol=1e-12)
    assert r.summary()["n_combination"] == 2


def test_posterior_matches_the_joint_gaussian_with_a_vague_nuisance_prior():
    # independent formulation: errors and nuisances together, nuisances with prior sd 1e5
    # (flat in the limit); the errors' marginal posterior sd must agree
    rng = np.random.default_rng(3)
    n, p, m = 40, 6, 3
    A, N = rng.normal(size=(n, p)), rng.normal(size=(n, m))
    sig, prior = rng.uniform(0.5, 2, n), rng.uniform(0.1, 1, p)
    d = Design("random", A, N, sig, tuple(f"E{i}" for i in range(p)),
               tuple(f"n{i}" for i in range(m)), tuple(map(str, range(n))))
    J = np.c_[A, N] / sig[:, None]
    prec = J.T @ J + np.diag(np.r_[1 / prior**2, np.full(m, 1e-10)])
    want = np.sqrt(np.diag(np.linalg.inv(prec))[:p])
    np.testing.assert_allclose(identifiability(d, prior_sd=prior).posterior_sd, want,
                               rtol=1e-6)


def _with_null(null, n=30, seed=0):
    """A random design whose errors' exact null space is spanned by the columns of null."""
    rng = np.random.default_rng(seed)
    null = np.asarray(null, dtype=float)
    Qn = np.linalg.qr(null)[0]
    A = rng.normal(size=(n, null.shape[0]))
    A = A - (A @ Qn) @ Qn.T
    return Design("structured", A, np.ones((n, 1)), 0.01,
                  tuple(f"E{i}" for i in range(null.shape[0])), ("offset",),
                  tuple(map(str, range(n))))


def test_combinations_are_canonical_whatever_basis_or_prior():
    d1 = np.array([1, 1, 1, 0, 0.0])
    d2 = np.array([0, 1, -1, 0, 0.0])
    want = {"E0": "E0 + 2 E2", "E1": "E1 - E2", "E2": "E0 + 2 E2; E1 - E2", "E3": "",
            "E4": ""}
    for null in (np.c_[d1, d2], np.c_[d1 + d2, d1 - 3 * d2]):
        for prior in (np.ones(5), np.array([1, 3, 0.5, 2, 1.0])):
            df = identifiability(_with_null(null), prior_sd=prior).to_df()
            assert dict(zip(df.symbol, df.combination, strict=True)) == want
            assert df.status.tolist() == ["combination"] * 3 + ["seen"] * 2


def test_a_combination_is_named_in_physical_units():
    # an on-axis R-test-like reading sees offset + h tilt (h = 200 mm): moving the offset by
    # 1 mm and the tilt by -1/200 rad changes nothing, whatever the priors
    rng = np.random.default_rng(1)
    x = rng.normal(size=(25, 1))
    A = 1000 * np.c_[x, 200 * x, rng.normal(size=(25, 1))]   # um per mm, um per rad
    d = Design("r-test", A, np.zeros((25, 0)), 1e-3, ("EX0C", "EB0C", "EZ0C"), (),
               tuple(map(str, range(25))))
    for prior in ([1e-3, 1e-5, 1e-3], [2e-3, 1e-5, 1.0]):
        df = identifiability(d, prior_sd=prior).to_df()
        assert df.combination.tolist() == ["EX0C - 0.005 EB0C"] * 2 + [""]
        assert df.status.tolist() == ["combination", "combination", "seen"]
    # a tilt whose whole prior range moves the reading by 1/50 of the offset's: the offset is
    # seen (to 200 x 1e-6 mm), the tilt blind
    df = identifiability(d, prior_sd=[1e-2, 1e-6, 1.0]).to_df()
    assert df.status.tolist() == ["seen", "blind", "seen"]
    np.testing.assert_allclose(df.unseen_share, [4e-4, 1 - 4e-4, 0], atol=1e-6)


def test_the_threshold_is_the_stated_shrink_factor():
    # one reading, one error, prior 1, noise 1: the data shrink the variance by 1 + a^2; blind
    # only when they remove at most 1/shrink of it (1 + a^2 <= 1 / (1 - 0.01)), else learned in
    # part ("combination": its posterior says how much)
    for a, want in ((np.sqrt(98.0), "combination"), (np.sqrt(99.5), "seen"), (0.1, "blind"),
                    (0.0, "blind")):
        d = Design("one", [[a]], np.zeros((1, 0)), 1.0, ("E",), (), ("r",))
        r = identifiability(d, prior_sd=[1.0])
        assert r.status == (want,) and r.rank == (want == "seen")
        np.testing.assert_allclose(r.posterior_sd, [1 / np.sqrt(1 + a * a)], rtol=1e-12)
    d = Design("one", [[np.sqrt(20.0)]], np.zeros((1, 0)), 1.0, ("E",), (), ("r",))
    assert identifiability(d, prior_sd=[1.0], shrink=10).status == ("seen",)
    assert np.isnan(identifiability(laser("x"), prior_sd=np.full(4, 1e-12)).condition_number)


def test_next_test_ranks_by_log_det_gain_and_says_what_changes():
    lx, ly, lz = laser("x"), laser("y"), laser("z")
    nt = next_test(circle(), [lx, ly, lz], prior_sd=PRIOR)
    df = nt.to_df().set_index("test")
    # analytic gain of the z laser: EZZ is seen by nothing else, log(1 + ||P a~||^2)
    x = np.linspace(-200.0, 200.0, 21)
    sz = np.sum((x - x.mean())**2) * (1000 * 1e-4 / 0.2) ** 2
    np.testing.assert_allclose(df.logdet_gain["laser z"], np.log1p(sz), rtol=1e-10)
    assert df.changes["laser z"] == "EZZ: blind -> seen"
    assert df.changes["laser x"] == "EXX: combination -> seen; EYY: combination -> seen"
    assert (df.rank_before == 2).all() and df.rank_after.tolist() == [3, 3, 3]
    assert nt.best == "laser z"
    # weights: EZZ unimportant, so the z laser adds nothing; x and y tie, kept in order
    nt = next_test(circle(), [lz, ly, lx], prior_sd=PRIOR, weights=[1, 1, 1, 0])
    assert list(nt.candidates) == ["laser y", "laser x", "laser z"]
    assert nt.logdet_gain[-1] == pytest.approx(0, abs=1e-12)


def _one(name, row):
    return Design(name, [row], np.zeros((1, 0)), 1.0, ("E0", "E1"), (), (name,))


def test_plan_tests_exchanges_past_the_greedy_choice():
    # analytic: c0 sees E0 + E1 (information 6 [[1, 1], [1, 1]]), c1 and c2 each one error
    # (information 10): greedy takes c0 first (log 13 > log 11), then det = 83; the exchange
    # finds {c1, c2}, det = 121
    cands = [_one("c0", [np.sqrt(6), np.sqrt(6)]), _one("c1", [np.sqrt(10), 0]),
             _one("c2", [0, np.sqrt(10)])]
    assert next_test(_one("base", [0, 0]), cands, prior_sd=[1, 1]).best == "c0"
    df = plan_tests(_one("base", [0, 0]), cands, prior_sd=[1, 1], n=2, shrink=10)
    assert df.test.tolist() == ["c1", "c2"]
    np.testing.assert_allclose(df.logdet_gain, [np.log(11), np.log(11)], rtol=1e-12)
    np.testing.assert_allclose(df.logdet_total.iloc[-1], np.log(121), rtol=1e-12)
    assert df.changes.tolist() == ["E0: blind -> seen", "E1: blind -> seen"]
    # against brute force over every pair of five random tests
    rng = np.random.default_rng(9)
    tests = [Design(f"t{i}", rng.normal(size=(4, 5)) * rng.uniform(0.5, 5), np.ones((4, 1)),
                    1.0, tuple(f"E{j}" for j in range(5)), ("z",), tuple("abcd"))
             for i in range(5)]
    df = plan_tests(tests[0], tests[1:], prior_sd=np.ones(5), n=2)
    best = max(np.linalg.slogdet(np.eye(5) + sum(
        (A.T @ A for A in (_perp(tests[0]), _perp(tests[i]), _perp(tests[j]))), 0))[1]
        for i in range(1, 5) for j in range(i + 1, 5))
    np.testing.assert_allclose(df.logdet_total.iloc[-1] + np.linalg.slogdet(
        np.eye(5) + _perp(tests[0]).T @ _perp(tests[0]))[1], best, rtol=1e-10)
    with pytest.raises(ValueError, match="n must be an int from 1 to 4"):
        plan_tests(tests[0], tests[1:], prior_sd=np.ones(5), n=5)


def _perp(d):
    """The design's A with its nuisances projected out (sigma 1, prior 1), by lstsq."""
    return d.A - d.N @ np.linalg.lstsq(d.N, d.A, rcond=None)[0]


def test_a_five_axis_size_plan_with_known_null_space():
    # 80 errors, ten tests of 200 readings with three nuisances each, five known null
    # directions: the rank and the statuses follow; and an identical plan built twice agrees
    rng = np.random.default_rng(7)
    p, null = 80, np.zeros((80, 5))
    null[np.arange(5), np.arange(5)] = 1.0          # E0..E4 blind
    tests = []
    for t in range(10):
        A = rng.normal(size=(200, p))
        A[:, :5] = 0.0
        tests.append(Design(f"t{t}", A, rng.normal(size=(200, 3)), 0.1,
                            tuple(f"E{i}" for i in range(p)), ("a", "b", "c"),
                            tuple(f"t{t} {k}" for k in range(200))))
    r = identifiability(combine(tests), prior_sd=np.full(p, 0.1))
    assert r.rank == 75 and r.nuisance_rank == 30
    assert r.status[:5] == ("blind",) * 5 and set(r.status[5:]) == {"seen"}


def test_bad_input_is_refused_naming_it():
    c = circle()
    with pytest.raises(ValueError, match=r"missing \['EZZ'\]"):
        identifiability(c, prior_sd={"EXX": 1e-4, "EYY": 1e-4, "EC0Y": 1e-4})
    with pytest.raises(ValueError, match=r"finite and > 0.*EYY"):
        identifiability(c, prior_sd=[1e-4, 0, 1e-4, 1e-4])
    with pytest.raises(ValueError, match=r"must be \(4,\)"):
        identifiability(c, prior_sd=[1e-4, 1e-4])
    with pytest.raises(ValueError, match="shrink"):
        identifiability(c, prior_sd=PRIOR, shrink=1.0)
    other = Design("other", np.ones((2, 1)), np.zeros((2, 0)), 1.0, ("Q",), (), ("a", "b"))
    with pytest.raises(ValueError, match="other errors"):
        next_test(c, [other], prior_sd=PRIOR)
    with pytest.raises(ValueError, match="weights"):
        next_test(c, [laser("x")], prior_sd=PRIOR, weights=[0, 0, 0, 0])
    with pytest.raises(ValueError, match="at least one"):
        next_test(c, [], prior_sd=PRIOR)
    with pytest.raises(ValueError, match="sigma must be finite and > 0"):
        Design("bad", np.ones((2, 4)), np.zeros((2, 0)), [1.0, 0.0], ERRORS, (), ("a", "b"))


def test_the_test_by_error_table():
    t = identifiability_table([circle(), laser("x")], prior_sd=PRIOR)
    assert t.columns.tolist() == ["circle", "laser x", "plan", "plan_combination"]
    assert t["laser x"].tolist() == ["seen", "blind", "blind", "blind"]
    assert t.plan.tolist() == ["seen", "seen", "seen", "blind"]
    assert t.loc["EXX", "circle"] == "combination"
