"""Sobol first-order and total indices from A, B and AB_i blocks, evaluated in chunks.

The estimators are SALib's (``SALib.analyze.sobol`` with ``calc_second_order=False``):
Saltelli et al. 2010 for the first order, Jansen 1999 for the total index, on outputs
standardised over all N(D+2) runs.  SALib's sampler materialises every run at once (at D=41,
N=2^17 it takes 44 s and 1.8 GB); here A and B are drawn once and each AB_i block is built and
evaluated chunk by chunk, so the model sees one batched call per chunk and memory stays bounded.
A test checks these numbers against SALib's at small N.

Layout: ``ya``, ``yb`` are (N, q); ``yab`` is (D, N, q) with ``yab[i]`` the model on AB_i (A
with column i taken from B).
"""

from __future__ import annotations

__all__ = ["base_samples", "from_unit_uniform", "from_unit_normal", "sobol_evaluate",
           "sobol_estimate", "sobol_bootstrap", "sobol_indices", "linear_indices"]

from collections.abc import Callable

import numpy as np
from scipy import stats
from scipy.stats import qmc


def base_samples(n: int, d: int, method: str, seed) -> tuple[np.ndarray, np.ndarray]:
    """Two independent (n, d) designs on the unit hypercube: the A and B matrices.

    method ``mc``: independent uniforms; ``lhs``: two independent Latin hypercubes
    (scipy.qmc); ``sobol``: one scrambled 2d-dimensional Sobol' sequence split in halves, as
    SALib's Saltelli sampler does (n should be a power of 2).
    """
    if int(n) != n or n < 2:
        raise ValueError(f"n must be an integer >= 2, got {n!r}")
    rng = np.random.default_rng(seed)
    n = int(n)
    if method == "mc":
        return rng.random((n, d)), rng.random((n, d))
    if method == "lhs":
        return (qmc.LatinHypercube(d=d, rng=rng).random(n),
                qmc.LatinHypercube(d=d, rng=rng).random(n))
    if method == "sobol":
        u = qmc.Sobol(d=2 * d, scramble=True, rng=rng).random(n)
        return u[:, :d], u[:, d:]
    raise ValueError(f"unknown sampling method {method!r}; allowed: mc, lhs, sobol")


def from_unit_uniform(u: np.ndarray, bounds: np.ndarray) -> np.ndarray:
    """Map unit-cube samples to independent uniforms on ``bounds`` (2, d)."""
    bounds = np.asarray(bounds, dtype=float)
    return bounds[0] + u * (bounds[1] - bounds[0])


def from_unit_normal(u: np.ndarray, sd: np.ndarray, mean: np.ndarray | float = 0.0) -> np.ndarray:
    """Map unit-cube samples to independent normals (inverse CDF), ``sd`` per column."""
    return np.asarray(mean) + np.asarray(sd) * stats.norm.ppf(u)


def sobol_evaluate(model: Callable[[np.ndarray], np.ndarray], a: np.ndarray, b: np.ndarray,
                   chunk: int = 200_000, progress: Callable[[int, int], None] | None = None
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Run ``model`` on A, B and every AB_i; returns ``ya`` (N, q), ``yb`` (N, q), ``yab``
    (D, N, q).

    ``model`` maps an (m, D) array to (m, q) (or (m,)) outputs.  Runs are batched ``chunk``
    rows at a time: N(D+2) model runs in about N(D+2)/chunk calls.  ``progress(done, total)``
    is called after each call with the number of runs done.
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    if a.shape != b.shape or a.ndim != 2:
        raise ValueError(f"A and B must be (N, D) arrays of one shape, got {a.shape}, {b.shape}")
    n, d = a.shape
    total = n * (d + 2)
    done = 0

    def run(x):
        nonlocal done
        y = np.asarray(model(x), dtype=float)
        y = y[:, None] if y.ndim == 1 else y
        done += x.shape[0]
        if progress:
            progress(done, total)
        return y

    def run_rows(x):
        return np.concatenate([run(x[s:s + chunk]) for s in range(0, x.shape[0], chunk)])

    ya, yb = run_rows(a), run_rows(b)
    yab = np.empty((d, n, ya.shape[1]))
    rows = max(1, chunk // n) if n <= chunk else 1  # AB blocks per model call
    for i0 in range(0, d, rows):
        i1 = min(i0 + rows, d)
        if n <= chunk:
            block = np.repeat(a[None], i1 - i0, axis=0)
            for k, i in enumerate(range(i0, i1)):
                block[k, :, i] = b[:, i]
            yab[i0:i1] = run(block.reshape(-1, d)).reshape(i1 - i0, n, -1)
        else:
            block = a.copy()
            block[:, i0] = b[:, i0]
            yab[i0] = run_rows(block)
    return ya, yb, yab


def sobol_estimate(ya: np.ndarray, yb: np.ndarray, yab: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
    """First-order (Saltelli 2010) and total (Jansen) indices, each (D, q), on outputs
    standardised over all runs as SALib does.  Works on leading bootstrap axes too: ``ya``
    (..., N, q), ``yab`` (..., D, N, q)."""
    mu = (ya.sum(-2) + yb.sum(-2) + yab.sum((-3, -2))) / (ya.shape[-2] * (yab.shape[-3] + 2))
    var = np.var(np.concatenate([ya, yb], axis=-2), axis=-2)
    diff = yab - ya[..., None, :, :]
    s1 = np.mean((yb[..., None, :, :] - mu[..., None, None, :]) * diff, axis=-2) / var[..., None, :]
    st = 0.5 * np.mean(diff**2, axis=-2) / var[..., None, :]
    return s1, st


def sobol_bootstrap(ya, yb, yab, n_boot: int, seed, conf: float = 0.95, chunk: int = 20):
    """Bootstrap half-widths of the ``conf`` confidence intervals of S1 and ST (D, q) each,
    from ``n_boot`` resamples of the N base rows (as SALib: normal quantile times the
    bootstrap standard deviation).  Resamples are batched ``chunk`` at a time."""
    rng = np.random.default_rng(seed)
    n = ya.shape[0]
    s1s, sts = [], []
    for start in range(0, n_boot, chunk):
        k = min(chunk, n_boot - start)
        idx = rng.integers(0, n, size=(k, n))
        s1, st = sobol_estimate(ya[idx], yb[idx], np.moveaxis(yab[:, idx], 0, 1))
        s1s.append(s1)
        sts.append(st)
    z = stats.norm.ppf(0.5 + conf / 2)
    return (z * np.concatenate(s1s).std(axis=0, ddof=1),
            z * np.concatenate(sts).std(axis=0, ddof=1))


def sobol_indices(model, a, b, chunk: int = 200_000, progress=None):
    """Convenience: :func:`sobol_evaluate` then :func:`sobol_estimate`; returns (S1, ST)."""
    return sobol_estimate(*sobol_evaluate(model, a, b, chunk=chunk, progress=progress))


def linear_indices(jacobian: np.ndarray, sd: np.ndarray) -> np.ndarray:
    """Sobol indices of a linear model with independent inputs: for output k and input i,
    ``J_ki^2 sd_i^2 / sum_j J_kj^2 sd_j^2`` (first-order = total; any distribution).

    ``jacobian`` (..., q, d), ``sd`` (d,).  An output with zero variance gets zeros.
    """
    v = (np.asarray(jacobian, dtype=float) * np.asarray(sd, dtype=float)) ** 2
    tot = v.sum(axis=-1, keepdims=True)
    return np.divide(v, tot, out=np.zeros_like(v), where=tot > 0)
