"""Least squares, leave-one-out errors and the sparse solver paths of a PCE (OMP, LARS).

:func:`loo_error` and :func:`loo_path` give the (corrected) leave-one-out error of least-squares
fits from the hat matrix, without refits; :func:`omp_path` is orthogonal matching pursuit with an
incremental QR and the corrected LOO error along the way (it stops when the error has not
improved for ``patience`` steps), :func:`lars_order` the order in which
``sklearn.linear_model.lars_path`` activates the terms.  Why OMP is written here and not taken
from scikit-learn: see :mod:`mtaccuracy.sensitivity.pce`.
"""

from __future__ import annotations

__all__ = ["loo_error", "loo_path", "column_norms", "omp_path", "lars_order"]

import warnings

import numpy as np

# ------------------------------------------------------------------------------------------
# Least squares and leave-one-out errors.
# ------------------------------------------------------------------------------------------

def loo_error(psi: np.ndarray, y: np.ndarray, corrected: bool = True) -> tuple[float, np.ndarray]:
    """Relative leave-one-out error of the least-squares fit of ``y`` on ``psi``, and coefficients.

    From the hat matrix (no refits).  ``corrected`` applies Chapelle's factor
    T(k, n) = n/(n-k) (1 + tr((psi^T psi / n)^-1)/n), as UQLab does.

    Parameters
    ----------
    psi : array (n, k)
        Design matrix.
    y : array (n,)
        The output.
    corrected : bool
        Apply Chapelle's factor.

    Returns
    -------
    error : float
        Relative LOO error.
    coef : array (k,)
    """
    n, k = psi.shape
    q, r = np.linalg.qr(psi)
    coef = np.linalg.solve(r, q.T @ y)
    h = np.sum(q * q, axis=1)
    res = (y - psi @ coef) / np.maximum(1.0 - h, 1e-12)
    err = float(np.mean(res**2) / np.var(y)) if np.var(y) > 0 else 0.0
    if corrected and n > k:
        rinv = np.linalg.inv(r)
        err *= n / (n - k) * (1.0 + np.sum(rinv * rinv))
    return err, coef


def loo_path(psi: np.ndarray, y: np.ndarray, corrected: bool = True) -> np.ndarray:
    """:func:`loo_error` of the fits of ``y`` on every leading block ``psi[:, :k]``, k = 1..K.

    From one QR factorisation: the QR of a leading block is the leading part of the
    QR of the whole, so hat-matrix diagonals, residuals and the trace of the inverse Gram
    matrix are cumulative sums over the columns of Q and R^-1.  Returns (K,) errors; equal to
    :func:`loo_error` on each block up to rounding (a test checks it).

    Parameters
    ----------
    psi : array (n, K)
        Design matrix, columns in path order.
    y : array (n,)
        The output.
    corrected : bool
        Apply Chapelle's factor.

    Returns
    -------
    array (K,)
    """
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
        fac = np.where(n > k, n / np.maximum(n - k, 1) * (1.0 + tr), np.inf)
        err = err * fac
    return err


