"""Sparse polynomial chaos expansion (PCE) with basis adaptivity, and its Sobol indices.

Zheng et al. 2024 (Eqs. 13-23) fit a degree-3 Hermite PCE to 1000 samples with orthogonal
matching pursuit (OMP) in UQLab and read Sobol indices off the coefficients.  This module does
that, and what UQLab and OpenTURNS do around it (Blatman & Sudret 2011; the UQLab PCE manual,
Sec. 1.3-1.5):

* **Bases by input law** (:class:`~mtaccuracy.sensitivity.Inputs`).  Each input's law picks its
  orthonormal family (Wiener-Askey): Legendre for a uniform input (mapped to [-1, 1]), Hermite
  for a normal one (standardised), and for any other law the isoprobabilistic transform to a
  standard normal (z = Phi^-1(F(x))) with Hermite.  The one-dimensional families are chaospy's
  (``chaospy.expansion.hermite`` / ``legendre``, ``normed=True``); the multi-indices are
  chaospy's ``glexindex`` (total degree with hyperbolic q-norm truncation); the design matrix is
  built in numpy from them (chaospy's multivariate polynomial objects are far too slow in 41
  dimensions).
* **Sparse solver paths**: OMP (:func:`omp_path`, the paper's) and LARS
  (``sklearn.linear_model.lars_path``), each followed by least squares on the selected terms
  (hybrid LARS/OMP), with the corrected leave-one-out error along the path (:func:`loo_path`).
* **Model selection that does not fool itself** (:func:`fit_sparse_pce`): degree and q-norm
  adaptivity by corrected LOO (UQLab), then a k-fold validation of the *whole* selection
  procedure (the path is re-run on each training part, so the choice of terms is validated,
  not only their coefficients): the number of terms is where that validation error stops
  improving, the error is reported beside LOO, and a fit whose validation error exceeds
  :data:`POOR_FIT` raises :class:`PoorFitWarning` instead of returning confident indices.

Why OMP is written here and not taken from scikit-learn: ``orthogonal_mp`` cannot stop on a
criterion, so a path must be recomputed to grow, and it copies (or needs a column-normalised
copy of) the design matrix on each call.  :func:`omp_path` keeps an incremental QR of the
selected columns and the corrected LOO error along the way, and stops as soon as the error has
not improved for ``patience`` steps: on the Zheng model (13,244 candidates) the fit takes a
third of the time of the scikit-learn path.  A test checks that both pick the same terms.
"""

from __future__ import annotations

__all__ = ["multi_indices", "hermite_table", "poly_table", "design_matrix",
           "loo_error", "loo_path", "column_norms", "omp_path", "lars_order",
           "validation_curve", "PCEFit", "fit_pce",
           "fit_pce_outputs", "LOO_RTOL", "TARGET", "POOR_FIT", "PoorFitWarning",
           "pce_selection_order", "select_pce", "SparsePCE", "fit_sparse_pce", "pce_sobol"]

import functools
import warnings
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from threadpoolctl import threadpool_limits

from ..validate import integer, rng
from .inputs import Inputs
from .screening import rank_with_ties

#: Corrected leave-one-out errors closer than this (relative) are ties in model selection:
#: far above their rounding noise (about 1e-12 relative for the designs here), far below any
#: difference that would make one basis predict better than another.
LOO_RTOL = 1e-6

#: Default target accuracy of :func:`fit_pce` (relative corrected LOO error).
TARGET = 1e-8

#: A validation error (relative mean square, i.e. the unexplained share of the variance) above
#: this makes :func:`fit_sparse_pce` warn: the indices are sums of squared coefficients over the
#: explained share, so an index of a few per cent is then within the unexplained part.
POOR_FIT = 0.05

FAMILIES = ("hermite", "legendre")


class PoorFitWarning(UserWarning):
    """The PCE does not represent the model well enough for its indices to be trusted."""


# ------------------------------------------------------------------------------------------
# Basis and design matrix.
# ------------------------------------------------------------------------------------------

