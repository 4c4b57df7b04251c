"""One description of independent inputs: names, marginal laws, samples, moments, standard map.

:class:`Inputs` is what the estimators of this package take in place of bounds, standard
deviations, variances or a bare tuple of laws (issue 25 item 2), in the spirit of SALib's
``ProblemSpec`` and of chaospy's joint distributions: a name and a frozen ``scipy.stats`` law
per input.  It draws designs (:meth:`Inputs.sample`, :meth:`Inputs.sample_blocks`: Monte
Carlo, Latin hypercube or a scrambled Sobol' sequence, every point the inverse CDF of a
unit-cube point: the package's one implementation of each design, which the Sobol' designs, the
Spearman designs and the benchmarks draw through), gives the moments the closed
forms need (:attr:`Inputs.mean`, :attr:`Inputs.var`, :attr:`Inputs.sd`) and the map to the
standard variables of the polynomial chaos (:meth:`Inputs.to_standard`).

Uniform and normal laws, the two the compendium uses, are computed from their location and
scale in closed form (``loc + scale u`` and ``loc + scale Phi^-1(u)``, the arithmetic of
``scipy.stats``' own ``ppf``, bitwise; moments ``loc + scale/2``, ``scale^2/12``...), so a
design or a moment is the same number whichever way it was asked for; any other law goes
through its own ``ppf``, ``cdf`` and moments.
"""

from __future__ import annotations

__all__ = ["Inputs"]


import warnings
from collections.abc import Iterator, Sequence

import numpy as np
from scipy import stats
from scipy.special import ndtri
from scipy.stats import qmc

from ..validate import integer
from ..validate import rng as _rng

#: Sampling methods of :meth:`Inputs.sample`.
METHODS = ("mc", "lhs", "sobol")

_SOBOL_BALANCE = "The balance properties of Sobol' points require n to be a power of 2."


def _loc_scale(m) -> tuple[float, float]:
    """Location and scale of a frozen law without shape parameters (uniform, normal), read
    from the arguments it was frozen with (positional ``loc, scale`` or keywords)."""
    given = dict(zip(("loc", "scale"), m.args, strict=False))
    given.update(m.kwds)
    return float(given.get("loc", 0.0)), float(given.get("scale", 1.0))


