"""Samplers and sensitivity measures, batched over samples (and over repeats).

Spearman ranking (Guo et al. 2016) lives here; Sobol estimators, sparse polynomial chaos and
key-error rules join it with the later papers.  Latin hypercubes are drawn by
:meth:`~mtaccuracy.sensitivity.Inputs.sample` (``scipy.stats.qmc.LatinHypercube``), the
package's one sampler; ranks are ``scipy.stats.rankdata``.
"""

from __future__ import annotations

__all__ = ["latin_hypercube", "repeated_latin_hypercube", "average_ranks",
           "SpearmanCoefficients", "POSITION_OUTPUTS", "spearman", "centred_ranks",
           "rank_by_magnitude", "below_group_mean",
           "position_outputs", "spearman_over_poses", "rank_positions", "rank_intervals",
           "sum_of_squares", "rank_r_squared", "lhs_rank_eigenvalues"]

import numpy as np
from scipy import stats

from mtaccuracy import validate

from .inputs import Inputs
from .results import IndexArray


def latin_hypercube(n: int, bounds: np.ndarray, seed) -> np.ndarray:
    """``n`` Latin hypercube samples (n, d) of independent uniforms on ``bounds`` (2, d).

    The design is :meth:`Inputs.sample` of the unit cube (``method="lhs"``,
    ``scipy.stats.qmc.LatinHypercube``: random placement within strata), mapped to the
    bounds as ``lower + u (upper - lower)`` (what :meth:`Inputs.from_unit` computes for a
    uniform, bitwise).  A thin adaptor for designs given by bounds: unlike
    :meth:`Inputs.from_bounds` it takes a zero-width column (``lower == upper``, an input held
    at one value), which no probability law describes.

    Parameters
    ----------
    n : int
        Samples (>= 2), one per stratum of every input.
    bounds : array (2, d)
        Lower and upper bounds of the d inputs (mm, rad), ``lower <= upper``.
    seed : int, SeedSequence, Generator or None
        The randomness (:func:`mtaccuracy.validate.rng`); a Generator is used as it is, so the
        caller's stream continues.

    Returns
    -------
    array (n, d)
        The design, in the units of ``bounds``.

    Raises
    ------
    ValueError
        If ``n`` < 2, ``bounds`` is not (2, d), not finite, or has ``upper < lower``.
    """
    bounds = np.asarray(bounds, dtype=float)
    if bounds.ndim != 2 or bounds.shape[0] != 2:
        raise ValueError(f"bounds must have shape (2, d), got {bounds.shape}")
    n = validate.integer(n, "n", low=2)
    if not np.all(np.isfinite(bounds)) or np.any(bounds[1] < bounds[0]):
        raise ValueError("bounds must be finite with lower <= upper")
    u = Inputs.unit(bounds.shape[1]).sample(n, method="lhs", seed=seed)
    return bounds[0] + u * (bounds[1] - bounds[0])


def repeated_latin_hypercube(n: int, bounds: np.ndarray, *, repeats: int, seed) -> np.ndarray:
    """``repeats`` independent Latin hypercube designs, (repeats, n, d).

    Each design gets its own child of ``numpy.random.SeedSequence(seed)``, so design ``r`` is
    the same whatever ``repeats`` is.

    Parameters
    ----------
    n : int
        Samples per design (>= 2).
    bounds : array (2, d)
        Lower and upper bounds of the d inputs (mm, rad).
    repeats : int
        Independent designs (>= 1).
    seed : int
        Seed of the parent ``SeedSequence``, whose children seed the designs.

    Returns
    -------
    array (repeats, n, d)
        The designs, in the units of ``bounds``.
    """
    repeats = validate.integer(repeats, "repeats", low=1)
    children = np.random.SeedSequence(seed).spawn(repeats)
    return np.stack([latin_hypercube(n, bounds, np.random.default_rng(c)) for c in children])


def average_ranks(a: np.ndarray) -> np.ndarray:
    """Ranks 1..n along axis -2, ties getting their average rank (``scipy.stats.rankdata``).

    One stable argsort; only when some column has equal values does it fall back to scipy's
    ``rankdata`` (continuous samples have none, so the fallback is rare).

    Parameters
    ----------
    a : array (..., n, k)
        Samples along axis -2.

    Returns
    -------
    array (..., n, k)
        Ranks 1..n (floats).
    """
    a = np.asarray(a, dtype=float)
    order = np.argsort(a, axis=-2, kind="stable")
    s = np.take_along_axis(a, order, axis=-2)
    if np.any(s[..., 1:, :] == s[..., :-1, :]) or np.isnan(s).any():
        return stats.rankdata(a, axis=-2)
    ranks = np.empty_like(a)
    n = a.shape[-2]
    np.put_along_axis(ranks, order, np.broadcast_to(np.arange(1.0, n + 1.0)[:, None],
                                                    a.shape), axis=-2)
    return ranks


