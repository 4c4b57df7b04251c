"""Sparse polynomial chaos expansion (PCE) by orthogonal matching pursuit, and its Sobol indices.

Zheng et al. 2024 (Eqs. 13-23) fit a degree-3 Hermite PCE to 1000 samples with OMP in UQLab
and read Sobol indices off the coefficients.  Here: chaospy supplies the multi-index set
(``chaospy.glexindex``, total degree with optional hyperbolic q-norm truncation) and the
one-dimensional orthonormal Hermite family (``chaospy.expansion.hermite``); the design matrix
is built in numpy from the multi-indices (chaospy's multivariate polynomial objects are far too
slow in 41 dimensions); scikit-learn's ``orthogonal_mp`` gives the OMP path; the number of
terms along the path, and optionally the degree and q-norm, are chosen by the (corrected)
leave-one-out error, as UQLab does.  Inputs are standard normal variables ``xi``.
"""

from __future__ import annotations

__all__ = ["multi_indices", "hermite_table", "design_matrix", "loo_error", "PCEFit",
           "fit_pce", "select_pce", "pce_sobol"]

from dataclasses import dataclass

import numpy as np
from sklearn.linear_model import orthogonal_mp


def multi_indices(dim: int, degree: int, q_norm: float = 1.0) -> np.ndarray:
    """All multi-indices of total degree <= ``degree`` with q-norm <= degree, (P, dim)."""
    import chaospy

    if degree < 0 or dim < 1 or not 0 < q_norm <= 1:
        raise ValueError(f"need dim >= 1, degree >= 0, 0 < q_norm <= 1; got {dim}, {degree}, "
                         f"{q_norm}")
    return np.asarray(chaospy.glexindex(start=0, stop=degree + 1, dimensions=dim,
                                        cross_truncation=q_norm), dtype=np.int64)


def hermite_table(xi: np.ndarray, degree: int) -> np.ndarray:
    """Orthonormal (probabilists') Hermite polynomials He_k(x)/sqrt(k!) of every column,
    k = 0..degree: (degree + 1, n, d), from chaospy's one-dimensional family."""
    import chaospy

    xi = np.asarray(xi, dtype=float)
    polys = chaospy.expansion.hermite(degree, normed=True)
    return np.asarray(polys(xi.ravel()), dtype=float).reshape((degree + 1,) + xi.shape)


def design_matrix(xi: np.ndarray, alphas: np.ndarray) -> np.ndarray:
    """(n, P) matrix of the multivariate orthonormal Hermite polynomials ``alphas`` at ``xi``.

    Each column is a product over the non-zero entries of its multi-index, so the cost is
    n x P x (max number of non-zero entries), not n x P x d.
    """
    xi = np.asarray(xi, dtype=float)
    alphas = np.asarray(alphas)
    table = hermite_table(xi, int(alphas.max(initial=0)))
    k = int((alphas > 0).sum(axis=1).max(initial=0))
    order = np.argsort(-alphas, axis=1, kind="stable")[:, :max(k, 1)]  # non-zero entries first
    deg = np.take_along_axis(alphas, order, axis=1)
    psi_t = np.ones((alphas.shape[0], xi.shape[0]))  # built by rows: contiguous writes
    for j in range(order.shape[1]):
        use = np.flatnonzero(deg[:, j] > 0)
        psi_t[use] *= table[deg[use, j], :, order[use, j]]
    return psi_t.T


def loo_error(psi: np.ndarray, y: np.ndarray, corrected: bool = True) -> tuple[float, np.ndarray]:
    """Relative leave-one-out error of the least-squares fit of ``y`` on ``psi`` (n, k), from
    the hat matrix (no refits), and the coefficients.  ``corrected`` applies Chapelle's factor
    T(k, n) = n/(n-k) (1 + tr((psi^T psi / n)^-1)/n), as UQLab does."""
    n, k = psi.shape
    q, r = np.linalg.qr(psi)
    coef = np.linalg.solve(r, q.T @ y)
    h = np.sum(q * q, axis=1)
    res = (y - psi @ coef) / np.maximum(1.0 - h, 1e-12)
    err = float(np.mean(res**2) / np.var(y)) if np.var(y) > 0 else 0.0
    if corrected and n > k:
        rinv = np.linalg.inv(r)
        err *= n / (n - k) * (1.0 + n * np.sum(rinv * rinv) / n)
    return err, coef


