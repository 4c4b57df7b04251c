"""Sparse polynomial chaos expansion (PCE) by orthogonal matching pursuit, and its Sobol indices.

Zheng et al. 2024 (Eqs. 13-23) fit a degree-3 Hermite PCE to 1000 samples with OMP in UQLab
and read Sobol indices off the coefficients.  Here: chaospy supplies the multi-index set
(``chaospy.glexindex``, total degree with optional hyperbolic q-norm truncation) and the
one-dimensional orthonormal Hermite family (``chaospy.expansion.hermite``); the design matrix
is built in numpy from the multi-indices (chaospy's multivariate polynomial objects are far too
slow in 41 dimensions); scikit-learn's ``orthogonal_mp`` gives the OMP path; the number of
terms along the path, and optionally the degree and q-norm, are chosen by the (corrected)
leave-one-out error, as UQLab does, with differences below :data:`LOO_RTOL` and errors below
the target accuracy treated as ties that go to the smallest basis (:func:`pce_selection_order`).
Inputs are standard normal variables ``xi``.
"""

from __future__ import annotations

__all__ = ["multi_indices", "hermite_table", "design_matrix", "loo_error", "loo_path", "PCEFit",
           "fit_pce", "fit_pce_outputs", "LOO_RTOL", "TARGET", "pce_selection_order", "select_pce",
           "pce_sobol"]

import functools
from dataclasses import dataclass

import numpy as np
from sklearn.linear_model import orthogonal_mp
from threadpoolctl import threadpool_limits

from .screening import rank_with_ties

#: Corrected leave-one-out errors closer than this (relative) are ties in model selection:
#: far above their rounding noise (about 1e-12 relative for the designs here), far below any
#: difference that would make one basis predict better than another.
LOO_RTOL = 1e-6

#: Default target accuracy of :func:`fit_pce` (relative corrected LOO error).
TARGET = 1e-8


def multi_indices(dim: int, degree: int, q_norm: float = 1.0) -> np.ndarray:
    """All multi-indices of total degree <= ``degree`` with q-norm <= degree, (P, dim)
    (a fresh copy of a cached table: chaospy takes a quarter of a second for 41 dimensions at
    degree 3)."""
    if degree < 0 or dim < 1 or not 0 < q_norm <= 1:
        raise ValueError(f"need dim >= 1, degree >= 0, 0 < q_norm <= 1; got {dim}, {degree}, "
                         f"{q_norm}")
    return _multi_indices(int(dim), int(degree), float(q_norm)).copy()


@functools.lru_cache(maxsize=16)
def _multi_indices(dim: int, degree: int, q_norm: float) -> np.ndarray:
    import chaospy

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


def loo_path(psi: np.ndarray, y: np.ndarray, corrected: bool = True) -> np.ndarray:
    """:func:`loo_error` of the fits of ``y`` on every leading block ``psi[:, :k]``,
    k = 1..K, from one QR factorisation: the QR of a leading block is the leading part of the
    QR of the whole, so hat-matrix diagonals, residuals and the trace of the inverse Gram
    matrix are cumulative sums over the columns of Q and R^-1.  Returns (K,) errors; equal to
    :func:`loo_error` on each block up to rounding (a test checks it)."""
    n, kk = psi.shape
    q, r = np.linalg.qr(psi)
    qy = q.T @ y
    h = np.cumsum(q * q, axis=1)                               # (n, K) hat diagonals
    res = y[:, None] - np.cumsum(q * qy, axis=1)               # (n, K) residuals
    var = np.var(y)
    if var <= 0:
        return np.zeros(kk)
    err = np.mean((res / np.maximum(1.0 - h, 1e-12)) ** 2, axis=0) / var
    if corrected:
        k = np.arange(1, kk + 1)
        rinv = np.linalg.inv(r)                                 # upper triangular
        tr = np.cumsum(np.sum(rinv * rinv, axis=0))             # ||R_k^-1||_F^2
        fac = np.where(n > k, n / np.maximum(n - k, 1) * (1.0 + tr), 1.0)
        err = err * fac
    return err


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
            alphas: np.ndarray | None = None, target: float = TARGET) -> PCEFit:
    """Sparse PCE of one output by OMP; the path length is chosen by corrected LOO.

    The OMP path (scikit-learn) runs to ``max_terms`` (default n/3); LOO is evaluated along it
    and the search stops ``patience`` steps after the best value, or as soon as the relative
    LOO error reaches the target accuracy ``target`` (the variance is then explained to about
    eight digits; further terms, e.g. tiny products of angular errors, cannot change a Sobol
    index visibly but can make the path hundreds of terms long).  The constant term is always
    kept.  ``psi``/``alphas`` may be passed to reuse a design matrix across outputs (or use
    :func:`fit_pce_outputs`, which also shares the scaled copy OMP works on).
    """
    y = np.asarray(y, dtype=float)
    return fit_pce_outputs(xi, y[:, None], degree, q_norm, max_terms, patience, psi, alphas,
                           target)[0]