def multi_indices(dim: int, degree: int, q_norm: float = 1.0) -> np.ndarray:
    """All multi-indices of total degree <= ``degree`` with q-norm <= degree, (P, dim).

    Hyperbolic truncation (Blatman & Sudret 2011): (sum_i a_i^q)^(1/q) <= degree.  A fresh
    copy of a cached table: chaospy takes a quarter of a second for 41 dimensions at degree 3.

    >>> multi_indices(2, 2).tolist()
    [[0, 0], [1, 0], [2, 0], [0, 1], [1, 1], [0, 2]]

    Parameters
    ----------
    dim : int
        d.
    degree : int
        Total degree.
    q_norm : float
        In (0, 1].

    Returns
    -------
    array of int (P, dim)
    """
    if degree < 0 or dim < 1 or not 0 < q_norm <= 1:
        raise ValueError(f"need dim >= 1, degree >= 0, 0 < q_norm <= 1; got {dim}, {degree}, "
                         f"{q_norm}")
    return _multi_indices(int(dim), int(degree), float(q_norm)).copy()


@functools.lru_cache(maxsize=32)
def _multi_indices(dim: int, degree: int, q_norm: float) -> np.ndarray:
    import chaospy  # local: chaospy (numpoly) takes a second to import, only bases need it

    return np.asarray(chaospy.glexindex(start=0, stop=degree + 1, dimensions=dim,
                                        cross_truncation=q_norm), dtype=np.int64)


@functools.lru_cache(maxsize=16)
def _family(name: str, degree: int):
    import chaospy  # local: chaospy (numpoly) takes a second to import, only bases need it

    if name == "hermite":
        return chaospy.expansion.hermite(degree, normed=True)
    if name == "legendre":
        return chaospy.expansion.legendre(degree, lower=-1, upper=1, normed=True)
    raise ValueError(f"unknown polynomial family {name!r}; allowed: {', '.join(FAMILIES)}")


def poly_table(z: np.ndarray, degree: int, families="hermite") -> np.ndarray:
    """Orthonormal one-dimensional polynomials of every column of ``z``, degrees 0..degree.

    ``families``: one name for all columns or one per column (``hermite``: He_k/sqrt(k!),
    orthonormal for the standard normal; ``legendre``: sqrt(2k+1) P_k, orthonormal for the
    uniform law on [-1, 1]); chaospy's families.

    Parameters
    ----------
    z : array (n, d)
        Standard variables.
    degree : int
        Highest degree k.
    families : str or tuple of str
        Family per column.

    Returns
    -------
    array (degree + 1, n, d)
        Entry [k, j, i]: the degree-k polynomial of input i at point j.
    """
    z = np.asarray(z, dtype=float)
    if z.ndim != 2:
        raise ValueError(f"z must be (n, d), got shape {z.shape}")
    fams = (families,) * z.shape[1] if isinstance(families, str) else tuple(families)
    if len(fams) != z.shape[1]:
        raise ValueError(f"{len(fams)} families for {z.shape[1]} inputs")
    out = np.empty((degree + 1,) + z.shape)
    for name in set(fams):
        cols = [i for i, f in enumerate(fams) if f == name]
        vals = np.asarray(_family(name, degree)(z[:, cols].ravel()), dtype=float)
        out[:, :, cols] = vals.reshape((degree + 1, z.shape[0], len(cols)))
    return out


def hermite_table(xi: np.ndarray, degree: int) -> np.ndarray:
    """Orthonormal (probabilists') Hermite polynomials He_k(x)/sqrt(k!) of every column.

    k = 0..degree, from chaospy's one-dimensional family (:func:`poly_table` with
    ``hermite``).

    Parameters
    ----------
    xi : array (n, d)
        Standard normal variables.
    degree : int
        Highest degree k.

    Returns
    -------
    array (degree + 1, n, d)
        Entry [k, j, i]: He_k/sqrt(k!) of input i at point j.
    """
    return poly_table(xi, degree, "hermite")


