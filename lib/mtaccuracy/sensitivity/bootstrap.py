"""Bootstrap intervals of Sobol indices: resamples of the N base rows, held or streamed.

A bootstrap re-estimates the indices on resamples of the N base rows (a row being A's row, B's
row and the D AB_i rows built from them), and reports the spread of the re-estimates: the
half-width of a ``conf`` interval is the normal quantile times their standard deviation, as
SALib reports it (:func:`ci_half_width`).  Every term of the estimator (Saltelli 2010 and
Jansen, :func:`~mtaccuracy.sensitivity.sobol_estimate`) is a mean over rows, so a resample is a
weight per row, its count, and the re-estimate is the same estimator on the reweighted rows.
Two ways to draw the weights:

* **held** (:func:`sobol_bootstrap_samples`, :func:`sobol_bootstrap`), on the outputs
  :func:`~mtaccuracy.sensitivity.sobol_evaluate` keeps: the classic bootstrap, resamples of N
  rows drawn with replacement (:func:`bootstrap_counts`, SALib's ``rng.integers(0, N)``); each
  resample needs all N rows' draws, so the outputs and the per-row terms are held (16 kB per
  base row at D = 41, q = 6: 1.7 GB at N = 1e5).  Notebooks 02 and 06 use it.
* **streamed** (``sobol_indices(..., n_boot=, seed=)``): the Poisson bootstrap (Hanley &
  MacGibbon 2006; Chamandy et al. 2012, the bootstrap of data streams), in which the count of
  each row in each resample is an independent Poisson(1) draw (:func:`bootstrap_weights`), so
  the weights of a block of rows are drawn with that block, in row order, and the weighted sums
  of the estimator are accumulated block by block (:class:`StreamedBootstrap`): memory flat in
  N.  A resample then has N rows on average (not exactly N: its sums are divided by its own
  total weight); its re-estimates follow the classic bootstrap's distribution as N grows (a
  test checks the two half-widths agree, and that the intervals cover the exact indices of a
  linear model at their level).  The resamples differ from the held bootstrap's: the two give
  the same intervals up to their own Monte Carlo noise, not the same numbers.
"""

from __future__ import annotations

__all__ = ["bootstrap_counts", "sobol_bootstrap_samples", "ci_half_width", "sobol_bootstrap",
           "bootstrap_weights", "StreamedBootstrap"]

from collections.abc import Iterator

import numpy as np
from scipy import stats

from ..validate import integer
from ..validate import rng as _rng