class Inputs:
    """Independent inputs: a name and a marginal law (a frozen ``scipy.stats`` distribution) each.

    The law of each input also picks its orthonormal polynomial family for a PCE
    (Wiener-Askey): Legendre for a uniform input on z = 2 (x - lo)/(hi - lo) - 1, Hermite for a
    normal one on z = (x - mu)/sd, and Hermite on z = Phi^-1(F(x)) (the isoprobabilistic
    transform) for any other law (for laws with a family of their own, e.g. Laguerre for the
    gamma law, this converges more slowly, but it is always valid).

    >>> inp = Inputs([stats.uniform(-1, 2), stats.norm(0, 2)], names=["ex", "ey"])
    >>> inp.families, inp.names, inp.sd.tolist()
    (('legendre', 'hermite'), ('ex', 'ey'), [0.5773502691896258, 2.0])

    Parameters
    ----------
    marginals : sequence of frozen scipy distributions (d,)
        The input laws, in input order.
    names : sequence of str (d,), optional
        Distinct input names (default ``x1`` ... ``xd``); they label the indices' tables.

    Raises
    ------
    TypeError
        If a law is not a frozen scipy distribution.
    ValueError
        If there is no law, or the names are not d distinct strings.
    """

    def __init__(self, marginals, names: Sequence[str] | None = None):
        self._marginals = tuple(marginals)
        if not self._marginals:
            raise ValueError("need at least one input law")
        for i, m in enumerate(self._marginals):
            if not hasattr(m, "ppf") or not hasattr(m, "cdf") or not hasattr(m, "dist"):
                raise TypeError(f"input {i}: {m!r} is not a frozen scipy.stats distribution")
        d = len(self._marginals)
        names = tuple(f"x{i + 1}" for i in range(d)) if names is None else tuple(names)
        if len(names) != d or not all(isinstance(s, str) and s for s in names):
            raise ValueError(f"names must be {d} non-empty strings, got {names!r}")
        if len(set(names)) != d:
            raise ValueError(f"names must be distinct, got {names!r}")
        self._names = names
        self._kind = tuple(getattr(m.dist, "name", "") for m in self._marginals)
        self._params = tuple(_loc_scale(m) if k in ("uniform", "norm") else None
                             for m, k in zip(self._marginals, self._kind, strict=True))

    # --- constructors -----------------------------------------------------------------------

    @classmethod
    def uniform(cls, lower, upper, names: Sequence[str] | None = None) -> Inputs:
        """Independent uniforms on [lower_i, upper_i].

        Parameters
        ----------
        lower, upper : float or (d,) array_like
            The bounds (mm, rad), broadcast together; finite with ``lower < upper``.
        names : sequence of str (d,), optional
            Input names (default ``x1`` ... ``xd``).

        Returns
        -------
        Inputs
            One uniform input per (flattened) bound.

        Raises
        ------
        ValueError
            If a bound is not finite or ``lower >= upper``.
        """
        lo, hi = np.broadcast_arrays(np.asarray(lower, float), np.asarray(upper, float))
        if np.any(~np.isfinite(lo) | ~np.isfinite(hi) | (hi <= lo)):
            raise ValueError("uniform bounds must be finite with lower < upper")
        return cls([stats.uniform(a, b - a) for a, b in zip(lo.ravel(), hi.ravel(), strict=True)],
                   names)

    @classmethod
    def unit(cls, d: int, names: Sequence[str] | None = None) -> Inputs:
        """``d`` independent uniforms on [0, 1]: the unit hypercube.

        Its designs are the unit-cube points themselves (:meth:`from_unit` is ``0 + 1 u``,
        the identity to the bit), so a caller that maps the cube its own way (a row map of a
        :class:`~mtaccuracy.sensitivity.SobolDesign`, bounds with zero-width columns in
        :func:`~mtaccuracy.sensitivity.latin_hypercube`) still draws through
        :meth:`sample_blocks`.

        Parameters
        ----------
        d : int
            Number of inputs (>= 1).
        names : sequence of str (d,), optional
            Input names (default ``x1`` ... ``xd``).

        Returns
        -------
        Inputs
            ``d`` inputs, each ``scipy.stats.uniform(0, 1)``.
        """
        d = integer(d, "d", low=1)
        return cls([stats.uniform(0.0, 1.0)] * d, names)

    @classmethod
    def from_bounds(cls, bounds, names: Sequence[str] | None = None) -> Inputs:
        """Independent uniforms on a ``(2, d)`` array of lower and upper bounds.

        The form in which the compendium's readers and notebooks hold error ranges
        (``machines.readers.read_ranges``, SALib's ``bounds`` transposed).

        Parameters
        ----------
        bounds : (2, d) array_like
            Row 0 the lower, row 1 the upper bounds (mm, rad); finite with lower < upper.
        names : sequence of str (d,), optional
            Input names (default ``x1`` ... ``xd``).

        Returns
        -------
        Inputs

        Raises
        ------
        ValueError
            If ``bounds`` is not (2, d), not finite or has a column with upper <= lower.
        """
        b = np.asarray(bounds, dtype=float)
        if b.ndim != 2 or b.shape[0] != 2:
            raise ValueError(f"bounds must be a (2, d) array, got shape {b.shape}")
        return cls.uniform(b[0], b[1], names)

    @classmethod
    def normal(cls, mean, sd, names: Sequence[str] | None = None) -> Inputs:
        """Independent normals N(mean_i, sd_i^2).

        Parameters
        ----------
        mean, sd : float or (d,) array_like
            Means and standard deviations (mm, rad), broadcast together; finite, ``sd > 0``.
        names : sequence of str (d,), optional
            Input names (default ``x1`` ... ``xd``).

        Returns
        -------
        Inputs
            One normal input per (flattened) value.

        Raises
        ------
        ValueError
            If a value is not finite or ``sd <= 0``.
        """
        mu, s = np.broadcast_arrays(np.asarray(mean, float), np.asarray(sd, float))
        if np.any(~np.isfinite(mu) | ~np.isfinite(s) | (s <= 0)):
            raise ValueError("normal means and standard deviations must be finite, sd > 0")
        return cls([stats.norm(a, b) for a, b in zip(mu.ravel(), s.ravel(), strict=True)],
                   names)

    # --- description ------------------------------------------------------------------------

    def __repr__(self) -> str:
        laws = ", ".join(f"{n}: {k or type(m.dist).__name__}"
                         for n, k, m in zip(self._names, self._kind, self._marginals, strict=True))
        return f"Inputs({laws})"

    def __len__(self) -> int:
        return len(self._marginals)

    @property
    def names(self) -> tuple[str, ...]:
        """tuple of str (d,): the input names, in input order."""
        return self._names

    @property
    def dim(self) -> int:
        """int: the number of inputs d."""
        return len(self._marginals)

    @property
    def marginals(self) -> tuple:
        """tuple (d,): the frozen scipy distributions, in input order."""
        return self._marginals

    @property
    def families(self) -> tuple[str, ...]:
        """tuple of str (d,): the orthonormal polynomial family of each input (PCE)."""
        return tuple("legendre" if k == "uniform" else "hermite" for k in self._kind)

    def _moment(self, which: str) -> np.ndarray:
        out = np.empty(self.dim)
        for i, (m, kind, p) in enumerate(zip(self._marginals, self._kind, self._params,
                                             strict=True)):
            if kind == "uniform":
                loc, scale = p
                out[i] = {"mean": loc + scale / 2, "var": scale**2 / 12,
                          "sd": scale / np.sqrt(12.0)}[which]
            elif kind == "norm":
                loc, scale = p
                out[i] = {"mean": loc, "var": scale**2, "sd": scale}[which]
            else:
                out[i] = {"mean": m.mean, "var": m.var, "sd": m.std}[which]()
        return out

    @property
    def mean(self) -> np.ndarray:
        """(d,) ndarray: the means of the inputs (``loc + scale/2`` for a uniform)."""
        return self._moment("mean")

    @property
    def var(self) -> np.ndarray:
        """(d,) ndarray: the variances (``scale^2 / 12`` for a uniform, ``sd^2`` for a normal)."""
        return self._moment("var")

    @property
    def sd(self) -> np.ndarray:
        """(d,) ndarray: the standard deviations (``scale / sqrt 12``, or the normal's ``sd``)."""
        return self._moment("sd")

    @property
    def bounds(self) -> np.ndarray:
        """(2, d) ndarray: the lower and upper ends of the supports (ValueError if unbounded)."""
        b = np.array([m.support() for m in self._marginals], dtype=float).T
        if not np.all(np.isfinite(b)):
            bad = [n for n, ok in zip(self._names, np.isfinite(b).all(0), strict=True) if not ok]
            raise ValueError(f"input(s) {bad} have an unbounded law: no bounds")
        return b

    # --- samples ----------------------------------------------------------------------------

    def _check(self, x, what="inputs") -> np.ndarray:
        x = np.asarray(x, dtype=float)
        if x.ndim != 2 or x.shape[1] != self.dim:
            raise ValueError(f"{what} must be (n, {self.dim}), got {x.shape}")
        return x

    def from_unit(self, u) -> np.ndarray:
        """Unit-cube points to the inputs, each column through its law's inverse CDF.

        Uniform: ``loc + scale u``; normal: ``loc + scale Phi^-1(u)`` (``scipy.special.ndtri``,
        the function ``scipy.stats.norm.ppf`` evaluates, without its argument machinery: the
        same numbers, five times faster); any other law: its ``ppf``.  Row by row, so a design
        may be mapped a block at a time (:class:`~mtaccuracy.sensitivity.SobolDesign`).

        Parameters
        ----------
        u : (n, d) array
            Points of the unit hypercube, in [0, 1].

        Returns
        -------
        (n, d) ndarray
            The inputs in their physical units.

        Raises
        ------
        ValueError
            If ``u`` is not of shape ``(n, d)``.
        """
        u = self._check(u, "unit-cube points")
        x = np.empty_like(u)
        for i, (m, kind, p) in enumerate(zip(self._marginals, self._kind, self._params,
                                             strict=True)):
            if kind == "uniform":
                x[:, i] = p[0] + u[:, i] * p[1]
            elif kind == "norm":
                x[:, i] = p[0] + p[1] * ndtri(u[:, i])
            else:
                x[:, i] = m.ppf(u[:, i])
        return x

    def sample(self, n: int, *, method: str = "mc", seed=None) -> np.ndarray:
        """``n`` points of the inputs: unit-cube points through :meth:`from_unit`.

        The whole design of :meth:`sample_blocks` (one block): the same numbers, bitwise.

        Parameters
        ----------
        n : int
            Number of points (>= 1).
        method : {"mc", "lhs", "sobol"}
            ``mc``: independent uniforms of the generator (``Generator.random((n, d))``);
            ``lhs``: a Latin hypercube (``scipy.stats.qmc.LatinHypercube``); ``sobol``: a
            scrambled Sobol' sequence (``scipy.stats.qmc.Sobol``; n should be a power of 2,
            scipy warns otherwise).
        seed : None, int, SeedSequence or numpy.random.Generator
            The randomness (:func:`mtaccuracy.validate.rng`); a Generator's stream continues.

        Returns
        -------
        (n, d) ndarray
            The points, one row per point, in the inputs' units.

        Raises
        ------
        ValueError
            If ``n`` is not a positive integer or ``method`` is unknown.
        """
        n = integer(n, "n", low=1)
        (x,) = self.sample_blocks(n, method=method, seed=seed, rows=n)
        return x

    def sample_blocks(self, n: int, *, method: str = "mc", seed=None, rows: int
                      ) -> Iterator[np.ndarray]:
        """The design of :meth:`sample`, handed out ``rows`` points at a time.

        The one implementation of each design in this package; blocks are drawn as they are
        asked for, and their concatenation is :meth:`sample`'s design, bitwise:

        * ``mc``: each block continues one stream, ``Generator.random((m, d))`` (numpy draws
          the floats of a C-ordered array one after the other, so the pieces are the whole);
        * ``sobol``: successive points of one ``scipy.stats.qmc.Sobol`` sequence (``random``
          continues where it stopped); when ``n`` is not a power of 2 the warning scipy gives
          for the whole draw is given once here;
        * ``lhs``: a Latin hypercube is not a stream (each column is one random permutation
          of all n strata, so no point is known before the whole permutation is drawn): it is
          drawn whole when the first block is asked for (n d floats) and handed out in blocks.

        Parameters
        ----------
        n : int
            Number of points (>= 1).
        method : {"mc", "lhs", "sobol"}
            The design, as :meth:`sample`.
        seed : None, int, SeedSequence or numpy.random.Generator
            The randomness (:func:`mtaccuracy.validate.rng`); a Generator's stream continues
            as the blocks are drawn.
        rows : int
            Points per block (>= 1).

        Yields
        ------
        (m, d) ndarray
            The next ``m <= rows`` points, in the inputs' units.

        Raises
        ------
        ValueError
            If ``n`` or ``rows`` is not a positive integer or ``method`` is unknown (when
            called, before any block is drawn).
        """
        n = integer(n, "n", low=1)
        rows = integer(rows, "rows", low=1)
        if method not in METHODS:
            raise ValueError(f"unknown sampling method {method!r}; allowed: {', '.join(METHODS)}")
        return self._blocks(n, method, _rng(seed), rows)

    def _blocks(self, n, method, rng, rows):
        d = self.dim
        if method == "lhs":
            u = qmc.LatinHypercube(d=d, rng=rng).random(n)
            for s in range(0, n, rows):
                yield self.from_unit(u[s:s + rows])
        elif method == "mc":
            for s in range(0, n, rows):
                yield self.from_unit(rng.random((min(rows, n - s), d)))
        else:
            quiet = n > rows                   # the whole draw warns, not each block
            if quiet and n & (n - 1):
                warnings.warn(_SOBOL_BALANCE, UserWarning, stacklevel=3)
            seq = qmc.Sobol(d=d, scramble=True, rng=rng)
            for s in range(0, n, rows):       # no name keeps a block while the caller has it
                yield self.from_unit(_sobol_points(seq, min(rows, n - s), quiet))

    # --- standard variables of the polynomial chaos -----------------------------------------

    def to_standard(self, x) -> np.ndarray:
        """Physical inputs to the standard variables of their polynomial families.

        Uniform: ``z = 2 (x - lo)/(hi - lo) - 1``; normal: ``z = (x - mu)/sd``; any other
        law: ``z = Phi^-1(F(x))``.

        Parameters
        ----------
        x : (n, d) array
            Inputs in their physical units.

        Returns
        -------
        (n, d) ndarray
            The standard variables.

        Raises
        ------
        ValueError
            If ``x`` is not of shape ``(n, d)``.
        """
        x = self._check(x)
        z = np.empty_like(x)
        for i, (m, kind) in enumerate(zip(self._marginals, self._kind, strict=True)):
            if kind == "uniform":
                lo, hi = m.support()
                z[:, i] = 2 * (x[:, i] - lo) / (hi - lo) - 1
            elif kind == "norm":
                z[:, i] = (x[:, i] - m.mean()) / m.std()
            else:
                z[:, i] = stats.norm.ppf(m.cdf(x[:, i]))
        return z

    def from_standard(self, z) -> np.ndarray:
        """The inverse of :meth:`to_standard`.

        Parameters
        ----------
        z : (n, d) array
            Standard variables.

        Returns
        -------
        (n, d) ndarray
            The inputs in their physical units.

        Raises
        ------
        ValueError
            If ``z`` is not of shape ``(n, d)``.
        """
        z = self._check(z, "standard variables")
        x = np.empty_like(z)
        for i, (m, kind) in enumerate(zip(self._marginals, self._kind, strict=True)):
            if kind == "uniform":
                lo, hi = m.support()
                x[:, i] = lo + (z[:, i] + 1) * (hi - lo) / 2
            elif kind == "norm":
                x[:, i] = m.mean() + m.std() * z[:, i]
            else:
                x[:, i] = m.ppf(stats.norm.cdf(z[:, i]))
        return x


def _sobol_points(seq, m: int, quiet: bool) -> np.ndarray:
    """The next ``m`` points of the Sobol' sequence ``seq``, without scipy's balance warning
    when ``quiet`` (it was given once for the whole design)."""
    with warnings.catch_warnings():
        if quiet:
            warnings.filterwarnings("ignore", message="The balance properties")
        return seq.random(m)