def _centred(r: np.ndarray) -> np.ndarray:
    return r - r.mean(axis=-2, keepdims=True)


def _correlate(rx: np.ndarray, ry: np.ndarray) -> np.ndarray:
    """Pearson correlation of centred ranks (..., n, p) and (..., n, q) -> (..., p, q).

    Centred ranks are multiples of 1/2, their products of 1/4, and for n < 10^5 every partial
    sum stays far below 2^53 / 4: the numerator is exact in floating point whatever the
    summation order (any BLAS kernel gives the same bits), and so is the sum of squares."""
    num = np.swapaxes(rx, -1, -2) @ ry
    den = (np.sqrt((rx**2).sum(axis=-2))[..., :, None]
           * np.sqrt((ry**2).sum(axis=-2))[..., None, :])
    with np.errstate(invalid="ignore", divide="ignore"):
        return num / den


class SpearmanCoefficients(IndexArray):
    """Spearman coefficients ``(..., p, q)`` of p inputs with q outputs, labelled.

    What :func:`spearman` and :func:`spearman_over_poses` return: the array of coefficients
    (indexed and computed with as any array; what is computed from it is a plain array) that
    also knows its input and output names, and whose :meth:`to_df` is the ranking: per output,
    each input's coefficient ``rho`` and its ``rank`` by ``|rho|`` (:func:`rank_positions`:
    1 = largest, equal magnitudes in catalogue order).

    >>> r = SpearmanCoefficients([[0.2, -0.9], [-0.7, 0.1]], names=["a", "b"], outputs=["X", "Y"])
    >>> r.to_df().values.tolist()
    [['X', 'a', 0.2, 2], ['X', 'b', -0.7, 1], ['Y', 'a', -0.9, 1], ['Y', 'b', 0.1, 2]]

    Parameters
    ----------
    values : (..., p, q) array_like
        The coefficients, inputs by outputs, after any leading axes (poses, designs).
    names : sequence of str (p,), optional
        Input names (default ``x1`` ... ``xp``).
    outputs : sequence of str (q,), optional
        Output names (default ``y1`` ... ``yq``).
    lead : sequence of str, optional
        Names of the leading axes (default ``axis0``, ...).
    """

    columns = ("rho", "rank")

    def _values(self) -> dict[str, np.ndarray]:
        """``rho`` and its ``rank`` per output, in :meth:`to_df`'s row order."""
        v = self.view(np.ndarray)
        return {"rho": np.moveaxis(v, -1, -2).ravel(),
                "rank": np.moveaxis(rank_positions(v), -1, -2).ravel()}


