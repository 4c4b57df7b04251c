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
           "sobol_estimate", "bootstrap_counts", "sobol_bootstrap_samples", "ci_half_width",
           "sobol_bootstrap", "sobol_indices", "linear_indices", "FLOAT_NOISE", "TIE_REL",
           "TIE_ABS", "merge_ties", "cumulative_share_margin", "key_set_frequencies"]

from collections.abc import Callable

import numpy as np
from scipy import stats
from scipy.special import ndtri
from scipy.stats import qmc

from .linear import linear_indices  # it lives in .linear; kept here for old callers


def base_samples(n: int, d: int, method: str, seed) -> tuple[np.ndarray, np.ndarray]:
    """Two independent (n, d) designs on the unit hypercube: the A and B matrices.

    method ``mc``: independent uniforms; ``lhs``: two independent Latin hypercubes
    (scipy.qmc); ``sobol``: one scrambled 2d-dimensional Sobol' sequence split in halves, as
    SALib's Saltelli sampler does (n should be a power of 2).

    Parameters
    ----------
    n : int
        Base rows N.
    d : int
        Inputs.
    method : {"mc", "lhs", "sobol"}
        The design.
    seed : int or SeedSequence
        Seed of ``numpy.random.default_rng``.

    Returns
    -------
    a, b : arrays (n, d)
        In [0, 1).
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
    """Map unit-cube samples to independent uniforms on ``bounds`` (2, d).

    Parameters
    ----------
    u : array (n, d)
        Unit-cube samples.
    bounds : array (2, d)
        Lower and upper bounds (mm, rad).

    Returns
    -------
    array (n, d)
    """
    bounds = np.asarray(bounds, dtype=float)
    return bounds[0] + u * (bounds[1] - bounds[0])


def from_unit_normal(u: np.ndarray, sd: np.ndarray, mean: np.ndarray | float = 0.0) -> np.ndarray:
    """Map unit-cube samples to independent normals (inverse CDF), ``sd`` per column.

    ``scipy.special.ndtri`` is the function ``scipy.stats.norm.ppf`` evaluates, called
    without the distribution machinery (five times faster; the same numbers).

    Parameters
    ----------
    u : array (n, d)
        Unit-cube samples (in (0, 1)).
    sd : array (d,)
        Standard deviations.
    mean : array (d,) or float
        Means.

    Returns
    -------
    array (n, d)
    """
    return np.asarray(mean) + np.asarray(sd) * ndtri(u)


def _model_runs(model, n, d, chunk, progress):
    """``run(x)``: ``model`` on the (m, D) array x as an (m, q) float array, ``chunk`` rows
    per call, counting the runs against the N(D+2) of a Sobol design for ``progress``."""
    total = n * (d + 2)
    done = 0

    def run(x):
        nonlocal done
        out = []
        for s in range(0, x.shape[0], chunk):
            y = np.asarray(model(x[s:s + chunk]), dtype=float)
            out.append(y[:, None] if y.ndim == 1 else y)
            done += out[-1].shape[0]
            if progress:
                progress(done, total)
        return out[0] if len(out) == 1 else np.concatenate(out)
    return run


def _ab_blocks(a: np.ndarray, b: np.ndarray, chunk: int):
    """Yields ``(i0, i1, x)``: x the rows of AB_i0 ... AB_i(1-1) stacked, ((i1 - i0) N, D).

    As many AB blocks as fit in ``chunk`` rows go together (one block when N > chunk).  The
    blocks live in one buffer filled with A once: each step puts back the A columns the
    previous step replaced and takes the new ones from B, so a step writes 2 N values per
    block instead of copying A (N D values).  The model must not keep or modify its input."""
    n, d = a.shape
    rows = max(1, min(d, chunk // n))
    buf = np.repeat(a[None], rows, axis=0)                      # (rows, N, D)
    prev = []
    for i0 in range(0, d, rows):
        i1 = min(i0 + rows, d)
        for k, i in enumerate(prev):
            buf[k, :, i] = a[:, i]
        prev = list(range(i0, i1))
        for k, i in enumerate(prev):
            buf[k, :, i] = b[:, i]
        yield i0, i1, buf[:i1 - i0].reshape(-1, d)


def _check_ab(a, b):
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    if a.shape != b.shape or a.ndim != 2:
        raise ValueError(f"A and B must be (N, D) arrays of one shape, got {a.shape}, {b.shape}")
    return a, b


def sobol_evaluate(model: Callable[[np.ndarray], np.ndarray], a: np.ndarray, b: np.ndarray,
                   chunk: int = 200_000, progress: Callable[[int, int], None] | None = None
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Run ``model`` on A, B and every AB_i; returns ``ya`` (N, q), ``yb`` (N, q), ``yab``
    (D, N, q).

    ``model`` maps an (m, D) array to (m, q) (or (m,)) outputs, and must not modify its
    input.  Runs are batched ``chunk`` rows at a time: N(D+2) model runs in about
    N(D+2)/chunk calls.  ``progress(done, total)`` is called after each call with the number
    of runs done.  ``yab`` holds D N q floats: when only the indices are wanted,
    :func:`sobol_indices` gives them without it.

    Parameters
    ----------
    model : callable
        ``(m, D) -> (m, q)`` or ``(m,)``.
    a, b : arrays (N, D)
        The two designs.
    chunk : int
        Model runs per call.
    progress : callable, optional
        ``progress(done, total)`` after each call.

    Returns
    -------
    ya, yb : arrays (N, q)
    yab : array (D, N, q)
    """
    a, b = _check_ab(a, b)
    n, d = a.shape
    run = _model_runs(model, n, d, chunk, progress)
    ya, yb = run(a), run(b)
    yab = np.empty((d, n, ya.shape[1]))
    for i0, i1, x in _ab_blocks(a, b, chunk):
        yab[i0:i1] = run(x).reshape(i1 - i0, n, -1)
    return ya, yb, yab