def design_matrix(z: np.ndarray, alphas: np.ndarray, *, families="hermite",
                  block: int = 256) -> np.ndarray:
    """(n, P) matrix of the multivariate orthonormal polynomials ``alphas`` at the points ``z``.

    ``alphas`` (P, d) multi-indices, ``z`` (n, d) standard variables; Fortran-ordered (each
    column contiguous, as the solvers read it).

    Each column is a product over the non-zero entries of its multi-index, gathered from the
    one-dimensional table ``block`` terms at a time (cache-sized pieces): the cost is
    n x P x (largest number of non-zero entries), not n x P x d.

    Parameters
    ----------
    z : array (n, d)
        Standard variables.
    alphas : array (P, d)
        Multi-indices.
    families : str or tuple of str
        Polynomial family per input.
    block : int
        Terms gathered at a time.

    Returns
    -------
    array (n, P)
        Fortran-ordered.
    """
    z = np.asarray(z, dtype=float)
    alphas = np.asarray(alphas)
    if alphas.ndim != 2 or alphas.shape[1] != z.shape[1]:
        raise ValueError(f"alphas must be (P, {z.shape[1]}), got {alphas.shape}")
    n, d = z.shape
    table = poly_table(z, int(alphas.max(initial=0)), families)
    flat = np.ascontiguousarray(table.transpose(0, 2, 1)).reshape(-1, n)  # row k*d + i
    k = max(int((alphas > 0).sum(axis=1).max(initial=0)), 1)
    order = np.argsort(-alphas, axis=1, kind="stable")[:, :k]             # non-zero entries first
    deg = np.take_along_axis(alphas, order, axis=1)
    rows = deg * d + order                                                # (P, k) table rows
    rows[deg == 0] = order[deg == 0]                                      # degree 0: the ones row
    psi_t = np.empty((alphas.shape[0], n))
    for s in range(0, alphas.shape[0], block):
        part = psi_t[s:s + block]
        np.take(flat, rows[s:s + block, 0], axis=0, out=part)
        for j in range(1, k):
            part *= np.take(flat, rows[s:s + block, j], axis=0)
    return psi_t.T


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


# ------------------------------------------------------------------------------------------
# Fits.
# ------------------------------------------------------------------------------------------

@dataclass
class PCEFit:
    """A sparse PCE of one output: multi-indices and coefficients of the kept terms.

    ``alphas`` (k, d), ``coef`` (k,) in the orthonormal basis of ``families`` (one name per
    input; the inputs are the standard variables of :class:`Inputs`), ``loo`` the corrected
    leave-one-out error of the kept model, ``validation`` the k-fold validation error of the
    selection procedure (NaN when not computed), ``n_candidates`` the size of the truncated
    basis the solver chose from.

    Attributes
    ----------
    alphas : array (k, d)
        Multi-indices of the kept terms.
    coef : array (k,)
        Coefficients in the orthonormal basis.
    loo : float
        Corrected leave-one-out error of the kept model.
    degree : int
    q_norm : float
    n_candidates : int
        Size of the truncated basis.
    validation : float
        k-fold validation error of the selection (NaN when not computed).
    method : str
        The solver.
    families : str or tuple of str
        Polynomial family per input.
    """

    alphas: np.ndarray
    coef: np.ndarray
    loo: float
    degree: int
    q_norm: float
    n_candidates: int
    validation: float = float("nan")
    method: str = "omp"
    families: tuple | str = "hermite"

    def predict(self, z: np.ndarray) -> np.ndarray:
        """The expansion at standard variables.

        Parameters
        ----------
        z : (n, d) array
            Standard variables of the inputs (:meth:`Inputs.to_standard`).

        Returns
        -------
        (n,) ndarray
            The expansion's value, in the units of the fitted output.
        """
        return design_matrix(z, self.alphas, self.families) @ self.coef


def fit_pce(xi: np.ndarray, y: np.ndarray, *, degree: int = 3, q_norm: float = 1.0,
            max_terms: int | None = None, patience: int = 8, psi: np.ndarray | None = None,
            alphas: np.ndarray | None = None, target: float = TARGET,
            families="hermite", method: str = "omp") -> PCEFit:
    """Sparse PCE of one output by OMP (or LARS) on a fixed basis, its length by corrected LOO.

    The number of terms is chosen by corrected LOO along the path (UQLab's rule; for a
    validated choice see :func:`fit_sparse_pce`).

    The path stops ``patience`` steps after the best LOO error, or as soon as the relative LOO
    error reaches ``target`` (the variance is then explained to about eight digits; further
    terms, e.g. tiny products of angular errors, cannot change a Sobol index visibly but can make
    the path hundreds of terms long), or at ``max_terms`` (default n - 2).  The constant term is
    always kept.  ``psi``/``alphas`` may be passed to reuse a design matrix across outputs (or use
    :func:`fit_pce_outputs`).

    Parameters
    ----------
    xi : array (n, d)
        Standard variables of the inputs.
    y : array (n,)
        The output.
    degree : int
        Total degree of the candidate basis.
    q_norm : float
        Hyperbolic truncation, in (0, 1].
    max_terms : int, optional
        Longest path (default n - 2).
    patience : int
        Steps after the best LOO error before the path stops.
    psi : array (n, P), optional
        A design matrix to reuse (with ``alphas``).
    alphas : array (P, d), optional
        Its multi-indices.
    target : float
        Relative LOO error at which the path stops.
    families : str or tuple of str
        Polynomial family per input (``hermite``, ``legendre``).
    method : {"omp", "lars"}
        The sparse solver.

    Returns
    -------
    PCEFit
    """
    y = np.asarray(y, dtype=float)
    return fit_pce_outputs(xi, y[:, None], degree=degree, q_norm=q_norm, max_terms=max_terms,
                           patience=patience, psi=psi, alphas=alphas, target=target,
                           families=families, method=method)[0]