def spearman(x: np.ndarray, y: np.ndarray, *, names=None, outputs=None) -> SpearmanCoefficients:
    """Spearman rank correlation of every column of ``x`` with every column of ``y``.

    ``x`` (..., n, p) and ``y`` (..., n, q) share the sample axis ``-2``; leading axes
    broadcast (e.g. repeats or poses).  Returns (..., p, q).  Ties get average ranks (Eq. 15
    of Guo et al. 2016 is Pearson's correlation of the ranks).  The coefficients are exact
    rationals computed without rounding in the numerator (see :func:`_correlate`), so two
    coefficients that are equal in exact arithmetic are equal to the bit, and a ranking of
    them (:func:`rank_by_magnitude`) breaks the tie by catalogue order on every machine.
    A column with a single value has no rank correlation: NaN.

    Parameters
    ----------
    x : array (..., n, p)
        Inputs, samples along axis -2.
    y : array (..., n, q)
        Outputs on the same samples.
    names : sequence of str (p,), optional
        Input names (default ``x1`` ... ``xp``), labels of the result.
    outputs : sequence of str (q,), optional
        Output names (default ``y1`` ... ``yq``).

    Returns
    -------
    SpearmanCoefficients (..., p, q)
        Coefficients in [-1, 1] (NaN for a constant column); ``.to_df()`` ranks them.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if x.shape[-2] != y.shape[-2]:
        raise ValueError(f"x and y need the same number of samples, got {x.shape} and {y.shape}")
    rho = _correlate(_centred(average_ranks(x)), _centred(average_ranks(y)))
    return SpearmanCoefficients(rho, names=names, outputs=outputs)


def rank_by_magnitude(values: np.ndarray, names: list[str]) -> list[tuple[str, float]]:
    """(name, value) pairs by decreasing ``|value|``, equal ``|value|`` in catalogue order.

    For Spearman coefficients equal means equal to the bit (see :func:`spearman`); distinct
    coefficients of n samples differ by at least 1/4 of a rank product, about 3/n^3 of the
    denominator, far above rounding, so no tolerance is needed.

    Parameters
    ----------
    values : array (p,)
        Coefficients (their sign is kept, their magnitude ranks them).
    names : list of str (p,)
        Input names, in catalogue order: the order of equal magnitudes.

    Returns
    -------
    list of (str, float)
        Largest magnitude first.
    """
    values = np.asarray(values, dtype=float)
    order = sorted(range(len(names)), key=lambda j: (-abs(values[j]), j))
    return [(names[j], float(values[j])) for j in order]


def below_group_mean(coefficients: np.ndarray) -> np.ndarray:
    """Guo et al.'s weak-error rule: below the mean ``|rho|`` of its output, for every output.

    Parameters
    ----------
    coefficients : array (p, q)
        Spearman coefficients of p inputs with q outputs.

    Returns
    -------
    array of bool (p,)
        True for the weak inputs.
    """
    a = np.abs(np.asarray(coefficients, dtype=float))
    return np.all(a < a.mean(axis=0, keepdims=True), axis=1)


#: Names of the outputs of :func:`position_outputs`.
POSITION_OUTPUTS = ("Ex", "Ey", "Ez", "Et")


def position_outputs(pose_error: np.ndarray) -> np.ndarray:
    """Ex, Ey, Ez and Et = sqrt(Ex^2 + Ey^2 + Ez^2) (Guo et al. Eq. 14) from the pose errors.

    Parameters
    ----------
    pose_error : array (..., 6)
        Px, Py, Pz (mm), Vx, Vy, Vz (rad).

    Returns
    -------
    array (..., 4)
        Ex, Ey, Ez, Et (mm).
    """
    p = np.asarray(pose_error)[..., :3]
    return np.concatenate([p, np.linalg.norm(p, axis=-1, keepdims=True)], axis=-1)


def centred_ranks(samples: np.ndarray) -> np.ndarray:
    """Average ranks along axis -2 minus their mean, the design's part of a Spearman coefficient.

    What :func:`spearman_over_poses` needs of the design, computed once for an optimiser that
    calls it many times.

    Parameters
    ----------
    samples : array (..., n, d)
        The design, samples along axis -2.

    Returns
    -------
    array (..., n, d)
        Centred ranks (multiples of 1/2).
    """
    return _centred(average_ranks(samples))


def spearman_over_poses(machine, samples: np.ndarray, poses: dict, *, outputs=position_outputs,
                        chunk: int = 64, sample_ranks: np.ndarray | None = None,
                        names=None, output_names=None) -> SpearmanCoefficients:
    """Spearman coefficients of every error with every output, at many poses.

    One error design is reused at every pose (common random numbers).  Poses are evaluated in
    chunks, each chunk as one batched model call over ``chunk * n`` rows.

    Parameters
    ----------
    machine : ChainMachine
        Any object with ``pose_error(errors, pose)`` (errors (N, d) -> (N, 6)).
    samples : array (n, d)
        One error design (mm, rad), reused at every pose.
    poses : dict
        Axis name -> (P,) array of its values (mm, rad), one entry per pose.
    outputs : callable
        ``(..., 6) -> (..., q)``, the outputs ranked (default :func:`position_outputs`).
    chunk : int
        Poses per batched model call (>= 1): memory against the number of calls.
    sample_ranks : array (n, d), optional
        :func:`centred_ranks` of ``samples``, if already computed (an optimiser calling this
        many times computes them once).
    names : sequence of str (d,), optional
        Error names (default: the machine's ``error_names`` when it has d of them, else
        ``x1`` ... ``xd``), labels of the result.
    output_names : sequence of str (q,), optional
        Output names (default :data:`POSITION_OUTPUTS` for :func:`position_outputs`, else
        ``y1`` ... ``yq``).

    Returns
    -------
    SpearmanCoefficients (P, d, q)
        The coefficients per pose, error and output (leading axis ``pose``).
    """
    chunk = validate.integer(chunk, "chunk", low=1)
    samples = np.asarray(samples, dtype=float)
    n = samples.shape[0]
    sizes = {np.size(v) for v in poses.values()}
    if len(sizes) != 1:
        raise ValueError(f"pose arrays must have one common length, got {sorted(sizes)}")
    n_poses = sizes.pop()
    rx = centred_ranks(samples) if sample_ranks is None else np.asarray(sample_ranks)
    out = []
    for start in range(0, n_poses, chunk):
        stop = min(start + chunk, n_poses)
        k = stop - start
        pose = {name: np.repeat(np.asarray(v, dtype=float)[start:stop], n)
                for name, v in poses.items()}
        y = outputs(machine.pose_error(np.tile(samples, (k, 1)), pose)).reshape(k, n, -1)
        ry = _centred(average_ranks(y))
        out.append(_correlate(np.broadcast_to(rx, (k,) + rx.shape), ry))
    rho = np.concatenate(out, axis=0)
    if names is None:
        names = getattr(machine, "error_names", None)
        names = names if names is not None and len(names) == rho.shape[1] else None
    if output_names is None and outputs is position_outputs:
        output_names = POSITION_OUTPUTS
    return SpearmanCoefficients(rho, names=names, outputs=output_names, lead=("pose",))


def rank_positions(coefficients: np.ndarray) -> np.ndarray:
    """Rank (1 = largest ``|rho|``) of every input in every output column, batched.

    ``coefficients`` (..., p, q) as returned by :func:`spearman`; returns integer ranks of the
    same shape, equal ``|rho|`` ranked in input (catalogue) order as in
    :func:`rank_by_magnitude`.

    Parameters
    ----------
    coefficients : array (..., p, q)
        Spearman coefficients of p inputs (catalogue order) with q outputs, as
        :func:`spearman` returns them.

    Returns
    -------
    array of int (..., p, q)
        1 = largest ``|rho|``.
    """
    a = -np.abs(np.asarray(coefficients, dtype=float))
    order = np.argsort(a, axis=-2, kind="stable")  # stable: equal |rho| keep catalogue order
    ranks = np.empty(a.shape, dtype=int)
    np.put_along_axis(ranks, order, np.broadcast_to(
        np.arange(1, a.shape[-2] + 1)[:, None], a.shape), axis=-2)
    return ranks


def rank_intervals(repeated: np.ndarray, level: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
    """Sampling interval of each input's rank: its central range over repeated designs.

    ``numpy.quantile`` with ``method="inverted_cdf"``, so both ends are ranks that occurred.

    Parameters
    ----------
    repeated : array (R, p, q)
        Coefficients of R >= 2 independent designs of the same size.
    level : float
        Central share of the ranks covered, in (0, 1).

    Returns
    -------
    lo, hi : arrays of int (p, q)
        The interval's ends (1 = largest ``|rho|``).
    """
    r = rank_positions(repeated)
    if r.ndim != 3 or r.shape[0] < 2:
        raise ValueError(f"need coefficients of at least 2 designs, shape (R, p, q); got {r.shape}")
    if not 0 < level < 1:  # an open interval: validate.probability allows 0 and 1
        raise ValueError(f"level must be in (0, 1), got {level!r}")
    a = (1 - level) / 2
    lo = np.quantile(r, a, axis=0, method="inverted_cdf")
    hi = np.quantile(r, 1 - a, axis=0, method="inverted_cdf")
    return lo.astype(int), hi.astype(int)


def sum_of_squares(coefficients: np.ndarray) -> np.ndarray:
    """Sum over the inputs (axis -2) of the squared Spearman coefficients, (..., q).

    A necessary condition, whatever the model: for *independent* inputs the population sum is
    at most 1.  The population Spearman coefficient is Pearson's correlation of
    ``U_i = F_i(X_i)`` with ``V = G(Y)``; independent inputs give independent, hence
    uncorrelated, ``U_i``, and Bessel's inequality for the orthonormal standardised ``U_i``
    gives ``sum_i corr(U_i, V)^2 <= 1`` (equality when ``V`` is a linear function of the
    ``U_i``: a rank-linear model).  A sample of n points adds about (number of inputs) / n on
    average (each coefficient's sampling variance) and spreads by its own sampling noise;
    :func:`rank_r_squared` gives the exact sample bound.

    Parameters
    ----------
    coefficients : array (..., p, q)
        Spearman coefficients of p independent inputs with q outputs.

    Returns
    -------
    array (..., q)
        The sum per output (at most 1 in the population, see above).
    """
    return (np.asarray(coefficients, dtype=float) ** 2).sum(axis=-2)


def rank_r_squared(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """R^2 of the regression of the ranks of each ``y`` column on the ranks of all of ``x``.

    ``r^T C^{-1} r`` with ``r`` the Spearman coefficients and ``C`` the rank correlation
    matrix of the design: at most 1 in every sample (it is an R^2), and equal to
    :func:`sum_of_squares` when the design's ranks are exactly uncorrelated.

    Parameters
    ----------
    x : array (n, p)
        The design (its rank correlation matrix must be invertible).
    y : array (n, q)
        Outputs on the design.

    Returns
    -------
    array (q,)
        R^2 per output, in [0, 1].
    """
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    r = spearman(x, y)
    c = spearman(x, x)
    return np.einsum("pq,pq->q", r, np.linalg.solve(c, r))


#: designs per random block of :func:`lhs_rank_eigenvalues` (each block has its own child seed)
EIGEN_BLOCK = 500


def lhs_rank_eigenvalues(n: int, k: int, *, designs: int, seed) -> np.ndarray:
    """Largest eigenvalue of the k-input rank-correlation matrix of random Latin hypercubes.

    One value per independent ``n``-run design: the model-free bound on the sum of squared
    Spearman coefficients over any ``k`` inputs.

    For any output ``y`` whatsoever (any model, any pose, even noise), let ``U`` (n, k) hold
    the centred ranks of the ``k`` inputs scaled to unit length, ``v`` the same for ``y``,
    ``r = U^T v`` their Spearman coefficients and ``R = U^T U`` the inputs' sample rank
    correlation matrix.  Then ``sum r_i^2 = v^T U U^T v <= lambda_max(U U^T) =
    lambda_max(R)``; it is attained when the ranks of ``y`` are those of ``U a`` with ``a``
    the top eigenvector.  (Also ``r^T R^{-1} r <= 1``: the R^2 of the ranks of ``y`` on the
    inputs' ranks, :func:`rank_r_squared`.)  By Cauchy interlacing ``lambda_max(R_S) <=
    lambda_max(R_T)`` for ``S`` within ``T``, so the value for all ``d`` inputs of a design
    bounds every subset, however it was picked.  With uncorrelated population inputs
    ``R -> I`` as ``n`` grows, but at finite ``n`` ``lambda_max(R) > 1``: this function gives
    its distribution, so that a sum of squares printed without its design can be tested
    (Guo et al. 2016, Fig. 3, n = 500).

    The column ranks of a Latin hypercube design (``scipy.stats.qmc.LatinHypercube``, random
    placement within strata) are independent uniformly random permutations of 1..n, whatever
    the marginal laws, so the distribution depends on ``n`` and ``k`` only; ``R`` is
    invariant under a common relabelling of the runs, so the first column is taken as the
    identity.  The numerator is exact (products of half-integer centred ranks); designs are
    drawn in blocks of :data:`EIGEN_BLOCK`, block ``b`` from child ``b`` of
    ``numpy.random.SeedSequence(seed)``, so design ``i`` is the same whatever ``designs`` is.

    Parameters
    ----------
    n : int
        Runs per design (>= 3).
    k : int
        Inputs (>= 2).
    designs : int
        Independent designs (>= 1).
    seed : int
        Seed of the parent ``SeedSequence``.

    Returns
    -------
    array (designs,)
        ``lambda_max`` of each design's (k, k) Spearman correlation matrix, in [1, k].
    """
    n = validate.integer(n, "n", low=3)
    k = validate.integer(k, "k", low=2)
    designs = validate.integer(designs, "designs", low=1)
    centred = np.arange(n) - (n - 1) / 2.0          # centred ranks, half-integers
    norm2 = n * (n * n - 1) / 12.0                  # their sum of squares
    idx_type = np.int16 if n < 2**15 else np.int64
    base = np.arange(n, dtype=idx_type)
    n_blocks = -(-designs // EIGEN_BLOCK)
    out = []
    for b, child in enumerate(np.random.SeedSequence(seed).spawn(n_blocks)):
        m = min(EIGEN_BLOCK, designs - b * EIGEN_BLOCK)
        perm = np.random.default_rng(child).permuted(np.broadcast_to(base, (m, k - 1, n)), axis=-1)
        cols = np.concatenate([np.broadcast_to(centred, (m, 1, n)), centred[perm]], axis=1)
        r = (cols @ np.swapaxes(cols, -1, -2)) / norm2            # (m, k, k), exact numerator
        out.append(np.linalg.eigvalsh(r)[:, -1])
    return np.concatenate(out)
