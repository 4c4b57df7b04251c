"""Identification with uncertainty (mtaccuracy.measure.identify), on a physical model of our own.

The XY(Z) stage of tests/test_measure_identifiability.py: scales ``EXX``, ``EYY``, ``EZZ``
(mm/mm), squareness ``EC0Y`` (rad); actual position ``(x (1 + EXX) - y EC0Y, y (1 + EYY),
z (1 + EZZ))``.  Its exact ballbar reading (um) about a centre misplaced by ``(cx, cy)`` mm with
a bar-length error ``dL`` mm is ``1000 (|p_actual - c| - R - dL)``, written below in full; the
linear designs are its first-order terms.  Truth, noise and seeds are stated in each test.
"""

import numpy as np
import pytest
from scipy import stats

from mtaccuracy.measure.design import Design, combine
from mtaccuracy.measure.identify import identify, predict

ERRORS = ("EXX", "EYY", "EC0Y", "EZZ")
R, N_C = 150.0, 360
PRIOR = np.full(4, 1e-4)
TRUTH = np.array([2e-5, -1e-5, 3e-5, 1e-5])            # 20 um/m, -10 um/m, 30 urad, 10 um/m
TH = 2 * np.pi * np.arange(N_C) / N_C
X = np.linspace(-200.0, 200.0, 21)


def circle(sigma=0.05):
    c, s = np.cos(TH), np.sin(TH)
    A = 1000 * R * np.c_[c * c, s * s, -s * c, 0 * c]
    N = -1000 * np.c_[c, s, np.ones(N_C)]
    return Design("circle", A, N, sigma, ERRORS, ("cx mm", "cy mm", "dL mm"),
                  tuple(f"circle {k}" for k in range(N_C)))


def circle_exact(eps, nu):
    """The ballbar's exact reading, um: |actual - centre| - (R + dL)."""
    x, y = R * np.cos(TH), R * np.sin(TH)
    xa, ya = x * (1 + eps[0]) - y * eps[2], y * (1 + eps[1])
    return 1000 * (np.hypot(xa - nu[0], ya - nu[1]) - R - nu[2])


def laser(axis, sigma=0.2):
    A = np.zeros((X.size, 4))
    A[:, {"x": 0, "y": 1, "z": 3}[axis]] = 1000 * X
    return Design(f"laser {axis}", A, np.ones((X.size, 1)), sigma, ERRORS, ("zero um",),
                  tuple(f"laser {axis} {k}" for k in range(X.size)))


def test_noise_free_recovery_and_statuses():
    plan = combine([circle(), laser("x"), laser("z")])
    nu = np.array([0.01, -0.02, 0.005, 1.5, -0.7])
    y = plan.A @ TRUTH + plan.N @ nu
    res = identify(y, plan, prior_sd=PRIOR)
    assert res.status == ("seen",) * 4 and res.rank == 4
    np.testing.assert_allclose(res.estimate, TRUTH, rtol=1e-6)
    np.testing.assert_allclose(res.nuisance_estimate, nu, rtol=1e-6)
    assert res.chi2 < 1e-12 and res.dof == plan.n_obs - 5 - 4
    # the circle alone: the seen errors' estimates are exact, EXX and EYY only in their
    # seen combination (EXX - EYY), EZZ stays at the prior mean with the prior's uncertainty
    c = circle()
    res = identify(c.A @ TRUTH + c.N @ nu[:3], c, prior_sd=PRIOR)
    assert res.status == ("combination", "combination", "seen", "blind")
    np.testing.assert_allclose(res.estimate[2], TRUTH[2], rtol=1e-6)
    np.testing.assert_allclose(res.estimate[0] - res.estimate[1], TRUTH[0] - TRUTH[1],
                               rtol=1e-6)
    assert res.estimate[3] == 0 and res.standard_uncertainty[3] == pytest.approx(1e-4)