def _prefix_coefficients(psi_sel: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Least-squares coefficients of ``y`` on every leading block of ``psi_sel`` (n, K): (K, K)
    upper triangular, column k the coefficients of the first k + 1 columns (R^-1 Q^T y summed
    cumulatively, from one QR)."""
    q, r = np.linalg.qr(psi_sel)
    qy = q.T @ y
    return np.cumsum(np.linalg.inv(r) * qy[None, :], axis=1)


# ------------------------------------------------------------------------------------------
# Sparse solver paths.
# ------------------------------------------------------------------------------------------

def column_norms(psi: np.ndarray) -> np.ndarray:
    """Euclidean norms of the columns of ``psi`` (n, P), rows of its contiguous transpose.

    Parameters
    ----------
    psi : array (n, P)
        A design matrix: n samples of P basis polynomials.

    Returns
    -------
    array (P,)
        The norms, 1 for an all-zero column (so that dividing by them leaves it zero).
    """
    t = psi.T if psi.flags.f_contiguous else np.ascontiguousarray(psi.T)
    norms = np.sqrt(np.einsum("ij,ij->i", t, t))
    norms[norms == 0] = 1.0
    return norms


def omp_path(psi: np.ndarray, y: np.ndarray, *, max_terms: int | None = None,
             patience: int | None = 8, target: float = 0.0, norms: np.ndarray | None = None,
             rows: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Orthogonal matching pursuit with the constant always in, and the LOO error of every prefix.

    OMP on the non-constant columns ``psi[:, 1:]``, the constant column ``psi[:, 0]`` always in
    the model, with the corrected LOO error of the least-squares fit on every prefix of the path.

    Each step takes the column of largest ``|correlation|`` with the residual (columns compared
    at unit norm; ties go to the first), orthogonalises it against the columns taken (classical
    Gram-Schmidt, twice) and updates the residual, the hat-matrix diagonal and the trace of the
    inverse Gram matrix that the corrected LOO needs (O(n k) per step besides the one
    correlation pass over the matrix).  The path stops after ``max_terms`` terms (default:
    n - 2, the most a leave-one-out error allows), when a column is dependent on those taken,
    ``patience`` steps after the best LOO error (None: never), or as soon as the LOO error is
    below ``target``.  ``rows`` restricts the fit to those rows of ``psi`` (the training part of
    a fold) without copying the matrix: the other rows get weight zero, so the correlation pass
    reads the matrix as it is.

    Returns ``order`` (K,): the columns taken (indices into ``psi``, all >= 1), and ``loo``
    (K + 1,): the corrected relative LOO error with the constant plus the first k columns,
    k = 0..K (equal to :func:`loo_path` on ``psi[:, [0, *order]]``; a test checks it).

    Parameters
    ----------
    psi : array (n, P)
        Design matrix, constant column first.
    y : array (n,)
        The output.
    max_terms : int, optional
        Longest path.
    patience : int, optional
        Steps after the best LOO error before stopping (None: never early).
    target : float
        Relative LOO error at which to stop.
    norms : array (P,), optional
        :func:`column_norms` of ``psi``.
    rows : array of int, optional
        Rows used (a training fold).

    Returns
    -------
    order : array of int
        Columns taken, in order.
    loo : array
        Corrected LOO error of every prefix.
    """
    y = np.asarray(y, dtype=float)
    n, p = psi.shape
    if rows is None:
        w = None
        m = n
    else:  # a fold: rows outside it get weight 0 (no copy of the matrix)
        w = np.zeros(n)
        w[rows] = 1.0
        m = int(w.sum())
        y = y * w
    if norms is None:
        norms = column_norms(psi)
    cap = min(max_terms if max_terms is not None else m - 2, p - 1, m - 2)
    var = float(np.var(y)) if w is None else float(np.var(y[w > 0]))
    big = max(cap, 0) + 1
    qmat = np.empty((n, big))
    rinv = np.zeros((big, big))                  # inverse R factor of the unscaled columns
    col0 = psi[:, 0] if w is None else psi[:, 0] * w
    qmat[:, 0] = col0 / np.linalg.norm(col0)
    rinv[0, 0] = 1 / float(col0 @ qmat[:, 0])
    trace = rinv[0, 0] ** 2
    h = qmat[:, 0] ** 2
    res = y - qmat[:, 0] * (qmat[:, 0] @ y)
    taken = np.zeros(p, dtype=bool)
    taken[0] = True
    order, loo = [], []

    def corrected(k):  # k columns in the model, constant included; rows outside add 0
        if var <= 0:
            return 0.0
        e = float(np.sum((res / np.maximum(1.0 - h, 1e-12)) ** 2) / m / var)
        return e * m / (m - k) * (1.0 + trace) if m > k else np.inf

    loo.append(corrected(1))
    best, since = loo[0], 0
    inv_norms = 1.0 / norms
    for k in range(1, cap + 1):
        if var <= 0 or best < target:
            break
        c = np.abs(psi.T @ res) * inv_norms
        c[taken] = -1.0
        j = int(np.argmax(c))
        if c[j] <= 0:
            break
        col = psi[:, j] if w is None else psi[:, j] * w
        qk = qmat[:, :k]
        proj = qk.T @ col
        v = col - qk @ proj
        corr = qk.T @ v
        v -= qk @ corr
        proj += corr
        rkk = float(np.linalg.norm(v))
        if rkk <= 1e-10 * norms[j]:
            taken[j] = True  # dependent on the columns taken: never a useful term
            continue
        qmat[:, k] = v / rkk
        newcol = -(rinv[:k, :k] @ proj) / rkk
        rinv[:k, k] = newcol
        rinv[k, k] = 1.0 / rkk
        trace += float(newcol @ newcol) + rinv[k, k] ** 2
        h = h + qmat[:, k] ** 2
        res = res - qmat[:, k] * (qmat[:, k] @ res)
        taken[j] = True
        order.append(j)
        loo.append(corrected(len(order) + 1))
        if loo[-1] < best:
            best, since = loo[-1], 0
        else:
            since += 1
            if patience is not None and since >= patience:
                break
    return np.asarray(order, dtype=np.int64), np.asarray(loo)


def lars_order(psi: np.ndarray, y: np.ndarray, *, max_terms: int,
               rows: np.ndarray | None = None) -> np.ndarray:
    """The non-constant columns of ``psi`` in the order least-angle regression activates them.

    ``sklearn.linear_model.lars_path``, method ``lar`` (columns only enter), on centred
    columns at unit norm; at most ``max_terms``.  The least-squares fits on its
    prefixes ("hybrid LARS", Blatman & Sudret 2011) are evaluated as for OMP.

    Parameters
    ----------
    psi : array (n, P)
        Design matrix, constant column first.
    y : array (n,)
        The output.
    max_terms : int
        Longest path.
    rows : array of int, optional
        Rows used (a training fold).

    Returns
    -------
    array of int
        Column indices in activation order.
    """
    # local: scikit-learn's import takes half a second, and only the LARS solver needs it
    from sklearn.exceptions import ConvergenceWarning
    from sklearn.linear_model import lars_path

    x = psi[:, 1:] if rows is None else psi[rows][:, 1:]
    yy = np.asarray(y, dtype=float) if rows is None else np.asarray(y, dtype=float)[rows]
    x = x - x.mean(axis=0)
    nrm = np.linalg.norm(x, axis=0)
    nrm[nrm == 0] = 1.0
    x /= nrm
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        _, active, _ = lars_path(x, yy - yy.mean(), method="lar", max_iter=int(max_terms),
                                 return_path=False, copy_X=False)
    return np.asarray(active, dtype=np.int64)[:max_terms] + 1


def _solver_path(psi, y, method, max_terms, patience, target, norms, rows=None):
    """``(order, loo)`` of :func:`omp_path` for OMP, or of LARS's order with :func:`loo_path`
    (grown by doubling until ``patience`` steps past the best LOO or the cap)."""
    if method == "omp":
        return omp_path(psi, y, max_terms=max_terms, patience=patience, target=target,
                        norms=norms, rows=rows)
    if method != "lars":
        raise ValueError(f"unknown sparse solver {method!r}; allowed: omp, lars")
    n = psi.shape[0] if rows is None else len(rows)
    cap = min(max_terms if max_terms is not None else n - 2, psi.shape[1] - 1, n - 2)
    length = min(32, cap)
    yy = y if rows is None else y[rows]
    while True:
        order = lars_order(psi, y, max_terms=length, rows=rows)
        sub = psi[:, [0, *order]] if rows is None else psi[np.ix_(rows, [0, *order])]
        loo = loo_path(sub, yy)
        best = int(np.argmin(loo))
        if (patience is None or best <= len(order) - patience or len(order) < length
                or length >= cap or loo[best] < target):
            break
        length = min(2 * length, cap)
    if patience is not None:
        stop = min(len(order), best + patience)
        order, loo = order[:stop], loo[:stop + 1]
    return order, loo