def fit_pce_outputs(xi: np.ndarray, y: np.ndarray, degree: int = 3, q_norm: float = 1.0,
                    max_terms: int | None = None, patience: int = 8,
                    psi: np.ndarray | None = None, alphas: np.ndarray | None = None,
                    target: float = TARGET) -> list[PCEFit]:
    """:func:`fit_pce` for every column of ``y`` (n, q) on one design: the basis, the design
    matrix and its column-normalised copy are built once.

    The OMP path is computed first to 16 terms and doubled (or taken to the cap when that is
    near) until the LOO search has concluded inside it; OMP is greedy, so a path is a prefix
    of any longer one and the result does not depend on how the path grows.  BLAS runs
    single-threaded here: the result is then the same for any thread count, and the many
    small BLAS calls of OMP and the LOO search do not stall when another process shares the
    cores.
    """
    with threadpool_limits(limits=1, user_api="blas"):
        return _fit_pce_outputs(xi, y, degree, q_norm, max_terms, patience, psi, alphas, target)


def _fit_pce_outputs(xi, y, degree, q_norm, max_terms, patience, psi, alphas, target):
    xi = np.asarray(xi, dtype=float)
    y = np.asarray(y, dtype=float)
    if y.ndim != 2 or y.shape[0] != xi.shape[0]:
        raise ValueError(f"y must be (n, q) with n = {xi.shape[0]} rows, got {y.shape}")
    n, d = xi.shape
    if alphas is None:
        alphas = multi_indices(d, degree, q_norm)
    if psi is None:
        psi = design_matrix(xi, alphas)
    cap = min(max_terms or n // 3, alphas.shape[0] - 1, n - 2)
    norms = np.linalg.norm(psi[:, 1:], axis=0)
    norms[norms == 0] = 1.0
    scaled = np.asfortranarray(psi[:, 1:] / norms)
    fits = []
    for col in y.T:
        yc = col - col.mean()
        length = min(16, cap)
        while True:  # grow the OMP path until the LOO optimum lies well inside it
            path = orthogonal_mp(scaled, yc, n_nonzero_coefs=length, return_path=True)
            path = np.ascontiguousarray(path.reshape(path.shape[0], -1).T)  # (steps, P - 1)
            order, steps = [0], []  # columns in the order OMP took them; path step per size
            for step in range(path.shape[0]):
                new = np.setdiff1d(np.flatnonzero(path[step]) + 1, order[1:])
                if new.size:  # the path is nested: one new column per step
                    order += [int(c) for c in new]
                    steps.append(step)
            errs = loo_path(psi[:, order], col)[len(order) - len(steps):]
            best, since, last = (np.inf, 0), 0, 0
            for i, step in enumerate(steps):
                if errs[i] < best[0]:
                    best, since, last = (errs[i], i), 0, step
                    if errs[i] < target:
                        break
                else:
                    since += 1
                    if since >= patience:
                        break
            if best[0] < target or last < path.shape[0] - patience or length >= cap:
                break
            length = cap if 2 * length >= 0.75 * cap else 2 * length  # no short last step
        cols = order[:len(order) - len(steps) + best[1] + 1]
        cols = [0, *sorted(cols[1:])]  # the support in basis order, as the path stores it
        err, coef = loo_error(psi[:, cols], col)
        fits.append(PCEFit(alphas[cols], coef, err, degree, q_norm, alphas.shape[0]))
    return fits


def pce_selection_order(loo, basis, terms, degree, q_norm, rtol: float = LOO_RTOL,
                        floor: float = 0.0) -> np.ndarray:
    """Canonical ranking of candidate PCEs (one entry per fit) for model selection.

    Corrected LOO errors are first floored at ``floor`` (the target accuracy of the fits:
    below it every fit is as good as was asked for) and then compared with ties within
    ``rtol`` (relative); ties go to the smallest basis, then the fewest kept terms, the
    lowest degree and the smallest q-norm.  Returns indices, best first.
    """
    loo = np.asarray(loo, dtype=float)
    if not 0 <= floor < np.inf:
        raise ValueError(f"floor must be finite and >= 0, got {floor!r}")
    keys = np.c_[basis, terms, degree, q_norm].astype(float)
    return rank_with_ties(np.maximum(loo, floor), keys, rtol=rtol)


def select_pce(xi, y, degrees=(1, 2, 3), q_norms=(0.5, 0.75, 1.0), rtol: float = LOO_RTOL,
               **kw) -> tuple[PCEFit, list]:
    """Fit every (degree, q-norm) and keep the best by corrected LOO error, differences
    below ``rtol`` (relative) and LOO errors below the fits' target accuracy (``target``,
    see :func:`fit_pce`) being ties that go to the smallest basis
    (:func:`pce_selection_order`).  Returns the chosen fit and a list of (degree, q_norm,
    basis size, kept terms, LOO) in grid order."""
    fits, table = [], []
    for p in degrees:
        for q in q_norms:
            f = fit_pce(xi, y, degree=p, q_norm=q, **kw)
            fits.append(f)
            table.append((p, q, f.n_candidates, len(f.coef), f.loo))
    t = np.array(table, dtype=float)
    floor = kw.get("target", TARGET)
    order = pce_selection_order(t[:, 4], t[:, 2], t[:, 3], t[:, 0], t[:, 1], rtol, floor)
    return fits[order[0]], table


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