def test_500_noisy_replicates_unbiased_calibrated_and_covering():
    plan = combine([circle(), laser("x")])
    rng = np.random.default_rng(20260)
    nu = np.array([0.01, -0.02, 0.005, 1.5])
    clean = plan.A @ TRUTH + plan.N @ nu
    y = clean + rng.normal(size=(500, plan.n_obs)) * plan.sigma      # (500, n_obs) at once
    res = identify(y, plan, prior_sd=PRIOR)
    seen = np.array([s == "seen" for s in res.status])
    assert seen.tolist() == [True, True, True, False]
    est, su = res.estimate[:, seen], res.standard_uncertainty[seen]
    se = est.std(axis=0, ddof=1) / np.sqrt(500)
    assert np.all(np.abs(est.mean(axis=0) - TRUTH[seen]) < 3 * se)
    ratio = est.var(axis=0, ddof=1) / su**2
    assert np.all((ratio > 0.8) & (ratio < 1.25)), ratio
    cover = np.mean(np.abs(est - TRUTH[seen]) <= stats.norm.ppf(0.975) * su)
    assert 0.93 <= cover <= 0.97, cover
    # the nuisances too, and the chi-square: mean within 4 standard errors of dof, and the
    # p-values uniform (Kolmogorov-Smirnov at 1 %)
    nse = res.nuisance_estimate.std(axis=0, ddof=1)
    np.testing.assert_allclose(nse**2 / np.diag(res.nuisance_cov), 1, atol=0.2)
    assert abs(res.chi2.mean() - res.dof) < 4 * np.sqrt(2 * res.dof / 500)
    assert stats.kstest(res.p_value, "uniform").pvalue > 0.01


def test_map_is_calibrated_when_the_truth_is_drawn_from_the_prior():
    # Bayesian check: each replicate its own truth from N(0, prior); the posterior's 95 %
    # intervals cover it 93-97 % of the time, blind and combination errors included
    c = circle()
    rng = np.random.default_rng(11)
    truth = rng.normal(size=(500, 4)) * PRIOR
    y = truth @ c.A.T + rng.normal(size=(500, c.n_obs)) * c.sigma
    res = identify(y, c, prior_sd=PRIOR, method="map")
    cover = np.mean(np.abs(res.estimate - truth) <= 1.959964 * res.standard_uncertainty)
    assert 0.93 <= cover <= 0.97, cover
    # and the truncated SVD's uncertainty of a combination error is the prior's share
    tsvd = identify(y, c, prior_sd=PRIOR)
    assert tsvd.standard_uncertainty[0] > 0.5 * 1e-4 > res.standard_uncertainty[2]


def test_a_held_out_test_is_predicted_within_two_sigma():
    plan = combine([circle(), laser("x")])
    rng = np.random.default_rng(5)
    nu = np.array([0.01, -0.02, 0.005, 1.5])
    res = identify(plan.A @ TRUTH + plan.N @ nu + rng.normal(size=plan.n_obs) * plan.sigma,
                   plan, prior_sd=PRIOR)
    ly = laser("y")
    y2 = ly.A @ TRUTH + 3.0 + rng.normal(size=ly.n_obs) * ly.sigma    # its own zero: 3 um
    pr = predict(res, ly, y=y2)
    df = pr.to_df()
    assert np.all(np.abs(df.residual_um) <= 2 * df.residual_sd_um)
    # the nuisance-free part is the line through the truth, within two standard uncertainties
    free = predict(res, ly)
    assert np.all(np.abs(free.reading - ly.A @ TRUTH) <= 2 * free.standard_uncertainty + 1e-12)
    # analytic: the y laser's prediction carries only EYY's uncertainty, 1000 |x| u(EYY)
    np.testing.assert_allclose(free.standard_uncertainty,
                               1000 * np.abs(X) * res.standard_uncertainty[1], rtol=1e-9)
    # a test of what the plan cannot see is predicted with the prior's uncertainty
    lz = predict(res, laser("z"))
    np.testing.assert_allclose(lz.standard_uncertainty, 1000 * np.abs(X) * 1e-4, rtol=1e-9)


