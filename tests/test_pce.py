"""Sparse PCE: basis, design matrix, OMP fit and Sobol indices on analytic cases."""

import numpy as np
import pytest
from numpy.polynomial import hermite_e

from mtaccuracy import sensitivity as S

RNG = np.random.default_rng(8)


def test_hermite_family_is_orthonormal():
    x, w = hermite_e.hermegauss(20)
    w = w / w.sum()
    t = S.hermite_table(x[:, None], 4)[:, :, 0]
    assert np.allclose((t * w) @ t.T, np.eye(5), atol=1e-12)


def test_multi_index_counts():
    assert S.multi_indices(41, 3).shape == (13244, 41)  # C(44, 3)
    a = S.multi_indices(5, 3, 0.5)
    assert len(a) < len(S.multi_indices(5, 3)) and (a.sum(axis=1) <= 3).all()
    with pytest.raises(ValueError, match="q_norm"):
        S.multi_indices(3, 2, 1.5)


def test_design_matrix_equals_direct_products():
    xi = RNG.standard_normal((7, 4))
    alphas = S.multi_indices(4, 3)
    psi = S.design_matrix(xi, alphas)
    t = S.hermite_table(xi, 3)
    for k in RNG.choice(len(alphas), 10, replace=False):
        direct = np.prod([t[alphas[k, i], :, i] for i in range(4)], axis=0)
        assert np.allclose(psi[:, k], direct)


def interacting(xi, a=1.0, b=0.8, c=0.6):
    """a He1(x1) + b He2(x2)/sqrt2 + c He1(x1) He1(x3): x3 acts only through x1 (Ishigami-like)."""
    return a * xi[:, 0] + b * (xi[:, 1] ** 2 - 1) / np.sqrt(2) + c * xi[:, 0] * xi[:, 2]


def analytic(a=1.0, b=0.8, c=0.6, d=5):
    v = a**2 + b**2 + c**2
    s1 = np.zeros(d)
    st = np.zeros(d)
    s1[0], s1[1] = a**2 / v, b**2 / v
    st[0], st[1], st[2] = (a**2 + c**2) / v, b**2 / v, c**2 / v
    return s1, st


def test_pce_recovers_analytic_indices_of_linear_and_interacting_functions():
    xi = RNG.standard_normal((200, 5))
    coef = np.array([3.0, -2.0, 1.0, 0.5, 0.0])
    fit = S.fit_pce(xi, xi @ coef + 4.0, degree=3)
    s1, st = S.pce_sobol(fit)
    assert np.allclose(s1, coef**2 / (coef**2).sum(), atol=1e-10) and np.allclose(st, s1)
    assert fit.loo < 1e-20
    fit = S.fit_pce(xi, interacting(xi), degree=3)
    e1, et = analytic()
    got1, gott = S.pce_sobol(fit)
    assert np.allclose(got1, e1, atol=1e-10) and np.allclose(gott, et, atol=1e-10)


def test_sampling_estimators_agree_with_the_same_analytic_indices():
    ua, ub = S.base_samples(2**14, 5, "lhs", 3)
    s1, st = S.sobol_indices(interacting, S.from_unit_normal(ua, np.ones(5)),
                             S.from_unit_normal(ub, np.ones(5)))
    e1, et = analytic()
    assert np.allclose(s1[:, 0], e1, atol=0.03) and np.allclose(st[:, 0], et, atol=0.03)


def test_selection_prefers_the_needed_degree():
    xi = RNG.standard_normal((150, 3))
    y = xi[:, 0] + 0.5 * (xi[:, 1] ** 2 - 1)
    best, table = S.select_pce(xi, y, degrees=(1, 2), q_norms=(1.0,))
    assert best.degree == 2 and len(table) == 2
    assert table[0][4] > 1e3 * table[1][4]  # degree 1 cannot fit the square


def test_loo_error_equals_brute_force_leave_one_out():
    psi = np.c_[np.ones(30), RNG.standard_normal((30, 3))]
    y = psi @ [1.0, 2.0, -1.0, 0.5] + 0.1 * RNG.standard_normal(30)
    err, _ = S.loo_error(psi, y, corrected=False)
    res = []
    for i in range(30):
        keep = np.arange(30) != i
        c = np.linalg.lstsq(psi[keep], y[keep], rcond=None)[0]
        res.append(y[i] - psi[i] @ c)
    assert err == pytest.approx(np.mean(np.square(res)) / np.var(y), rel=1e-10)