def bootstrap_counts(n: int, n_boot: int, *, seed, chunk: int = 20, block: int = 2**21):
    """The ``n_boot`` bootstrap resamples of ``n`` rows as counts, a few resamples at a time.

    Yields (k, n) float arrays ``w`` with ``w[b, i]`` = how often row i is drawn in resample
    b, about ``block / n`` resamples at a time (one matrix product each; many small products
    are slow when a multi-threaded BLAS shares a busy machine).

    The draws are ``rng.integers(0, n, size=(k, n))`` for successive chunks of ``k <= chunk``
    resamples of one generator ``mtaccuracy.validate.rng(seed)``: the resamples that
    :func:`sobol_bootstrap` has always used (and the key-set frequencies of
    ``screening.key_set_bootstrap``, which take its re-estimates).

    Parameters
    ----------
    n : int
        Rows (>= 1).
    n_boot : int
        Resamples (>= 1).
    seed : None, int, SeedSequence or numpy.random.Generator
        The randomness (:func:`mtaccuracy.validate.rng`).
    chunk : int
        Resamples per draw (>= 1).
    block : int
        Counts held at a time.

    Yields
    ------
    array (k, n)
        Counts of k resamples.
    """
    n = integer(n, "n", low=1)
    n_boot = integer(n_boot, "n_boot", low=1)
    chunk = integer(chunk, "chunk", low=1)
    rng = _rng(seed)
    per_block = max(chunk, block // max(n, 1))
    drawn = []
    for start in range(0, int(n_boot), chunk):
        drawn.append(rng.integers(0, n, size=(min(chunk, int(n_boot) - start), n)))
        if sum(len(d) for d in drawn) >= per_block or start + chunk >= n_boot:
            idx = np.concatenate(drawn)
            drawn = []
            k = idx.shape[0]
            flat = (idx + n * np.arange(k)[:, None]).ravel()
            yield np.bincount(flat, minlength=k * n).reshape(k, n).astype(float)


def sobol_bootstrap_samples(ya, yb, yab, *, n_boot: int, seed, chunk: int = 20,
                            block: int = 2**21) -> tuple[np.ndarray, np.ndarray]:
    """S1 and ST re-estimated on ``n_boot`` resamples of the N base rows: (n_boot, D, q) each.

    The same estimates as :func:`sobol_estimate` on ``ya[idx], yb[idx], yab[:, idx]`` for the
    resamples of :func:`bootstrap_counts`, computed without copying the resampled rows: every
    term of the estimator is a mean over rows, so a resample is a weight vector (the counts)
    and all resamples of a chunk are one matrix product of the counts with the per-row terms
    (``ya``, ``yb``, their squares, ``sum_i yab_i``, and per input ``yab_i - ya``,
    ``yb (yab_i - ya)``, ``(yab_i - ya)^2``).  Outputs are centred on their overall mean first
    (the indices do not change), so the variance ``E[y^2] - E[y]^2`` has no cancellation.
    Memory: N x (3 + 3 D) q floats, and ``block`` counts at a time.  Sums in a different order
    than :func:`sobol_estimate`: equal to it within floating-point rounding (a test checks
    1e-12).

    Parameters
    ----------
    ya, yb : arrays (N, q)
        The outputs on A and on B.
    yab : array (D, N, q)
        As :func:`sobol_evaluate` returns them.
    n_boot : int
        Resamples.
    seed : None, int, SeedSequence or numpy.random.Generator
        The randomness of the resampling (:func:`mtaccuracy.validate.rng`).
    chunk, block : int
        As :func:`bootstrap_counts`.

    Returns
    -------
    s1, st : arrays (n_boot, D, q)
        The re-estimates, one per resample.
    """
    ya, yb, yab = (np.asarray(v, dtype=float) for v in (ya, yb, yab))
    n, q = ya.shape
    d = yab.shape[0]
    centre = np.concatenate([ya, yb]).mean(0)
    ya, yb, yab = ya - centre, yb - centre, yab - centre
    diff = (yab - ya[None]).transpose(1, 0, 2).reshape(n, d * q)          # (N, D q)
    ybd = diff * np.tile(yb, d)
    rows = np.concatenate([ya + yb, ya**2 + yb**2, yab.sum(0) + ya + yb, diff, ybd, diff**2],
                          axis=1)
    s1s, sts = [], []
    for w in bootstrap_counts(n, n_boot, seed=seed, chunk=chunk, block=block):
        m = (w @ rows) / n                                                  # (k, 3q + 3Dq)
        mean_y = m[:, :q] / 2
        var = m[:, q:2 * q] / 2 - mean_y**2                                 # (k, q)
        mu = m[:, 2 * q:3 * q] / (d + 2)
        md, mybd, md2 = (m[:, (3 + j * d) * q:(3 + (j + 1) * d) * q].reshape(-1, d, q)
                         for j in range(3))
        s1s.append((mybd - mu[:, None, :] * md) / var[:, None, :])
        sts.append(0.5 * md2 / var[:, None, :])
    return np.concatenate(s1s), np.concatenate(sts)


def ci_half_width(samples: np.ndarray, conf: float = 0.95) -> np.ndarray:
    """Half-width of the ``conf`` interval from bootstrap ``samples`` (leading axis), as SALib's.

    The normal quantile times their standard deviation (ddof 1), as SALib reports it.

    Parameters
    ----------
    samples : array (n_boot, ...)
        Bootstrap estimates.
    conf : float
        Confidence level, in (0, 1).

    Returns
    -------
    array (...)
        The half-widths, one per estimate.
    """
    z = stats.norm.ppf(0.5 + conf / 2)
    return z * np.asarray(samples).std(axis=0, ddof=1)


def sobol_bootstrap(ya, yb, yab, *, n_boot: int, seed, conf: float = 0.95, chunk: int = 20):
    """Bootstrap half-widths of the ``conf`` confidence intervals of S1 and ST, (D, q) each.

    From ``n_boot`` resamples of the N base rows (as SALib: normal quantile times the
    bootstrap standard deviation); see :func:`sobol_bootstrap_samples`.

    Parameters
    ----------
    ya, yb : arrays (N, q)
        The outputs on A and on B.
    yab : array (D, N, q)
        As :func:`sobol_evaluate` returns them.
    n_boot : int
        Resamples.
    seed : None, int, SeedSequence or numpy.random.Generator
        The randomness of the resampling (:func:`mtaccuracy.validate.rng`).
    conf : float
        Confidence level.
    chunk : int
        As :func:`bootstrap_counts`.

    Returns
    -------
    s1_half, st_half : arrays (D, q)
        Half-widths of the intervals.
    """
    s1s, sts = sobol_bootstrap_samples(ya, yb, yab, n_boot=n_boot, seed=seed, chunk=chunk)
    return ci_half_width(s1s, conf), ci_half_width(sts, conf)


def bootstrap_weights(n: int, n_boot: int, *, seed, rows: int) -> Iterator[np.ndarray]:
    """Poisson(1) bootstrap weights of ``n`` rows in ``n_boot`` resamples, ``rows`` rows at a time.

    Yields (m, n_boot) float arrays ``w`` with ``w[i, b]`` the count of row i in resample b,
    independent Poisson(1) draws, each by inversion of one uniform ``u`` (the smallest k with
    ``u < F(k)``, F the Poisson(1) distribution function).  The uniforms are one stream of the
    generator ``mtaccuracy.validate.rng(seed)`` in row order (``Generator.random((m, n_boot))``
    for successive blocks: the n_boot counts of a row one after the other), so the
    concatenated blocks are the counts of ``Generator.random((n, n_boot))`` whatever ``rows``
    is: the resamples of :func:`~mtaccuracy.sensitivity.sobol_indices` do not depend on its
    blocks.

    Parameters
    ----------
    n : int
        Rows (>= 1).
    n_boot : int
        Resamples (>= 1).
    seed : None, int, SeedSequence or numpy.random.Generator
        The randomness (:func:`mtaccuracy.validate.rng`).
    rows : int
        Rows per block (>= 1).

    Yields
    ------
    array (m, n_boot)
        The counts of the next m <= rows rows, as floats.
    """
    n = integer(n, "n", low=1)
    n_boot = integer(n_boot, "n_boot", low=1)
    rows = integer(rows, "rows", low=1)
    rng = _rng(seed)
    return (_poisson_counts(rng, min(rows, n - s), n_boot) for s in range(0, n, rows))


#: The Poisson(1) distribution function at 0, 1, ..., 19 (``sum_j<=k e^-1 / j!``): beyond 19
#: it is 1 to the last bit (``P(X > 19) < 1e-18``).
_POISSON1_CDF = np.cumsum(np.exp(-1.0) / np.cumprod(np.r_[1.0, np.arange(1.0, 20.0)]))


def _poisson_counts(rng, m, n_boot):
    """The next ``m n_boot`` Poisson(1) counts of ``rng``, row by row, as an (m, n_boot) float
    array: by inversion, ``min{k : u < F(k)}`` of one uniform ``u`` each (``rng.random``; four
    times quicker than ``Generator.poisson``, and a plain stream of uniforms)."""
    u = rng.random((m, n_boot))
    return np.searchsorted(_POISSON1_CDF, u, side="right").astype(float)


class StreamedBootstrap:
    """The weighted sums of the Sobol estimator on Poisson bootstrap resamples, block by block.

    What ``sobol_indices(..., n_boot=, seed=)`` keeps besides its own sums: per resample b, with
    ``w`` the rows' Poisson(1) counts (:meth:`weights`, drawn in row order) and the outputs
    shifted by ``c``, the first block's mean of ``ya`` and ``yb`` (so the sums of squares do not
    cancel), the total weight ``W = sum w``, ``sum w (ya + yb)``, ``sum w (ya^2 + yb^2)``,
    ``sum w (ya + yb + sum_i yab_i)``, and per input i ``sum w d_i``, ``sum w yb d_i`` and
    ``sum w d_i^2`` with ``d_i = yab_i - ya``: (n_boot, D, q) floats each, whatever N.
    :meth:`estimates` turns them into the estimator of
    :func:`~mtaccuracy.sensitivity.sobol_estimate` on each reweighted set of rows: the variance
    of the A and B outputs, ``mu`` the mean of all N (D + 2) runs, ``S1_i = mean(w (yb - mu)
    d_i) / var`` and ``ST_i = mean(w d_i^2) / (2 var)``, every mean a weighted one (divided by
    ``W``).  Written by hand: no library streams a bootstrap of these estimators.

    Parameters
    ----------
    n_boot : int
        Resamples (>= 2).
    seed : None, int, SeedSequence or numpy.random.Generator
        The randomness of the weights (:func:`mtaccuracy.validate.rng`).
    d : int
        Inputs D (>= 1).
    """

    def __init__(self, n_boot: int, seed, *, d: int):
        self.n_boot = integer(n_boot, "n_boot", low=2)
        self.d = integer(d, "d", low=1)
        self._rng = _rng(seed)
        self._centre = None
        self._sums = None

    def weights(self, m: int) -> np.ndarray:
        """The Poisson(1) counts of the next ``m`` rows in every resample, (m, n_boot) floats.

        Parameters
        ----------
        m : int
            Rows.

        Returns
        -------
        array (m, n_boot)
            Counts: Poisson(1) draws by inversion of the generator's next ``m n_boot``
            uniforms, in row order.
        """
        return _poisson_counts(self._rng, m, self.n_boot)

    def add_base(self, w: np.ndarray, ya: np.ndarray, yb: np.ndarray):
        """Add a block's A and B terms: its weights, the weighted sums of ``ya + yb`` and squares.

        The first block fixes the centre ``c`` (its mean of ``ya`` and ``yb``).

        Parameters
        ----------
        w : array (m, n_boot)
            The block's weights (:meth:`weights`).
        ya, yb : arrays (m, q)
            The outputs on the block's rows of A and B.
        """
        if self._centre is None:
            self._centre = np.concatenate([ya, yb]).mean(0)
            q = ya.shape[1]
            self._sums = dict(w=np.zeros(self.n_boot), y=np.zeros((self.n_boot, 3 * q)),
                              d=np.zeros((self.n_boot, 3 * self.d * q)))
        yac, ybc = ya - self._centre, yb - self._centre
        s = yac + ybc
        terms = np.concatenate([s, yac * yac + ybc * ybc, s], axis=1)   # the runs: A and B
        self._sums["w"] += w.sum(0)
        self._sums["y"] += w.T @ terms

    def add_inputs(self, w: np.ndarray, i0: int, i1: int, diff: np.ndarray, ya: np.ndarray,
                   yb: np.ndarray):
        """Add the AB_i terms of inputs ``i0 .. i1 - 1`` of a block (after its :meth:`add_base`).

        The weighted sums of ``d_i``, ``(yb - c) d_i`` and ``d_i^2``, and of the AB_i runs,
        ``yab_i - c = d_i + ya - c``, in the mean of all runs.

        Parameters
        ----------
        w : array (m, n_boot)
            The block's weights.
        i0, i1 : int
            The inputs, ``i0 <= i < i1``.
        diff : array (i1 - i0, m, q)
            ``yab_i - ya`` of those inputs on the block's rows.
        ya, yb : arrays (m, q)
            The outputs on the block's rows of A and B.
        """
        k, m, q = diff.shape
        dd = diff.transpose(1, 0, 2).reshape(m, k * q)
        runs = diff.sum(0) + k * (ya - self._centre)
        terms = np.concatenate([dd, dd * np.tile(yb - self._centre, k), dd * dd, runs], axis=1)
        part = w.T @ terms                                         # (n_boot, 3 k q + q)
        dq, kq = self.d * q, k * q
        for j in range(3):
            self._sums["d"][:, j * dq + i0 * q:j * dq + i1 * q] += part[:, j * kq:(j + 1) * kq]
        self._sums["y"][:, 2 * q:] += part[:, 3 * kq:]

    def estimates(self) -> tuple[np.ndarray, np.ndarray]:
        """S1 and ST re-estimated on every resample, (n_boot, D, q) each.

        Returns
        -------
        s1, st : arrays (n_boot, D, q)
            The re-estimates (NaN for a resample of total weight 0, which has probability
            ``exp(-N)``).
        """
        s = self._sums
        q = s["y"].shape[1] // 3
        with np.errstate(invalid="ignore", divide="ignore"):
            wt = s["w"][:, None]                                                   # (n_boot, 1)
            mean = s["y"][:, :q] / (2 * wt)
            var = (s["y"][:, q:2 * q] / (2 * wt) - mean**2)[:, None, :]
            mu = (s["y"][:, 2 * q:] / ((self.d + 2) * wt))[:, None, :]
            sd_, sbd, sd2 = (s["d"][:, j * self.d * q:(j + 1) * self.d * q]
                             .reshape(-1, self.d, q) / wt[:, :, None] for j in range(3))
            return (sbd - mu * sd_) / var, 0.5 * sd2 / var