def fit_pce_outputs(xi: np.ndarray, y: np.ndarray, *, degree: int = 3, q_norm: float = 1.0,
                    max_terms: int | None = None, patience: int = 8,
                    psi: np.ndarray | None = None, alphas: np.ndarray | None = None,
                    target: float = TARGET, families="hermite",
                    method: str = "omp") -> list[PCEFit]:
    """:func:`fit_pce` for every column of ``y`` (n, q) on one design, built once.

    The basis, the design matrix and its column norms are built once.  BLAS runs
    single-threaded here: the result is
    then the same for any thread count, and the many small BLAS calls of the path do not stall
    when another process shares the cores.

    Parameters
    ----------
    xi : array (n, d)
        Standard variables of the inputs.
    y : array (n, q)
        The outputs.
    degree : int
        Total degree of the candidate basis.
    q_norm : float
        Hyperbolic truncation, in (0, 1].
    max_terms : int, optional
        Longest path (default n - 2).
    patience : int
        Steps after the best LOO error before the path stops.
    psi : array (n, P), optional
        A design matrix to reuse (with ``alphas``).
    alphas : array (P, d), optional
        Its multi-indices.
    target : float
        Relative LOO error at which the path stops.
    families : str or tuple of str
        Polynomial family per input (``hermite``, ``legendre``).
    method : {"omp", "lars"}
        The sparse solver.

    Returns
    -------
    list of PCEFit (q,)
    """
    with threadpool_limits(limits=1, user_api="blas"):
        xi = np.asarray(xi, dtype=float)
        y = np.asarray(y, dtype=float)
        if y.ndim != 2 or y.shape[0] != xi.shape[0]:
            raise ValueError(f"y must be (n, q) with n = {xi.shape[0]} rows, got {y.shape}")
        if alphas is None:
            alphas = multi_indices(xi.shape[1], degree, q_norm)
        if psi is None:
            psi = design_matrix(xi, alphas, families=families)
        norms = column_norms(psi)
        fits = []
        for col in y.T:
            order, loo = _solver_path(psi, col, method, max_terms, patience, target, norms)
            fits.append(_final_fit(psi, col, alphas, order, loo, degree, q_norm, families,
                                   method))
        return fits


def _best_length(curve: np.ndarray, rtol: float = LOO_RTOL, floor: float = 0.0) -> int:
    """Index of the smallest value of an error curve over path lengths, values within ``rtol``
    (relative) of it, or all below ``floor``, counting as ties that go to the shortest."""
    c = np.maximum(np.asarray(curve, dtype=float), floor)
    return int(rank_with_ties(np.where(np.isfinite(c), c, 1e300),
                              np.arange(c.size), rtol=rtol)[0])


def _final_fit(psi, y, alphas, order, loo, degree, q_norm, families, method, length=None,
               validation=float("nan"), floor=TARGET):
    """The fit on the constant plus the first ``length`` path columns (default: the best LOO
    length), with its support in basis order."""
    k = _best_length(loo, floor=floor) if length is None else int(length)
    cols = [0, *sorted(int(c) for c in order[:k])]
    err, coef = loo_error(psi[:, cols], y)
    fam = families if isinstance(families, str) else tuple(families)
    return PCEFit(alphas[cols], coef, err, degree, q_norm, alphas.shape[0], validation,
                  method, fam)


def pce_selection_order(loo, basis, terms, degree, q_norm, *, rtol: float = LOO_RTOL,
                        floor: float = 0.0) -> np.ndarray:
    """Canonical ranking of candidate PCEs (one entry per fit) for model selection.

    Corrected LOO errors are first floored at ``floor`` (the target accuracy of the fits:
    below it every fit is as good as was asked for) and then compared with ties within
    ``rtol`` (relative); ties go to the smallest basis, then the fewest kept terms, the
    lowest degree and the smallest q-norm.  Returns indices, best first.

    Parameters
    ----------
    loo, basis, terms, degree, q_norm : arrays (m,)
        Per candidate fit.
    rtol : float
        Relative tie window.
    floor : float
        LOO errors below it count as equal.

    Returns
    -------
    array of int (m,)
    """
    loo = np.asarray(loo, dtype=float)
    if not 0 <= floor < np.inf:
        raise ValueError(f"floor must be finite and >= 0, got {floor!r}")
    keys = np.c_[basis, terms, degree, q_norm].astype(float)
    return rank_with_ties(np.maximum(loo, floor), keys, rtol=rtol)