def test_refinement_on_the_exact_model_recovers_what_the_linear_one_misses():
    plan = circle()
    truth = np.array([4e-4, 1e-4, 5e-4, 0.0])
    nu = np.array([0.4, -0.3, 0.05])        # a centre 0.5 mm off: quadratic terms ~0.8 um
    prior = np.full(4, 1e-3)
    # the test's own model first: at um/urad sizes its linear design is the exact model's
    # first order (the quadratic remainder ~ (1e-3 mm)^2 / R, 1e-3 of the reading or less)
    small, nu_small = np.array([2e-5, -1e-5, 3e-5, 0.0]), np.array([1e-3, -2e-3, 1e-3])
    lin_small = plan.A @ small + plan.N @ nu_small
    assert np.abs(circle_exact(small, nu_small) - lin_small).max() < 1e-3 * np.abs(
        lin_small).max()
    clean = circle_exact(truth, nu)
    # the linearisation's error at these sizes is far above the noise (0.05 um)
    assert np.abs(clean - (plan.A @ truth + plan.N @ nu)).max() > 0.2
    y = clean + np.random.default_rng(2).normal(size=N_C) * 0.05
    with pytest.warns(RuntimeWarning, match=r"depart from the model.*give exact="):
        identify(y, plan, prior_sd=prior)         # the linear model alone misfits
    res = identify(y, plan, prior_sd=prior, exact=circle_exact)
    lin = res.linear
    d_lin = lin.estimate[0] - lin.estimate[1] - (truth[0] - truth[1])
    u_diff = np.sqrt([1, -1, 0, 0] @ lin.cov @ [1, -1, 0, 0])
    assert abs(lin.estimate[2] - truth[2]) > 10 * lin.standard_uncertainty[2]
    assert abs(d_lin) > 10 * u_diff
    d_ref = res.estimate[0] - res.estimate[1] - (truth[0] - truth[1])
    assert abs(res.estimate[2] - truth[2]) < 3 * res.standard_uncertainty[2]
    assert abs(d_ref) < 3 * np.sqrt([1, -1, 0, 0] @ res.cov @ [1, -1, 0, 0])
    assert res.method == "tsvd+refined" and res.chi2 < res.dof + 4 * np.sqrt(2 * res.dof)
    # noise-free: the refinement recovers the seen errors and the centre to 1e-6 relative
    # when the blind mean scale is where the truncated SVD holds it (zero); off it, the seen
    # ones carry its second-order coupling (here 2.6e-6 relative for EC0Y: 2.5e-4 x 5e-4 rad)
    flat = np.array([3e-4, -3e-4, 5e-4, 0.0])
    res = identify(circle_exact(flat, nu), plan, prior_sd=prior, exact=circle_exact)
    np.testing.assert_allclose(res.estimate[:3], flat[:3], rtol=1e-6)
    np.testing.assert_allclose(res.nuisance_estimate, nu, rtol=1e-6)
    res = identify(clean, plan, prior_sd=prior, exact=circle_exact)
    assert abs(res.estimate[2] - truth[2]) < 2 * abs(truth[0] + truth[1]) / 2 * truth[2]
    # MAP refinement on a full plan (the x laser fixes EXX): all four near the truth
    full = combine([plan, laser("x"), laser("z")])

    def full_exact(eps, nuf):
        return np.concatenate([circle_exact(eps, nuf[:3]), 1000 * X * eps[0] + nuf[3],
                               1000 * X * eps[3] + nuf[4]])

    nuf = np.r_[nu, 1.0, -2.0]
    res = identify(full_exact(truth, nuf), full, prior_sd=prior, exact=full_exact)
    np.testing.assert_allclose(res.estimate[:3], truth[:3], rtol=1e-6)
    np.testing.assert_allclose(res.nuisance_estimate, nuf, rtol=1e-6)
    res = identify(full_exact(truth, nuf), full, prior_sd=prior, exact=full_exact,
                   method="map")
    np.testing.assert_allclose(res.estimate, truth, atol=1e-6 * np.abs(truth).max())


def test_to_df_in_display_units():
    c = combine([circle(), laser("x")])
    res = identify(c.A @ TRUTH, c, prior_sd=PRIOR,
                   units={"EXX": "um/m", "EYY": "um/m", "EC0Y": "urad"})
    df = res.to_df()
    assert df.columns.tolist() == ["symbol", "estimate", "standard_uncertainty", "unit",
                                   "status"]
    np.testing.assert_allclose(df.estimate[:3], [20, -10, 30], rtol=1e-6)
    assert df.unit.tolist() == ["um/m", "um/m", "urad", "design unit"]
    assert df.status.tolist() == ["seen", "seen", "seen", "blind"]


