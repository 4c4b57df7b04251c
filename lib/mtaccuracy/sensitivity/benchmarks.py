"""Test functions of the sensitivity-analysis literature with analytic Sobol indices.

Used by the tests (a PCE or a sampling estimator must recover these indices within a stated
tolerance), by ``make bench`` (ours beside OpenTURNS on the same samples) and by notebook 01 (the
sparse PCE at work on a nonlinear model).  Each benchmark gives the model, its inputs (an
:class:`~mtaccuracy.sensitivity.Inputs`: names and laws) and its exact first-order and total
indices.

| function | inputs | reference |
| --- | --- | --- |
| :func:`ishigami` | 3 uniform on [-pi, pi] | Ishigami & Homma 1990; Sudret 2008, Eq. 53-55 |
| :func:`g_function` | d uniform on [0, 1] | Sobol' 1993; Saltelli et al. 2010, Sec. 4 |
| :func:`interaction_polynomial` | d uniform on [-1, 1] | exact: orthogonal Legendre terms |
"""

from __future__ import annotations

__all__ = ["Benchmark", "ishigami", "g_function", "interaction_polynomial", "BENCHMARKS"]

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy import stats

from .inputs import Inputs


@dataclass(frozen=True)
class Benchmark:
    """A model with independent inputs and its exact Sobol indices.

    ``model`` maps (n, d) inputs to (n,) outputs; ``inputs`` names the d inputs and gives their
    laws; ``s1``, ``st`` (d,) the exact first-order and total indices; ``variance`` the exact
    output variance.

    Attributes
    ----------
    name : str
        What the benchmark is, with its coefficients.
    model : callable
        ``(n, d) -> (n,)``.
    inputs : Inputs
        The d inputs (names ``x1`` ... ``xd`` and uniform laws).
    s1, st : arrays (d,)
        Exact first-order and total indices.
    variance : float
        Exact output variance.
    """

    name: str
    model: Callable[[np.ndarray], np.ndarray]
    inputs: Inputs
    s1: np.ndarray
    st: np.ndarray
    variance: float

    @property
    def dim(self) -> int:
        """int: the number of inputs d."""
        return self.inputs.dim

    def sample(self, n: int, seed, method: str = "lhs") -> np.ndarray:
        """``n`` input points from :meth:`Inputs.sample`, a Latin hypercube by default.

        Parameters
        ----------
        n : int
            Number of points.
        seed : None, int or numpy.random.Generator
            The randomness (:func:`mtaccuracy.validate.rng`).
        method : {"lhs", "mc", "sobol"}
            The design on the unit cube, mapped through each input's inverse CDF.

        Returns
        -------
        (n, d) ndarray
            The input points.
        """
        return self.inputs.sample(n, method=method, seed=seed)


def ishigami(a: float = 7.0, b: float = 0.1) -> Benchmark:
    """f = sin x1 + a sin^2 x2 + b x3^4 sin x1, x_i ~ U(-pi, pi).

    Exact (Sudret 2008, Eqs. 53-55): V1 = 1/2 (1 + b pi^4/5)^2, V2 = a^2/8,
    V13 = b^2 pi^8 (1/18 - 1/50), V = a^2/8 + b pi^4/5 + b^2 pi^8/18 + 1/2; x3 acts only
    through its interaction with x1.  The classic a = 7, b = 0.1 gives S = (0.3139, 0.4424, 0)
    and ST = (0.5576, 0.4424, 0.2437).

    Parameters
    ----------
    a, b : float
        The coefficients.

    Returns
    -------
    Benchmark
    """
    def model(x):
        x = np.asarray(x, dtype=float)
        return np.sin(x[:, 0]) + a * np.sin(x[:, 1]) ** 2 + b * x[:, 2] ** 4 * np.sin(x[:, 0])

    v1 = 0.5 * (1 + b * np.pi**4 / 5) ** 2
    v2 = a**2 / 8
    v13 = b**2 * np.pi**8 * (1 / 18 - 1 / 50)
    v = v1 + v2 + v13
    law = stats.uniform(-np.pi, 2 * np.pi)
    return Benchmark(f"Ishigami (a={a:g}, b={b:g})", model, Inputs((law,) * 3),
                     np.array([v1, v2, 0.0]) / v, np.array([v1 + v13, v2, v13]) / v, float(v))