def select_pce(xi, y, *, degrees=(1, 2, 3), q_norms=(0.5, 0.75, 1.0), rtol: float = LOO_RTOL,
               **kw) -> tuple[PCEFit, list]:
    """Fit every (degree, q-norm) and keep the best by corrected LOO error.

    Differences below ``rtol`` (relative) and LOO errors below the fits' target accuracy
    (``target``, see :func:`fit_pce`) are ties that go to the smallest basis
    (:func:`pce_selection_order`).  Returns the chosen fit and a list of (degree, q_norm,
    basis size, kept terms, LOO) in grid order.

    Parameters
    ----------
    xi : array (n, d)
        Standard variables.
    y : array (n,)
        The output.
    degrees : sequence of int
        Total degrees tried.
    q_norms : sequence of float
        q-norms tried at each degree.
    rtol : float
        Relative tie window.
    **kw
        Passed to :func:`fit_pce`.

    Returns
    -------
    fit : PCEFit
    table : list of tuple
    """
    fits, table = [], []
    for p in degrees:
        for q in q_norms:
            f = fit_pce(xi, y, degree=p, q_norm=q, **kw)
            fits.append(f)
            table.append((p, q, f.n_candidates, len(f.coef), f.loo))
    t = np.array(table, dtype=float)
    floor = kw.get("target", TARGET)
    order = pce_selection_order(t[:, 4], t[:, 2], t[:, 3], t[:, 0], t[:, 1], rtol=rtol,
                                floor=floor)
    return fits[order[0]], table


# ------------------------------------------------------------------------------------------
# Basis-adaptive sparse PCE with k-fold validation.
# ------------------------------------------------------------------------------------------

@dataclass
class SparsePCE:
    """Result of :func:`fit_sparse_pce`.

    ``fit``: the chosen :class:`PCEFit`; ``candidates``: one row per (degree, q-norm) tried
    (degree, q_norm, basis, terms, loo) in the order tried; ``validation_curve``: the k-fold
    validation error of the chosen basis against the number of non-constant terms (index k =
    k terms); ``s1``, ``st``: the Sobol indices from the coefficients; ``reliable``: the
    validation error is at most ``poor_fit``; :meth:`to_df` the indices labelled by input.

    Attributes
    ----------
    fit : PCEFit
        The chosen fit.
    candidates : list of dict
        One row per (degree, q-norm) tried.
    validation_curve : array
        Validation error of the chosen basis against the number of terms.
    poor_fit : float
        Validation error above which the fit is flagged unreliable.
    names : tuple of str (d,)
        The input names (:attr:`Inputs.names`; empty: ``x1`` ... ``xd``).
    """

    fit: PCEFit
    candidates: list = field(default_factory=list)
    validation_curve: np.ndarray = field(default_factory=lambda: np.zeros(0))
    poor_fit: float = POOR_FIT
    names: tuple = ()

    @property
    def s1(self) -> np.ndarray:
        """(d,) ndarray: first-order Sobol indices from the coefficients (:func:`pce_sobol`)."""
        return pce_sobol(self.fit)[0]

    @property
    def st(self) -> np.ndarray:
        """(d,) ndarray: total Sobol indices from the coefficients (:func:`pce_sobol`)."""
        return pce_sobol(self.fit)[1]

    @property
    def reliable(self) -> bool:
        """bool: the k-fold validation error is at most ``poor_fit``."""
        return bool(self.fit.validation <= self.poor_fit)

    def to_df(self, output: str = "y") -> pd.DataFrame:
        """The indices as a long table, one row per input, labelled by output and input name.

        A PCE's indices are read off its coefficients and carry no sampling interval; the
        table says how far to trust them instead, in the columns ``validation`` (the k-fold
        validation error of the fit) and ``reliable``.

        Parameters
        ----------
        output : str
            The name of the fitted output (the ``output`` column).

        Returns
        -------
        pandas.DataFrame
            Columns ``output``, ``input``, ``S1``, ``ST``, ``validation``, ``reliable``; d rows
            in input order.
        """
        s1, st = pce_sobol(self.fit)
        names = self.names or tuple(f"x{i + 1}" for i in range(s1.size))
        return pd.DataFrame({"output": output, "input": list(names), "S1": s1, "ST": st,
                             "validation": self.fit.validation, "reliable": self.reliable})