def test_bad_input_is_refused_naming_it():
    c = circle()
    y = c.A @ TRUTH
    with pytest.raises(ValueError, match=r"y must be \(360,\) or \(n_replicates, 360\)"):
        identify(y[:-1], c, prior_sd=PRIOR)
    bad = y.copy()
    bad[17] = np.nan
    with pytest.raises(ValueError, match=r"reading 17 \('circle 17'\)"):
        identify(bad, c, prior_sd=PRIOR)
    with pytest.raises(ValueError, match=r"replicate 1, reading 17"):
        identify(np.stack([y, bad]), c, prior_sd=PRIOR)
    with pytest.raises(ValueError, match="method must be"):
        identify(y, c, prior_sd=PRIOR, method="ls")
    with pytest.raises(ValueError, match="unknown unit"):
        identify(y, c, prior_sd=PRIOR, units={"EXX": "inch"})
    with pytest.raises(ValueError, match=r"exact\(eps, nu\) must return \(360,\)"):
        identify(y, c, prior_sd=PRIOR, exact=lambda e, n: np.zeros(3))
    with pytest.raises(ValueError, match="one replicate"):
        identify(np.stack([y, y]), c, prior_sd=PRIOR, exact=circle_exact)
    with pytest.raises(ValueError, match="finite and > 0"):
        identify(y, c, prior_sd=[1, 1, -1, 1])
    with pytest.raises(ValueError, match="sigma must be finite and > 0"):
        Design("bad", c.A, c.N, np.r_[0.0, np.ones(N_C - 1)], ERRORS, c.nuisances, c.labels)
    res = identify(y, c, prior_sd=PRIOR)
    other = Design("other", np.ones((2, 1)), np.zeros((2, 0)), 1.0, ("Q",), (), ("a", "b"))
    with pytest.raises(ValueError, match="other errors"):
        predict(res, other)
    with pytest.raises(ValueError, match=r"y must be \(21,\)"):
        predict(res, laser("y"), y=np.zeros(5))
    with pytest.raises(ValueError, match="pass replicate"):
        identify(np.stack([y, y]), c, prior_sd=PRIOR).to_df()


def test_map_is_the_joint_gaussian_posterior_with_a_vague_nuisance_prior():
    # independent formulation: errors and nuisances as one Gaussian unknown, the nuisances with
    # prior sd 1e5 (flat in the limit), solved by the normal equations; and a design with fewer
    # readings than errors and no nuisances against Gaussian conditioning
    rng = np.random.default_rng(4)
    n, p, m = 30, 5, 2
    A, N = rng.normal(size=(n, p)), rng.normal(size=(n, m))
    sig, prior = rng.uniform(0.5, 2, n), rng.uniform(0.2, 1, p)
    d = Design("random", A, N, sig, tuple(f"E{i}" for i in range(p)), ("n0", "n1"),
               tuple(map(str, range(n))))
    y = A @ (prior * rng.normal(size=p)) + N @ rng.normal(size=m) + sig * rng.normal(size=n)
    J = np.c_[A, N] / sig[:, None]
    cov = np.linalg.inv(J.T @ J + np.diag(np.r_[1 / prior**2, 1e-10, 1e-10]))
    mean = cov @ J.T @ (y / sig)
    res = identify(y, d, prior_sd=prior, method="map")
    np.testing.assert_allclose(res.estimate, mean[:p], rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(res.nuisance_estimate, mean[p:], rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(res.cov, cov[:p, :p], rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(res.nuisance_cov, cov[p:, p:], rtol=1e-5, atol=1e-9)
    few = Design("few", A[:3], np.zeros((3, 0)), sig[:3], d.errors, (), ("a", "b", "c"))
    S0 = np.diag(prior**2)
    gain = S0 @ A[:3].T @ np.linalg.inv(A[:3] @ S0 @ A[:3].T + np.diag(sig[:3] ** 2))
    res = identify(y[:3], few, prior_sd=prior, method="map")
    np.testing.assert_allclose(res.estimate, gain @ y[:3], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(res.cov, S0 - gain @ A[:3] @ S0, rtol=1e-9, atol=1e-12)


def test_a_weak_direction_below_the_seen_threshold_does_not_bias_a_seen_error():
    """A direction with S**2 = 49 (below shrink - 1 = 99) still carries signal: the estimate
    uses it, so the seen error it touches is recovered exactly from noise-free readings (left at
    the prior mean it would be off by sin(0.05) of a prior standard deviation)."""
    a = 0.05
    V = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    rng = np.random.default_rng(4)
    U = np.linalg.qr(rng.standard_normal((40, 2)))[0]
    prior = np.array([2.0, 3.0])
    A = (U * [30.0, 7.0]) @ V.T / prior                       # whitened, prior-scaled: U S V'
    d = Design("weak", A, np.zeros((40, 0)), 1.0, ("E1", "E2"), (), tuple(map(str, range(40))))
    truth = np.array([1.5, -2.0])
    r = identify(A @ truth, d, prior_sd=prior)
    assert r.status[0] == "seen" and r.status[1] != "seen"
    assert np.allclose(r.estimate, truth, rtol=1e-9, atol=0)
    assert abs(r.chi2) < 1e-18 and r.dof == 38
