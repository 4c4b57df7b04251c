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


def test_loo_path_equals_loo_error_on_every_leading_block():
    psi = np.c_[np.ones(40), RNG.standard_normal((40, 6))]
    y = psi @ RNG.standard_normal(7) + 0.05 * RNG.standard_normal(40)
    path = S.loo_path(psi, y)
    each = [S.loo_error(psi[:, :k], y)[0] for k in range(1, 8)]
    assert np.allclose(path, each, rtol=1e-10, atol=0)
    assert np.allclose(S.loo_path(psi, y, corrected=False),
                       [S.loo_error(psi[:, :k], y, corrected=False)[0] for k in range(1, 8)],
                       rtol=1e-10, atol=0)


def test_fit_pce_outputs_equals_one_fit_per_column():
    xi = RNG.standard_normal((120, 4))
    y = np.c_[interacting(xi[:, [0, 1, 2]]), xi[:, 3] - 0.3 * (xi[:, 0] ** 2 - 1)]
    both = S.fit_pce_outputs(xi, y, degree=2)
    for k in range(2):
        one = S.fit_pce(xi, y[:, k], degree=2)
        assert np.array_equal(both[k].alphas, one.alphas) and np.allclose(both[k].coef, one.coef)
        assert both[k].loo == pytest.approx(one.loo, rel=1e-12)
    with pytest.raises(ValueError, match=r"\(n, q\)"):
        S.fit_pce_outputs(xi, y[:50])


def test_selection_treats_rounding_level_differences_as_ties():
    # three bases whose LOO errors differ only in the twelfth digit: the smallest basis wins,
    # whichever happens to be smallest by rounding
    basis, terms, degree, q = [42, 903, 13244], [32, 32, 32], [1, 2, 3], [1.0, 1.0, 1.0]
    for loo in ([2e-3 * (1 + 1e-12), 2e-3, 2e-3 * (1 - 1e-12)], [2e-3, 2e-3 * (1 + 1e-12), 2e-3]):
        assert S.pce_selection_order(loo, basis, terms, degree, q)[0] == 0
    # a real difference wins over the size of the basis
    assert S.pce_selection_order([2e-3, 1e-3, 2e-3], basis, terms, degree, q)[0] == 1
    # below the target accuracy every fit is as good as asked for: ties, even at a factor 2
    assert S.pce_selection_order([2e-9, 1e-9, 3e-9], basis, terms, degree, q, floor=1e-8)[0] == 0
    assert S.pce_selection_order([2e-9, 1e-9, 3e-9], basis, terms, degree, q)[0] == 1
    # equal basis: fewer terms, then lower degree, then smaller q-norm
    assert S.pce_selection_order([1.0, 1.0], [83, 83], [5, 4], [2, 2], [0.5, 0.5])[0] == 1
    assert S.pce_selection_order([1.0, 1.0], [83, 83], [5, 5], [2, 2], [0.75, 0.5])[0] == 1


def test_select_pce_on_a_linear_model_takes_the_smallest_basis():
    xi = RNG.standard_normal((200, 5))
    # linear, but for 2e-5 of the variance
    y = xi @ np.array([1.0, -0.5, 0.3, 0.0, 2.0]) + 0.01 * (xi[:, 0] * xi[:, 1])
    # the grid lists the largest basis first: equal LOO errors must not go to the first one
    best, table = S.select_pce(xi, y, degrees=(3, 2, 1), q_norms=(1.0, 0.5), target=1e-3)
    assert all(row[4] < 1e-3 for row in table)  # every basis reaches the target accuracy
    assert (best.degree, best.n_candidates) == (1, 6)