def _folds(n: int, k: int, seed) -> list[np.ndarray]:
    """``k`` disjoint validation parts of ``range(n)`` (a seeded permutation cut in k), sorted."""
    perm = rng(seed).permutation(n)
    return [np.sort(perm[i::k]) for i in range(k)]


def _check_folds(folds, n: int) -> int:
    """``folds`` as an int in [2, n // 2], the one bound of the k-fold validation.

    What the code needs is a held-out part of at least one point per fold (k <= n).  The
    bound asks for two: a held-out part of one point makes every fold a leave-one-out
    refit of the whole path (n path runs, the cost k-fold validation is there to avoid), and
    ``n // 2`` is the largest k whose parts all hold two points or more.  (``fit_sparse_pce``
    used to stop at n/4 and ``validation_curve`` at n/2: nothing in either needs n/4.)

    Parameters
    ----------
    folds : int
        The number of folds asked for.
    n : int
        The number of points cut into folds.

    Returns ``folds`` as a Python int; a ValueError unless it is an integer in [2, n // 2].
    """
    return integer(folds, "folds", low=2, high=n // 2)


def validation_curve(psi: np.ndarray, y: np.ndarray, *, method: str = "omp", length: int = 100,
                     folds: int = 5, norms: np.ndarray | None = None, seed=0
                     ) -> tuple[np.ndarray, np.ndarray]:
    """k-fold validation error of the solver path against its length, and its standard error.

    For each fold the solver path is run on the other parts (to ``length`` terms, no early
    stop), the least-squares fits on its prefixes predict the held-out part, and the squared
    errors are pooled over folds.  Returns ``curve`` (length + 1,): mean squared error /
    Var(y) (index k: the constant plus k terms; lengths a fold's path did not reach are
    infinite) and ``se`` (length + 1,): its standard error (standard deviation of the n pooled
    squared errors / sqrt(n), / Var(y)).

    Parameters
    ----------
    psi : array (n, P)
        Design matrix, constant column first.
    y : array (n,)
        The output.
    method : {"omp", "lars"}
        The solver.
    length : int
        Path length (>= 0).
    folds : int
        Folds, 2..n/2 (:func:`check_folds`).
    norms : array (P,), optional
        :func:`column_norms` of ``psi``.
    seed : None, int or numpy.random.Generator
        Randomness of the folds (:func:`mtaccuracy.validate.rng`).

    Returns
    -------
    curve : array (length + 1,)
        Validation error over Var(y) per path length.
    se : array (length + 1,)
        Its standard error.
    """
    if method not in ("omp", "lars"):
        raise ValueError(f"unknown sparse solver {method!r}; allowed: omp, lars")
    n = psi.shape[0]
    folds = _check_folds(folds, n)
    length = integer(length, "length", low=0)
    norms = column_norms(psi) if norms is None else norms
    sq = np.zeros((n, length + 1))
    reached = length
    for test in _folds(n, folds, seed):
        train = np.setdiff1d(np.arange(n), test, assume_unique=True)
        if method == "omp":
            order, _ = omp_path(psi, y, max_terms=length, patience=None, norms=norms,
                                rows=train)
        else:
            order = lars_order(psi, y, max_terms=min(length, len(train) - 2, psi.shape[1] - 1),
                               rows=train)
        cols = [0, *order]
        coefs = _prefix_coefficients(psi[np.ix_(train, cols)], y[train])     # (K+1, K+1)
        pred = psi[np.ix_(test, cols)] @ coefs                               # (n_test, K+1)
        sq[test, :len(cols)] = (y[test, None] - pred) ** 2
        reached = min(reached, len(order))
    var = np.var(y)
    if var <= 0:
        return np.zeros(length + 1), np.zeros(length + 1)
    curve, se = sq.mean(axis=0) / var, sq.std(axis=0) / np.sqrt(n) / var
    curve[reached + 1:] = np.inf
    return curve, se


def _pick(cands, target) -> int | None:
    """The chosen candidate basis: the smallest validation error, where every error within one
    standard error of it (the one-standard-error rule: Breiman et al. 1984; Hastie et al. 2009,
    Sec. 7.10) or below ``target`` ties, and ties go to the smallest basis, then the fewest
    terms, the lowest degree and the smallest q-norm (:func:`pce_selection_order`)."""
    if not cands:
        return None
    v = np.array([c["validation"] for c in cands])
    b = int(np.argmin(v))
    v = np.where(v <= v[b] + cands[b]["validation_se"], v[b], v)
    keys = np.array([[c["basis"], c["terms"], c["degree"], c["q_norm"]] for c in cands], float)
    return int(pce_selection_order(v, *keys.T, rtol=0.0, floor=target)[0])


def _validated_length(psi, y, method, folds, norms, seed, patience, target, start=16):
    """The k-fold validation curve of the path on ``psi``, its length grown until it turns.

    :func:`validation_curve`, its length doubled from ``start`` while the smallest error lies
    within ``patience`` steps of the end (and the end is not the cap n_train - 2 or P - 1);
    returns (curve, se, best length)."""
    n = psi.shape[0]
    cap = min(psi.shape[1] - 1, n - -(-n // folds) - 2)
    length = min(cap, start)
    while True:
        curve, se = validation_curve(psi, y, method=method, length=length, folds=folds,
                                     norms=norms, seed=seed)
        k = _best_length(curve, floor=target)
        if k <= length - patience or length >= cap or curve[k] <= target:
            return curve, se, k
        length = min(cap, 2 * length)


def fit_sparse_pce(x: np.ndarray, y: np.ndarray, *, inputs: Inputs | None = None,
                   degrees=(1, 2, 3), q_norms=(0.5, 0.75, 1.0), method: str = "omp",
                   folds: int = 5, seed=0, degree_patience: int = 2, patience: int = 10,
                   target: float = TARGET, poor_fit: float = POOR_FIT,
                   max_basis: int = 200_000) -> SparsePCE:
    """Basis-adaptive sparse PCE of one output, every choice made on a validation error.

    1. **Basis**: the standard variables of ``inputs`` (``x`` physical inputs (n, d); None:
       ``x`` are already standard normal) and their families (:class:`Inputs`).
    2. **Validation error of a basis**: ``folds``-fold cross validation of the whole solver
       path (:func:`validation_curve`: the path, ``omp`` or ``lars``, is re-run on every
       training part, so the choice of the terms is validated and not only their
       coefficients).  The number of terms is where the validation error is smallest; the path
       is extended while that minimum lies within ``patience`` steps of its end, so there is no
       term cap but n_train - 2.  The corrected LOO error of the terms a solver picked is not
       used for any choice: the selection saw the point left out, and with many candidates it
       is optimistic by orders of magnitude (41-d G function, 13,244 candidates: LOO 9e-9 at 891
       terms, validation error 0.32; a test shows it).  It is reported beside the validation
       error, as UQLab reports it.
    3. **Degree and q-norm** (basis adaptivity, as UQLab's but on the validation error): each
       degree in ascending order with each q-norm (hyperbolic truncation), a basis identical to
       one already tried skipped; degrees stop after ``degree_patience`` degrees that do not
       lower the smallest validation error (UQLab's default: 2).  The smallest validation
       error wins; errors within one standard error of it, or below ``target``, are ties that
       go to the smallest basis (:func:`_pick`: a larger basis must earn its place by more
       than the noise of the validation).
    4. **Warning**: a validation error above ``poor_fit`` raises :class:`PoorFitWarning`
       (``SparsePCE.reliable`` is False): the indices are not to be trusted.

    The final model is the full-data path to the chosen length, refitted by least squares.
    Folds are a seeded permutation (``seed``).  Returns a :class:`SparsePCE`.  BLAS runs
    single-threaded (results independent of the thread count).

    Parameters
    ----------
    x : array (n, d)
        Inputs (physical, or standard normal when ``inputs`` is None).
    y : array (n,)
        The output.
    inputs : Inputs, optional
        The input laws and names (None: ``x`` standard normal, named ``x1`` ... ``xd``).
    degrees : sequence of int
        Degrees tried, ascending.
    q_norms : sequence of float
        q-norms tried at each degree.
    method : {"omp", "lars"}
        The sparse solver.
    folds : int
        Folds of the validation, 2..n/2 (:func:`check_folds`).
    seed : None, int or numpy.random.Generator
        Randomness of the folds (:func:`mtaccuracy.validate.rng`); a Generator is read once
        per candidate basis, so pass an int for folds that are the same for every basis.
    degree_patience : int
        Degrees without improvement before stopping.
    patience : int
        Path steps beyond the validation minimum.
    target : float
        Errors below it are ties.
    poor_fit : float
        Validation error above which a warning is raised.
    max_basis : int
        Largest candidate basis built.

    Returns
    -------
    SparsePCE
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if x.ndim != 2 or y.shape != (x.shape[0],):
        raise ValueError(f"need x (n, d) and y (n,), got {x.shape} and {y.shape}")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise ValueError("x and y must be finite")
    n, d = x.shape
    folds = _check_folds(folds, n)
    if method not in ("omp", "lars"):
        raise ValueError(f"unknown sparse solver {method!r}; allowed: omp, lars")
    degrees = sorted({int(p) for p in degrees})
    if not degrees or degrees[0] < 1:
        raise ValueError(f"degrees must be integers >= 1, got {degrees!r}")
    if inputs is None:
        z, families, names = x, "hermite", tuple(f"x{i + 1}" for i in range(d))
    else:
        if inputs.dim != d:
            raise ValueError(f"{inputs.dim} input laws for {d} input columns")
        z, families, names = inputs.to_standard(x), inputs.families, inputs.names
    with threadpool_limits(limits=1, user_api="blas"):
        cands, kept, seen, worse, lowest = [], [], set(), 0, np.inf
        for p in degrees:
            before = lowest
            for q in sorted(q_norms):
                alphas = multi_indices(d, p, q)
                key = alphas.tobytes()
                if key in seen:
                    continue
                seen.add(key)
                if alphas.shape[0] > max_basis:
                    raise ValueError(f"degree {p}, q-norm {q:g}: {alphas.shape[0]} terms, above "
                                     f"max_basis = {max_basis}")
                psi = design_matrix(z, alphas, families=families)
                norms = column_norms(psi)
                curve, se, k = _validated_length(psi, y, method, folds, norms, seed, patience,
                                                 target)
                cands.append(dict(degree=p, q_norm=q, basis=alphas.shape[0], terms=k + 1,
                                  validation=float(curve[k]), validation_se=float(se[k])))
                kept.append((curve, k))
            lowest = min([lowest] + [c["validation"] for c in cands if c["degree"] == p])
            worse = 0 if lowest < before * (1 - LOO_RTOL) else worse + 1
            if worse >= degree_patience or lowest <= target:
                break
        i = _pick(cands, target)
        curve, k = kept[i]
        pick = cands[i]
        alphas = multi_indices(d, pick["degree"], pick["q_norm"])
        psi = design_matrix(z, alphas, families=families)  # rebuilt: cheaper than keeping every one
        norms = column_norms(psi)
        order, loo = _solver_path(psi, y, method, max(k, 1), None, 0.0, norms)
        fit = _final_fit(psi, y, alphas, order, loo, pick["degree"], pick["q_norm"], families,
                         method, length=min(k, len(order)), validation=float(curve[k]))
        for j, c in enumerate(cands):
            c["chosen"] = j == i
            c["loo"] = fit.loo if j == i else float("nan")
    res = SparsePCE(fit, cands, curve, poor_fit, names)
    if not res.reliable:
        warnings.warn(f"sparse PCE: validation error {fit.validation:.3g} (share of the variance "
                      f"not explained, {folds}-fold) is above {poor_fit:g}; its Sobol indices "
                      "are not reliable (more samples, another basis or a sampling estimator)",
                      PoorFitWarning, stacklevel=2)
    return res


def pce_sobol(fit: PCEFit) -> tuple[np.ndarray, np.ndarray]:
    """First-order and total Sobol indices (d,) from the coefficients of a PCE.

    Zheng et al. Eq. 23; Sudret 2008: the variance of an orthonormal PCE is the sum of its
    squared non-constant coefficients, and an index sums those of the terms that hold only
    (S1) or also (ST) the input.

    Parameters
    ----------
    fit : PCEFit
        A fit in an orthonormal basis (constant term included).

    Returns
    -------
    s1, st : arrays (d,)
        First-order and total indices, in input order.
    """
    a = fit.alphas
    c2 = fit.coef**2
    nonconst = a.sum(axis=1) > 0
    var = c2[nonconst].sum()
    if var == 0:
        return np.zeros(a.shape[1]), np.zeros(a.shape[1])
    active = a > 0
    only = active & (active.sum(axis=1, keepdims=True) == 1)
    return (c2[:, None] * only).sum(axis=0) / var, (c2[:, None] * active).sum(axis=0) / var