@dataclass
class PCEFit:
    """A sparse PCE of one output: multi-indices and coefficients of the kept terms."""

    alphas: np.ndarray      # (k, d) kept multi-indices
    coef: np.ndarray        # (k,) coefficients
    loo: float              # corrected leave-one-out error of the kept model
    degree: int
    q_norm: float
    n_candidates: int       # size of the truncated basis OMP chose from

    def predict(self, xi: np.ndarray) -> np.ndarray:
        return design_matrix(xi, self.alphas) @ self.coef


def fit_pce(xi: np.ndarray, y: np.ndarray, degree: int = 3, q_norm: float = 1.0,
            max_terms: int | None = None, patience: int = 8, psi: np.ndarray | None = None,
            alphas: np.ndarray | None = None, target: float = 1e-8) -> PCEFit:
    """Sparse PCE of one output by OMP; the path length is chosen by corrected LOO.

    The OMP path (scikit-learn) runs to ``max_terms`` (default n/3); LOO is evaluated along it
    and the search stops ``patience`` steps after the best value, or as soon as the relative
    LOO error reaches the target accuracy ``target`` (the variance is then explained to about
    eight digits; further terms, e.g. tiny products of angular errors, cannot change a Sobol
    index visibly but can make the path hundreds of terms long).  The constant term is always
    kept.  ``psi``/``alphas`` may be passed to reuse a design matrix across outputs.
    """
    xi = np.asarray(xi, dtype=float)
    y = np.asarray(y, dtype=float)
    n, d = xi.shape
    if alphas is None:
        alphas = multi_indices(d, degree, q_norm)
    if psi is None:
        psi = design_matrix(xi, alphas)
    cap = min(max_terms or n // 3, alphas.shape[0] - 1, n - 2)
    yc = y - y.mean()
    norms = np.linalg.norm(psi[:, 1:], axis=0)
    norms[norms == 0] = 1.0
    scaled = np.asfortranarray(psi[:, 1:] / norms)
    length = min(64, cap)
    while True:  # grow the OMP path until the LOO optimum lies well inside it
        path = orthogonal_mp(scaled, yc, n_nonzero_coefs=length, return_path=True)
        path = path.reshape(path.shape[0], -1)
        best, since, seen, last = (np.inf, None, None), 0, set(), 0
        for step in range(path.shape[1]):
            support = tuple(np.flatnonzero(path[:, step]) + 1)
            if support in seen:
                continue
            seen.add(support)
            cols = [0, *support]
            err, coef = loo_error(psi[:, cols], y)
            if err < best[0]:
                best, since, last = (err, cols, coef), 0, step
                if err < target:
                    break
            else:
                since += 1
                if since >= patience:
                    break
        if best[0] < target or last < path.shape[1] - patience or length >= cap:
            break
        length = min(2 * length, cap)
    err, cols, coef = best
    return PCEFit(alphas[cols], coef, err, degree, q_norm, alphas.shape[0])


def select_pce(xi, y, degrees=(1, 2, 3), q_norms=(0.5, 0.75, 1.0), **kw) -> tuple[PCEFit, list]:
    """Fit every (degree, q-norm) and keep the one with the smallest corrected LOO error.
    Returns the best fit and a list of (degree, q_norm, basis size, kept terms, LOO)."""
    fits, table = [], []
    for p in degrees:
        for q in q_norms:
            f = fit_pce(xi, y, degree=p, q_norm=q, **kw)
            fits.append(f)
            table.append((p, q, f.n_candidates, len(f.coef), f.loo))
    return min(fits, key=lambda f: f.loo), table


def pce_sobol(fit: PCEFit) -> tuple[np.ndarray, np.ndarray]:
    """First-order and total Sobol indices (d,) from the coefficients (Eq. 23): the variance
    of an orthonormal PCE is the sum of its squared non-constant coefficients."""
    a = fit.alphas
    c2 = fit.coef**2
    nonconst = a.sum(axis=1) > 0
    var = c2[nonconst].sum()
    if var == 0:
        return np.zeros(a.shape[1]), np.zeros(a.shape[1])
    active = a > 0
    only = active & (active.sum(axis=1, keepdims=True) == 1)
    return (c2[:, None] * only).sum(axis=0) / var, (c2[:, None] * active).sum(axis=0) / var
