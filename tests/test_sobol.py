"""Sobol estimators: agreement with SALib, the Ishigami function, chunking invariance."""

import numpy as np
import pytest
from SALib.analyze import sobol as salib_sobol

from mtaccuracy import sensitivity as S


def ishigami(x, a=7.0, b=0.1):
    return np.sin(x[:, 0]) + a * np.sin(x[:, 1]) ** 2 + b * x[:, 2] ** 4 * np.sin(x[:, 0])


def ishigami_exact(a=7.0, b=0.1):
    v1 = 0.5 * (1 + b * np.pi**4 / 5) ** 2
    v2 = a**2 / 8
    v13 = b**2 * np.pi**8 * (1 / 18 - 1 / 50)
    v = v1 + v2 + v13
    return np.array([v1, v2, 0.0]) / v, np.array([v1 + v13, v2, v13]) / v


BOUNDS = np.array([[-np.pi] * 3, [np.pi] * 3])


def test_agrees_with_salib_on_the_same_runs():
    ua, ub = S.base_samples(256, 3, "sobol", 0)
    a, b = S.from_unit_uniform(ua, BOUNDS), S.from_unit_uniform(ub, BOUNDS)
    ya, yb, yab = S.sobol_evaluate(ishigami, a, b)
    s1, st = S.sobol_estimate(ya, yb, yab)
    # SALib's layout without second order: per base row A, AB_1..AB_D, B.
    y = np.concatenate([ya, yab[:, :, 0].T, yb], axis=1).ravel()
    problem = {"num_vars": 3, "names": ["x1", "x2", "x3"], "bounds": BOUNDS.T.tolist()}
    ref = salib_sobol.analyze(problem, y, calc_second_order=False, num_resamples=10, seed=1)
    assert np.allclose(s1[:, 0], ref["S1"], atol=1e-12)
    assert np.allclose(st[:, 0], ref["ST"], atol=1e-12)


@pytest.mark.parametrize("method", ["mc", "lhs", "sobol"])
def test_ishigami_converges_to_the_analytic_indices(method):
    ua, ub = S.base_samples(2**14, 3, method, 4)
    s1, st = S.sobol_indices(ishigami, S.from_unit_uniform(ua, BOUNDS),
                             S.from_unit_uniform(ub, BOUNDS))
    e1, et = ishigami_exact()
    assert np.allclose(s1[:, 0], e1, atol=0.04) and np.allclose(st[:, 0], et, atol=0.04)


def test_chunking_does_not_change_the_result_and_reports_progress():
    ua, ub = S.base_samples(100, 3, "mc", 2)
    seen = []
    one = S.sobol_evaluate(ishigami, ua, ub, chunk=10_000)
    many = S.sobol_evaluate(ishigami, ua, ub, chunk=37, progress=lambda d, t: seen.append((d, t)))
    for x, y in zip(one, many, strict=True):
        assert np.array_equal(x, y)
    assert seen[-1] == (500, 500) and len(seen) > 10


def test_bootstrap_half_width_shrinks_with_n():
    widths = []
    for n in (256, 4096):
        ua, ub = S.base_samples(n, 3, "mc", 3)
        ya, yb, yab = S.sobol_evaluate(ishigami, S.from_unit_uniform(ua, BOUNDS),
                                       S.from_unit_uniform(ub, BOUNDS))
        w1, wt = S.sobol_bootstrap(ya, yb, yab, 50, 0)
        assert w1.shape == wt.shape == (3, 1)
        widths.append(wt[1, 0])
    assert widths[1] < widths[0] / 2.5  # ~ 1/sqrt(N): factor 4 expected


def test_bad_input():
    with pytest.raises(ValueError, match="allowed: mc, lhs, sobol"):
        S.base_samples(8, 2, "halton", 0)
    with pytest.raises(ValueError, match="one shape"):
        S.sobol_evaluate(ishigami, np.zeros((4, 3)), np.zeros((5, 3)))


def test_linear_indices_equal_the_sampling_estimate_of_a_linear_model():
    jac = np.array([[2.0, -1.0, 0.5], [0.0, 0.0, 0.0]])
    sd = np.array([1.0, 3.0, 2.0])
    lin = S.linear_indices(jac, sd)
    assert np.allclose(lin[0], [4.0, 9.0, 1.0] / np.float64(14.0)) and not lin[1].any()
    ua, ub = S.base_samples(2**14, 3, "sobol", 5)
    s1, st = S.sobol_indices(lambda x: x @ jac[0], S.from_unit_normal(ua, sd),
                             S.from_unit_normal(ub, sd))
    assert np.allclose(st[:, 0], lin[0], atol=0.02) and np.allclose(s1[:, 0], lin[0], atol=0.02)

