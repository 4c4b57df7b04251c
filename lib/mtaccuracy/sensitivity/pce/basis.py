"""Orthonormal polynomial bases of a PCE: multi-indices, one-dimensional families, design matrix.

The one-dimensional families are chaospy's (``chaospy.expansion.hermite`` / ``legendre``,
``normed=True``: orthonormal for the standard normal and for the uniform law on [-1, 1]); the
multi-indices are chaospy's ``glexindex`` (total degree with hyperbolic q-norm truncation); the
design matrix is built in numpy from them (chaospy's multivariate polynomial objects are far too
slow in 41 dimensions).
"""

from __future__ import annotations

__all__ = ["multi_indices", "poly_table", "hermite_table", "design_matrix"]

import functools

import numpy as np

FAMILIES = ("hermite", "legendre")


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
