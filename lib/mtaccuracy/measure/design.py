"""One test (or a plan of tests) as a linear model: ``y = A eps + N nu + e``.

Every module of :mod:`mtaccuracy.measure` speaks this contract: a test model builds a
:class:`Design` from a machine, the identifiability analysis and the identification take one.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Design:
    """The linear model of one test's readings, or of a plan's (:func:`combine`).

    ``y = A eps + N nu + e`` with ``e ~ N(0, diag(sigma**2))``.

    Attributes
    ----------
    name : str
        The test ("circle XY r=150 mm cw"), or the plan's tests joined by ``" + "``.
    A : (n_obs, n_errors) ndarray
        d(reading)/d(error): readings in um, errors in the machine's units (mm, rad), so um
        per mm or um per rad.
    N : (n_obs, n_nuisances) ndarray
        d(reading)/d(nuisance), nuisances in the units their names state.
    sigma : (n_obs,) ndarray
        The standard deviation of each reading's noise, um (> 0).
    errors : tuple of str
        The machine's error symbols, the columns of ``A``.
    nuisances : tuple of str
        The nuisances' names, the columns of ``N``.
    labels : tuple of str
        One label per reading (the test and its point), for tables and messages.
    """

    name: str
    A: np.ndarray
    N: np.ndarray
    sigma: np.ndarray
    errors: tuple
    nuisances: tuple
    labels: tuple

    def __post_init__(self):
        A = np.asarray(self.A, dtype=float)
        n = A.shape[0] if A.ndim == 2 else -1
        N = np.asarray(self.N, dtype=float).reshape(n, -1) if n >= 0 else np.asarray(self.N)
        sigma = np.broadcast_to(np.asarray(self.sigma, dtype=float), (max(n, 0),)).copy()
        problems = []
        if A.ndim != 2 or A.shape[1] != len(self.errors):
            problems.append(f"A must be (n_obs, {len(self.errors)}), got {A.shape}")
        elif N.shape[1] != len(self.nuisances):
            problems.append(f"N must be ({n}, {len(self.nuisances)}), got {N.shape}")
        elif len(self.labels) != n:
            problems.append(f"{len(self.labels)} labels for {n} readings")
        elif not (np.isfinite(A).all() and np.isfinite(N).all()):
            problems.append("A and N must be finite")
        elif not (np.isfinite(sigma).all() and (sigma > 0).all()):
            problems.append("every sigma must be finite and > 0 (um)")
        if len(set(self.errors)) != len(self.errors):
            problems.append("error names repeat")
        if problems:
            raise ValueError(f"design {self.name!r}: " + "; ".join(problems))
        for k, v in (("A", A), ("N", N), ("sigma", sigma)):
            v.setflags(write=False)
            object.__setattr__(self, k, v)
        for k in ("errors", "nuisances", "labels"):
            object.__setattr__(self, k, tuple(getattr(self, k)))

    @property
    def n_obs(self) -> int:
        """The number of readings."""
        return self.A.shape[0]


def combine(designs: Sequence[Design], *, name: str | None = None) -> Design:
    """A plan: the tests' readings stacked, each test with its own nuisances.

    Parameters
    ----------
    designs : sequence of Design
        The tests, all of the same machine (the same ``errors``, in the same order).
    name : str, optional
        The plan's name (default the tests' names joined by ``" + "``).

    Returns
    -------
    Design
        Rows in the order given; ``N`` block-diagonal, nuisance ``v`` of test ``t`` named
        ``"t: v"``.

    Examples
    --------
    >>> import numpy as np
    >>> a = Design("a", np.eye(2), np.ones((2, 1)), 1.0, ("E1", "E2"), ("c",), ("a1", "a2"))
    >>> b = Design("b", np.eye(2), np.zeros((2, 0)), 2.0, ("E1", "E2"), (), ("b1", "b2"))
    >>> p = combine([a, b])
    >>> p.name, p.A.shape, p.N.shape, p.nuisances, p.sigma.tolist()
    ('a + b', (4, 2), (4, 1), ('a: c',), [1.0, 1.0, 2.0, 2.0])
    """
    designs = list(designs)
    if not designs:
        raise ValueError("a plan needs at least one test")
    errors = designs[0].errors
    for d in designs[1:]:
        if d.errors != errors:
            raise ValueError(f"test {d.name!r} has other errors than {designs[0].name!r}: "
                             "every test of a plan must be of the same machine")
    n_nu = sum(len(d.nuisances) for d in designs)
    N = np.zeros((sum(d.n_obs for d in designs), n_nu))
    r = c = 0
    for d in designs:
        N[r:r + d.n_obs, c:c + len(d.nuisances)] = d.N
        r, c = r + d.n_obs, c + len(d.nuisances)
    return Design(name or " + ".join(d.name for d in designs),
                  np.vstack([d.A for d in designs]), N,
                  np.concatenate([d.sigma for d in designs]), errors,
                  tuple(f"{d.name}: {v}" for d in designs for v in d.nuisances),
                  tuple(lab for d in designs for lab in d.labels))
