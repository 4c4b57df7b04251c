"""PCE fits at a given basis, the choice of degree and q-norm by corrected LOO, Sobol indices.

:func:`fit_pce` fits one output with a sparse solver path (:mod:`.solvers`) on a total-degree,
q-norm-truncated basis (:mod:`.basis`) and keeps the number of terms of smallest corrected LOO
error (UQLab); :func:`select_pce` tries several degrees and q-norms; :func:`pce_sobol` reads the
Sobol indices off the coefficients (Zheng et al. Eq. 23; Sudret 2008).
"""

from __future__ import annotations

__all__ = ["LOO_RTOL", "TARGET", "PCEFit", "fit_pce", "fit_pce_outputs", "pce_selection_order",
           "select_pce", "pce_sobol"]

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from threadpoolctl import threadpool_limits

from ..sobol import SobolIndices
from ..tie_rule import rank_with_ties
from .basis import design_matrix, multi_indices
from .solvers import _solver_path, column_norms, loo_error

#: Corrected leave-one-out errors closer than this (relative) are ties in model selection:
#: far above their rounding noise (about 1e-12 relative for the designs here), far below any
#: difference that would make one basis predict better than another.
LOO_RTOL = 1e-6

#: Default target accuracy of :func:`fit_pce` (relative corrected LOO error).
TARGET = 1e-8


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


def pce_sobol(fit: PCEFit, *, names: Sequence[str] | None = None,
              outputs: Sequence[str] | None = None) -> SobolIndices:
    """First-order and total Sobol indices (d,) from the coefficients of a PCE.

    Zheng et al. Eq. 23; Sudret 2008: the variance of an orthonormal PCE is the sum of its
    squared non-constant coefficients, and an index sums those of the terms that hold only
    (S1) or also (ST) the input.

    Parameters
    ----------
    fit : PCEFit
        A fit in an orthonormal basis (constant term included).
    names : sequence of str (d,), optional
        Input names (default ``x1`` ... ``xd``), labels of the result.
    outputs : sequence of one str, optional
        The output's name (default ``y1``).

    Returns
    -------
    SobolIndices
        Unpacks as ``s1, st``, arrays (d,): first-order and total indices, in input order;
        ``.to_df()`` labels them.
    """
    a = fit.alphas
    c2 = fit.coef**2
    nonconst = a.sum(axis=1) > 0
    var = c2[nonconst].sum()
    if var == 0:
        return SobolIndices(np.zeros(a.shape[1]), np.zeros(a.shape[1]), names=names,
                            outputs=outputs)
    active = a > 0
    only = active & (active.sum(axis=1, keepdims=True) == 1)
    return SobolIndices((c2[:, None] * only).sum(axis=0) / var,
                        (c2[:, None] * active).sum(axis=0) / var, names=names, outputs=outputs)