#: floats per temporary in :func:`sobol_estimate` (inputs are taken a few at a time)
_ESTIMATE_BLOCK = 2**21


def sobol_estimate(ya: np.ndarray, yb: np.ndarray, yab: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
    """First-order (Saltelli 2010) and total (Jansen) indices, each (D, q), on outputs
    standardised over all runs as SALib does.  Works on leading bootstrap axes too: ``ya``
    (..., N, q), ``yab`` (..., D, N, q).

    The inputs are taken a few at a time, so the temporaries stay near ``_ESTIMATE_BLOCK``
    floats whatever D and N (the estimate of every input is the same expression).

    Parameters
    ----------
    ya, yb : arrays (..., N, q)
        Outputs on A and B.
    yab : array (..., D, N, q)
        Outputs on every AB_i.

    Returns
    -------
    s1, st : arrays (..., D, q)
    """
    ya, yb, yab = (np.asarray(v, dtype=float) for v in (ya, yb, yab))
    n, d = ya.shape[-2], yab.shape[-3]
    mu = (ya.sum(-2) + yb.sum(-2) + yab.sum((-3, -2))) / (n * (d + 2))
    var = np.var(np.concatenate([ya, yb], axis=-2), axis=-2)[..., None, :]
    w = (yb - mu[..., None, :])[..., None, :, :]
    s1 = np.empty(yab.shape[:-2] + ya.shape[-1:])
    st = np.empty_like(s1)
    step = max(1, _ESTIMATE_BLOCK // max(1, yab[..., :1, :, :].size))
    for i0 in range(0, d, step):
        diff = yab[..., i0:i0 + step, :, :] - ya[..., None, :, :]
        s1[..., i0:i0 + step, :] = np.mean(w * diff, axis=-2)
        np.square(diff, out=diff)
        st[..., i0:i0 + step, :] = 0.5 * np.mean(diff, axis=-2)
    return s1 / var, st / var


def bootstrap_counts(n: int, n_boot: int, seed, chunk: int = 20, block: int = 2**21):
    """The ``n_boot`` bootstrap resamples of ``n`` rows as counts: yields (k, n) float arrays
    ``w`` with ``w[b, i]`` = how often row i is drawn in resample b, about ``block / n``
    resamples at a time (one matrix product each; many small products are slow when a
    multi-threaded BLAS shares a busy machine).

    The draws are ``rng.integers(0, n, size=(k, n))`` for successive chunks of ``k <= chunk``
    resamples of one ``numpy.random.default_rng(seed)``: the resamples that
    ``sobol_bootstrap`` and ``key_set_bootstrap`` have always used.

    Parameters
    ----------
    n : int
        Rows.
    n_boot : int
        Resamples.
    seed : int
        Seed of ``numpy.random.default_rng``.
    chunk : int
        Resamples per draw.
    block : int
        Counts held at a time.

    Yields
    ------
    array (k, n)
        Counts of k resamples.
    """
    if int(n_boot) != n_boot or n_boot < 1:
        raise ValueError(f"n_boot must be a positive integer, got {n_boot!r}")
    rng = np.random.default_rng(seed)
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


def sobol_bootstrap_samples(ya, yb, yab, n_boot: int, seed, chunk: int = 20, block: int = 2**21
                            ) -> tuple[np.ndarray, np.ndarray]:
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
    yab : array (D, N, q)
        As :func:`sobol_evaluate` returns them.
    n_boot : int
        Resamples.
    seed : int
        Seed of the resampling.
    chunk, block : int
        As :func:`bootstrap_counts`.

    Returns
    -------
    s1, st : arrays (n_boot, D, q)
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
    for w in bootstrap_counts(n, n_boot, seed, chunk, block):
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
    """Half-width of the ``conf`` interval from bootstrap ``samples`` (leading axis): the
    normal quantile times their standard deviation (ddof 1), as SALib reports it.

    Parameters
    ----------
    samples : array (n_boot, ...)
        Bootstrap estimates.
    conf : float
        Confidence level.

    Returns
    -------
    array (...)
    """
    z = stats.norm.ppf(0.5 + conf / 2)
    return z * np.asarray(samples).std(axis=0, ddof=1)


def sobol_bootstrap(ya, yb, yab, n_boot: int, seed, conf: float = 0.95, chunk: int = 20):
    """Bootstrap half-widths of the ``conf`` confidence intervals of S1 and ST (D, q) each,
    from ``n_boot`` resamples of the N base rows (as SALib: normal quantile times the
    bootstrap standard deviation); see :func:`sobol_bootstrap_samples`.

    Parameters
    ----------
    ya, yb : arrays (N, q)
    yab : array (D, N, q)
        As :func:`sobol_evaluate` returns them.
    n_boot : int
        Resamples.
    seed : int
        Seed of the resampling.
    conf : float
        Confidence level.
    chunk : int
        As :func:`bootstrap_counts`.

    Returns
    -------
    s1_half, st_half : arrays (D, q)
    """
    s1s, sts = sobol_bootstrap_samples(ya, yb, yab, n_boot, seed, chunk)
    return ci_half_width(s1s, conf), ci_half_width(sts, conf)


def sobol_indices(model: Callable[[np.ndarray], np.ndarray], a: np.ndarray, b: np.ndarray,
                  chunk: int = 200_000, progress: Callable[[int, int], None] | None = None
                  ) -> tuple[np.ndarray, np.ndarray]:
    """First-order and total Sobol indices of ``model``, streaming over the AB runs.

    The estimators are Saltelli et al. 2010 (first order) and Jansen 1999 (total), on outputs
    standardised over all N (D + 2) runs, as SALib's ``sobol.analyze``; the numbers equal
    :func:`sobol_estimate` on :func:`sobol_evaluate` within rounding (a test checks 1e-12)
    without ever holding ``yab`` (D N q floats: 200 MB for 41 inputs, N = 1e5, six outputs).

    Parameters
    ----------
    model : callable
        ``(m, D)`` inputs to ``(m, q)`` (or ``(m,)``) outputs; must not modify its input (the
        AB blocks share one buffer).
    a, b : (N, D) arrays
        The two independent designs (:func:`base_samples`, mapped to the input laws).
    chunk : int
        Model runs per call.
    progress : callable, optional
        ``progress(done, total)`` after each call, counting runs.

    Returns
    -------
    s1, st : (D, q) arrays
        First-order and total indices.

    Notes
    -----
    Each AB_i batch, once run, adds its per-input sums of ``yab_i - ya``,
    ``(yb - c)(yab_i - ya)`` and ``(yab_i - ya)^2`` and is dropped; ``c`` is the mean of ``ya``
    and ``yb``, and the overall mean ``mu`` enters at the end:
    ``mean((yb - mu) d) = mean((yb - c) d) - (mu - c) mean(d)``, without cancellation because
    the outputs are centred.  Memory: A, B, one batch of ``chunk`` runs, ``ya`` and ``yb``.
    """
    a, b = _check_ab(a, b)
    n, d = a.shape
    run = _model_runs(model, n, d, chunk, progress)
    ya, yb = run(a), run(b)
    q = ya.shape[1]
    both = np.concatenate([ya, yb])
    centre, var = both.mean(0), both.var(0)
    ybc = yb - centre
    total = both.sum(0)
    sd_, sbd, sd2 = np.empty((d, q)), np.empty((d, q)), np.empty((d, q))
    for i0, i1, x in _ab_blocks(a, b, chunk):
        y = run(x).reshape(i1 - i0, n, q)
        total += y.sum((0, 1))
        diff = y - ya                   # a new array: y may be a view of the model's input
        sd_[i0:i1] = diff.sum(1)
        sbd[i0:i1] = np.einsum("inq,nq->iq", diff, ybc)
        sd2[i0:i1] = np.einsum("inq,inq->iq", diff, diff)
    mu_c = total / (n * (d + 2)) - centre
    return (sbd - mu_c * sd_) / (n * var), 0.5 * sd2 / (n * var)


# --------------------------------------------------------------------------------------------
# Floating-point resolution of the estimates, and canonical ties.
# --------------------------------------------------------------------------------------------

#: Absolute floating-point resolution declared for Sobol indices estimated from model outputs
#: of a few hundredths of a mm computed from poses of hundreds of mm.  Such an output carries a
#: rounding error of about eps x 1000 mm = 2e-13 mm (measured across OpenBLAS kernels:
#: 2.3e-13 mm), 5e-12 of its standard deviation.  S1 is a mean over N rows of (yb - mu) times
#: the difference of two outputs, divided by the variance: each term carries 5e-12, so the
#: index carries at most 5e-12 (all terms of one sign) and typically 5e-12 / sqrt(N) = 6e-14
#: at N = 8192 (measured across kernels: 5e-14).  ST is a mean of squared differences: its
#: rounding is smaller still.  1e-11 is twice the worst case.  The sampling uncertainty (the
#: bootstrap half-widths, 1e-3 for the leading indices) is a different, far larger thing.
FLOAT_NOISE = 1e-11

#: Values within ``max(TIE_REL * |v|, TIE_ABS)`` of each other are ties for a ranking rule: far
#: above the floating-point resolution (:data:`FLOAT_NOISE`, 1e-9 of an index of 0.01), far
#: below any difference the sampling can resolve (1e-4 and more).
TIE_REL = 1e-9
TIE_ABS = FLOAT_NOISE


def merge_ties(values, rel: float = TIE_REL, abs_tol: float = TIE_ABS) -> np.ndarray:
    """A copy of ``values`` (D,) or (D, q) in which every group of near-equal values (along
    axis 0, per column) takes the group's largest value, so that a stable descending sort
    orders the group by its position (catalogue order) instead of by rounding noise.

    Groups: sort descending; a value joins the group of the value above it when the gap is at
    most ``max(rel * |larger|, abs_tol)``.  Errors that enter the model identically have equal
    indices in exact arithmetic; this makes "equal" mean equal within the stated tolerance, so
    the 90 % rule and the rankings are the same on every machine.  Leading (bootstrap) axes
    are allowed: ``values`` (..., D, q).

    Parameters
    ----------
    values : array (..., D) or (..., D, q)
        Indices.
    rel, abs_tol : float
        The tie tolerances.

    Returns
    -------
    array, the shape of ``values``
    """
    a = np.array(values, dtype=float)
    flat = a.ndim == 1
    if flat:
        a = a[:, None]
    order = np.argsort(-a, axis=-2, kind="stable")
    s = np.take_along_axis(a, order, axis=-2)
    gap = s[..., :-1, :] - s[..., 1:, :]
    tol = np.maximum(rel * np.abs(s[..., :-1, :]), abs_tol)
    new = np.concatenate([np.ones_like(gap[..., :1, :], dtype=bool), gap > tol], axis=-2)
    leader = np.where(new, np.arange(s.shape[-2])[:, None], 0)
    leader = np.maximum.accumulate(leader, axis=-2)
    merged = np.take_along_axis(s, leader, axis=-2)
    out = np.empty_like(a)
    np.put_along_axis(out, order, merged, axis=-2)
    return out[:, 0] if flat else out


def cumulative_share_margin(values, threshold: float) -> np.ndarray:
    """How far the 90 %-type rule is from changing its decision: per column of ``values``
    (D, q) (e.g. total indices), sort descending and take the cumulative shares; the rule
    stops at the first share above ``threshold``; the margin is the distance of the
    threshold from the nearer of that share and the one before.  A margin far above the
    floating-point resolution of the shares means rounding cannot change the key set.

    Parameters
    ----------
    values : array (D, q)
        Non-negative values (total indices).
    threshold : float
        The rule's share (0.9 in Rong et al.).

    Returns
    -------
    array (q,)
    """
    a = merge_ties(np.clip(np.asarray(values, dtype=float), 0, None))
    a = a[:, None] if a.ndim == 1 else a
    s = -np.sort(-a, axis=0)
    share = np.cumsum(s, axis=0) / s.sum(0)
    k = np.argmax(share > threshold, axis=0)
    cols = np.arange(a.shape[1])
    above = share[k, cols] - threshold
    below = np.where(k > 0, threshold - share[np.maximum(k - 1, 0), cols], np.inf)
    return np.minimum(above, below)


def key_set_frequencies(st_samples, names, outputs, threshold: float = 0.9):
    """The 90 % rule applied to each of many re-estimated total indices (``st_samples``
    (n_boot, >= D, q), e.g. from :func:`sobol_bootstrap_samples`; only the first
    ``len(names)`` inputs are candidates), after clipping at 0 and :func:`merge_ties`.
    Returns ``freq`` (per error: the share of resamples in which it is key, per output and
    for the union) and ``counts`` (per resample: the number of key errors per output and in
    the union), as ``key_set_bootstrap`` of :mod:`.screening` (which resamples itself).

    Parameters
    ----------
    st_samples : array (n_boot, >= D, q)
        Re-estimated total indices.
    names : sequence of str (D,)
        The candidate inputs.
    outputs : sequence of str (q,)
        Output names.
    threshold : float
        The rule's share.

    Returns
    -------
    freq : DataFrame (D, 2 + q)
        symbol, the share of resamples in which it is key per output, and in the union.
    counts : DataFrame (n_boot, q + 1)
        Key errors per output and in the union, per resample.
    """
    import pandas as pd

    from .screening import key_errors_by_output, union_key_set

    names, outputs = list(names), list(outputs)
    st = merge_ties(np.clip(np.asarray(st_samples, dtype=float)[:, :len(names)], 0, None))
    hits = {o: np.zeros(len(names)) for o in [*outputs, "union"]}
    counts = []
    for b in range(st.shape[0]):  # the rule per resample: a sort of D values, cheap
        sets = key_errors_by_output(st[b], names, outputs, threshold)
        for o, ks in sets.items():
            hits[o][list(ks.index)] += 1
        union = union_key_set(sets, names)
        hits["union"][[names.index(u) for u in union]] += 1
        counts.append({**{o: ks.n_key for o, ks in sets.items()}, "union": len(union)})
    freq = pd.DataFrame({"symbol": names, **{o: h / st.shape[0] for o, h in hits.items()}})
    return freq, pd.DataFrame(counts)