def g_function(a) -> Benchmark:
    """Sobol's G function ``prod_i (|4 x_i - 2| + a_i)/(1 + a_i)``, ``x_i ~ U(0, 1)``.

    Exact: each factor has mean 1 and variance V_i = 1/(3 (1 + a_i)^2); the output variance is
    V = prod (1 + V_i) - 1, S_i = V_i / V and ST_i = V_i prod_{j != i} (1 + V_j) / V.  A small
    a_i makes input i important, a large one (99) nearly inert: a dummy input with a tiny but
    exact index.  The kink of ``|4x - 2|`` at x = 1/2 makes it a hard case for polynomials, and
    every factor is even about 1/2, so odd Legendre degrees carry nothing.

    Parameters
    ----------
    a : sequence of float (d,)
        The coefficients a_i >= 0.

    Returns
    -------
    Benchmark
    """
    a = np.asarray(a, dtype=float)
    if a.ndim != 1 or a.size < 1 or np.any(a < 0):
        raise ValueError(f"a must be a non-empty vector of non-negative numbers, got {a!r}")

    def model(x):
        x = np.asarray(x, dtype=float)
        return np.prod((np.abs(4 * x - 2) + a) / (1 + a), axis=1)

    vi = 1 / (3 * (1 + a) ** 2)
    v = float(np.prod(1 + vi) - 1)
    st = vi * np.prod(1 + vi) / (1 + vi) / v
    return Benchmark(f"G function (d={a.size})", model, Inputs((stats.uniform(0, 1),) * a.size),
                     vi / v, st, v)


def interaction_polynomial(linear, pairs) -> Benchmark:
    """f = sum_i c_i x_i + sum_(i,j) c_ij x_i x_j, x_i ~ U(-1, 1) (d = len(linear)).

    Every term is a product of distinct first-degree Legendre polynomials, so the terms are
    orthogonal: Var(x_i) = 1/3 and Var(x_i x_j) = 1/9.  Hence S_i = c_i^2/3 / V and
    ST_i = (c_i^2/3 + sum over the pairs holding i of c_ij^2/9) / V.  ``pairs`` maps (i, j),
    i != j, to c_ij.  A PCE of degree >= 2 represents it exactly.

    Parameters
    ----------
    linear : sequence of float (d,)
        The c_i.
    pairs : dict of (int, int) to float
        The c_ij.

    Returns
    -------
    Benchmark
    """
    c = np.asarray(linear, dtype=float)
    d = c.size
    pairs = {tuple(int(v) for v in k): float(w) for k, w in dict(pairs).items()}
    for i, j in pairs:
        if not (0 <= i < d and 0 <= j < d and i != j):
            raise ValueError(f"pair {(i, j)} is not two distinct inputs of {d}")

    def model(x):
        x = np.asarray(x, dtype=float)
        out = x @ c
        for (i, j), w in pairs.items():
            out = out + w * x[:, i] * x[:, j]
        return out

    v1 = c**2 / 3
    vt = v1.copy()
    for (i, j), w in pairs.items():
        vt[i] += w**2 / 9
        vt[j] += w**2 / 9
    v = float(v1.sum() + sum(w**2 / 9 for w in pairs.values()))
    return Benchmark(f"interaction polynomial (d={d})", model, Inputs((stats.uniform(-1, 2),) * d),
                     v1 / v, vt / v, v)


#: The cases of the tests and of ``make bench`` (issue 13): the classic Ishigami function, the G
#: function in low dimension and in 41 dimensions (the size of the Zheng et al. model, six
#: important inputs and 35 nearly inert ones) and a polynomial with known interactions.
BENCHMARKS = {
    "ishigami": lambda: ishigami(7.0, 0.1),
    "g_function_8d": lambda: g_function([0, 1, 4.5, 9, 99, 99, 99, 99]),
    "g_function_41d": lambda: g_function([0, 0, 1, 1, 2, 2] + [99] * 35),
    "interaction_polynomial": lambda: interaction_polynomial(
        [1.0, -0.8, 0.6, 0.0, 0.3], {(0, 1): 0.9, (2, 3): 0.7, (1, 4): -0.5}),
}
