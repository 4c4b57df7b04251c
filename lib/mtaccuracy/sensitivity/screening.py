"""Key-error screening by total Sobol indices, and the reduced model (Rong et al.).

The rule (Rong et al., Section 3): sort the total indices in descending order and keep the
smallest top set whose share of the sum of all total indices *exceeds* the threshold (90 % in
the paper).  The errors kept are the key errors; the reduced model sets every other error to
zero on the same samples.  The simplification rate is the share of errors removed,
``(D - k) / D``.

For a model additive in the errors (the error models here are, to first order, also when the pose
is a further random input) with zero-mean errors, the reduced model's residual is the sum of the
dropped terms, so its mean square is the dropped share of the variance:
``E[residual^2] / Var(full) = sum_{dropped} ST_i / sum ST_i``.  Keeping a share ``s`` of the total
indices therefore leaves an RMS residual of ``sqrt(1 - s)`` of the full model's RMS
(:func:`expected_rms_ratio`); the threshold sweep shows it.

Written by hand because the rule is the paper's own (a few lines); the indices come from
:mod:`.sobol` (this module imports it, never the reverse).

Ties: the compendium's one tie rule lives in :mod:`.tie_rule` (:func:`~.tie_rule.ties`,
:func:`~.tie_rule.merge_ties`, :func:`~.tie_rule.rank_with_ties`).  The 90 % rule's bootstrap,
:func:`key_set_bootstrap`, and its margin, :func:`cumulative_share_margin`, merge estimated
indices at their floating-point resolution first, so that errors entering the model identically
are ordered by catalogue position on every machine; :func:`key_errors` itself breaks exact ties
by catalogue order (a stable sort) and takes the values as given.
"""

from __future__ import annotations

__all__ = ["KeySet", "KeySets", "KeySetFrequencies", "key_errors", "key_errors_by_output",
           "union_key_set",
           "simplification_rate", "pooled_indices", "zero_non_key", "reduced_model",
           "residual_summary", "expected_rms_ratio", "threshold_sweep", "key_set_bootstrap",
           "cumulative_share_margin"]

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from mtaccuracy import validate

from .sobol import SobolIndices
from .tie_rule import TIE_ABS, TIE_REL, merge_ties, rank_with_ties, ties  # noqa: F401  (as before)

#: A share counts as exceeding the threshold only if it is larger by more than this (so that a
#: share equal to the threshold up to rounding, e.g. 0.6 + 0.3 against 0.9, does not count).
EXCEED_TOL = 1e-12


@dataclass(frozen=True)
class KeySet:
    """The key errors chosen by :func:`key_errors`.

    ``names`` and ``index`` list the key errors in descending order of the index; ``share`` is
    their share of the sum of all indices; ``n_total`` the number of candidate errors.

    Attributes
    ----------
    names : tuple of str
        The key errors, in descending order of the index.
    index : tuple of int
        Their positions among the candidates.
    share : float
        Their share of the sum of all indices.
    threshold : float
        The rule's share.
    n_total : int
        The number of candidate errors.
    values : tuple of float
        Their indices, as the rule sorted them (empty when not given).
    cumulative : tuple of float
        The share of the sum of all indices after each key error in turn, the last
        ``share`` (empty when not given).
    """

    names: tuple[str, ...]
    index: tuple[int, ...]
    share: float
    threshold: float
    n_total: int
    values: tuple[float, ...] = ()
    cumulative: tuple[float, ...] = ()

    def to_df(self) -> pd.DataFrame:
        """The key errors as a table, in rank order.

        Returns
        -------
        pandas.DataFrame
            Columns ``rank`` (1 = largest index), ``input`` (the name), ``position`` (among
            the candidates), ``value`` (the index) and ``cumulative_share``.
        """
        n = len(self.index)
        return pd.DataFrame({"rank": np.arange(1, n + 1), "input": list(self.names),
                             "position": list(self.index),
                             "value": list(self.values) or [np.nan] * n,
                             "cumulative_share": list(self.cumulative) or [np.nan] * n})

    @property
    def n_key(self) -> int:
        """int: the number of key errors."""
        return len(self.index)

    @property
    def simplification_rate(self) -> float:
        """Share of the errors removed, ``(n_total - n_key) / n_total``."""
        return simplification_rate(self.n_key, self.n_total)


def _check_threshold(threshold) -> float:
    t = float(threshold)
    if not 0.0 < t < 1.0:
        raise ValueError(f"threshold must be a share strictly between 0 and 1 (0.9 for 90 %), "
                         f"got {threshold!r}")
    return t


def _check_indices(st, ndim: int, what: str = "total indices") -> np.ndarray:
    a = np.asarray(st, dtype=float)
    if a.ndim != ndim or a.shape[0] == 0:
        shape = "(D,)" if ndim == 1 else "(D, q)"
        raise ValueError(f"{what} must be a non-empty array of shape {shape}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{what} contain NaN or infinite values")
    if np.any(a < 0):
        raise ValueError(f"{what} must be >= 0 (a total index is a share of variance); got "
                         f"minimum {a.min():.3g}; clip small negative estimates first")
    return a


def _names(names, d: int) -> list[str]:
    if names is None:
        return [str(i) for i in range(d)]
    names = [str(n) for n in names]
    if len(names) != d:
        raise ValueError(f"{len(names)} names for {d} indices")
    if len(set(names)) != d:
        raise ValueError("error names must be unique")
    return names


def key_errors(st, *, names: Sequence[str] | None = None, threshold: float = 0.9,
               tie_tol: float | None = None) -> KeySet:
    """The smallest top set of errors whose share of ``sum(st)`` exceeds ``threshold``.

    Rong et al.'s rule (Section 3).  Ties are broken by the original order (a stable sort), so
    the result is deterministic; indices equal only up to rounding should be merged first
    (:func:`merge_ties`).  Raises ValueError for indices that sum to zero, a threshold outside
    (0, 1) or names that do not match.

    Parameters
    ----------
    st : array (D,)
        Total indices (>= 0), in catalogue order.
    names : sequence of str (D,), optional
        Error names, unique (default ``"0"``, ``"1"``, ...).
    threshold : float
        The share of ``sum(st)`` the key set must exceed, strictly, in (0, 1) (0.9: Rong et
        al.'s 90 % rule).
    tie_tol : float, optional
        Not in the paper: also keep every further error whose index is within this relative
        distance, in [0, 1), of the last one kept, so that errors that enter the model
        identically are kept or dropped together (``share`` is then the enlarged set's).

    Returns
    -------
    KeySet
        The key errors in descending order of the index, with their share.
    """
    a = _check_indices(st, 1)
    t = _check_threshold(threshold)
    names = _names(names, a.size)
    total = a.sum()
    if total <= 0:
        raise ValueError("total indices sum to zero: the output does not depend on any error")
    order = np.argsort(-a, kind="stable")
    share = np.cumsum(a[order]) / total
    k = int(np.argmax(share > t + EXCEED_TOL)) + 1 if np.any(share > t + EXCEED_TOL) else a.size
    if tie_tol is not None:
        if not 0 <= tie_tol < 1:  # a half-open share: validate.probability allows 1
            raise ValueError(f"tie_tol must be in [0, 1), got {tie_tol!r}")
        last = a[order[k - 1]]
        while k < a.size and a[order[k]] > 0 and a[order[k]] >= (1 - tie_tol) * last:
            k += 1
    keep = order[:k]
    return KeySet(tuple(names[i] for i in keep), tuple(int(i) for i in keep),
                  float(share[k - 1]), t, a.size, tuple(float(v) for v in a[keep]),
                  tuple(float(v) for v in share[:k]))


class KeySets(dict):
    """The key sets of every output, ``{output: KeySet}``, with the candidates' names.

    What :func:`key_errors_by_output` returns: the dict it has always returned (its items,
    keys and values as before), that also knows every candidate's name (:meth:`union`) and
    gives itself as one table (:meth:`to_df`).

    Parameters
    ----------
    sets : mapping of str to KeySet
        One key set per output, in output order.
    names : sequence of str (D,)
        Every candidate's name, in catalogue order.
    """

    def __init__(self, sets, names: Sequence[str]):
        super().__init__(sets)
        self.names = tuple(names)

    def union(self) -> tuple[str, ...]:
        """The errors that are key for at least one output, in catalogue order.

        Returns
        -------
        tuple of str
            :func:`union_key_set` of these sets.
        """
        return union_key_set(self, self.names)

    def to_df(self) -> pd.DataFrame:
        """Every output's key errors as one long table, outputs outermost.

        Returns
        -------
        pandas.DataFrame
            Column ``output``, then those of :meth:`KeySet.to_df`.
        """
        parts = [ks.to_df().assign(output=o) for o, ks in self.items()]
        df = pd.concat(parts, ignore_index=True) if parts else pd.DataFrame(
            columns=["rank", "input", "position", "value", "cumulative_share", "output"])
        return df[["output", *df.columns[:-1]]]


def key_errors_by_output(st, *, names: Sequence[str] | None = None,
                         outputs: Sequence[str] | None = None,
                         threshold: float = 0.9, tie_tol: float | None = None
                         ) -> KeySets:
    """:func:`key_errors` for every output column of ``st`` (D, q).

    Parameters
    ----------
    st : array (D, q)
        Total indices (>= 0), one column per output.
    names : sequence of str (D,), optional
        Error names, unique (default ``"0"``, ``"1"``, ...).
    outputs : sequence of str (q,), optional
        Output names, the keys of the result (default ``y0``, ``y1``, ...).
    threshold, tie_tol : float
        The rule's share and the optional relative tie tolerance, as in :func:`key_errors`.

    Returns
    -------
    KeySets
        One key set per output, in the order of ``outputs`` (a dict; ``.to_df()``,
        ``.union()``).
    """
    a = _check_indices(st, 2)
    outputs = list(outputs) if outputs is not None else [f"y{k}" for k in range(a.shape[1])]
    if len(outputs) != a.shape[1]:
        raise ValueError(f"{len(outputs)} output names for {a.shape[1]} columns")
    return KeySets({o: key_errors(a[:, k], names=names, threshold=threshold, tie_tol=tie_tol)
                    for k, o in enumerate(outputs)}, _names(names, a.shape[0]))


def union_key_set(sets, names: Sequence[str]) -> tuple[str, ...]:
    """Errors that are key for at least one output, in the order of ``names``.

    Parameters
    ----------
    sets : dict of str to KeySet, or sequence of KeySet
        Key sets per output (:func:`key_errors_by_output`).
    names : sequence of str (D,)
        Every error name, in catalogue order: the order of the result.

    Returns
    -------
    tuple of str
        The union, in catalogue order.
    """
    sets = list(sets.values()) if isinstance(sets, dict) else list(sets)
    chosen = {n for s in sets for n in s.names}
    unknown = chosen - set(names)
    if unknown:
        raise ValueError(f"key errors {sorted(unknown)} are not among the names given")
    return tuple(n for n in names if n in chosen)


def simplification_rate(n_key: int, n_total: int) -> float:
    """Share of errors removed by the reduced model, ``(n_total - n_key) / n_total``.

    Parameters
    ----------
    n_key : int
        Errors kept (key errors), in [0, n_total].
    n_total : int
        Errors in the full model, >= 1.

    Returns
    -------
    float
        In [0, 1]: 0 when every error is kept.
    """
    n_total = validate.integer(n_total, "n_total", low=1)
    n_key = validate.integer(n_key, "n_key", low=0, high=n_total)
    return (n_total - n_key) / n_total


def pooled_indices(indices, variances) -> np.ndarray:
    """Variance-weighted mean of indices over a trailing axis (outputs or poses).

    ``indices`` (..., D, m) and ``variances`` (..., m) of the m outputs (or poses): returns
    (..., D) ``sum_m V_m S_im / sum_m V_m``, the share of the summed variance that each error
    explains (for outputs: the indices of the squared-norm-like total; for poses: of the
    workspace-mean variance).

    Parameters
    ----------
    indices : array (..., D, m)
        Indices of D errors at m outputs or poses.
    variances : array (..., m)
        The output variance at each of the m (>= 0, positive sum): the weights.

    Returns
    -------
    array (..., D)
        The pooled indices.
    """
    s = np.asarray(indices, dtype=float)
    v = np.asarray(variances, dtype=float)
    if s.ndim < 2 or v.shape != s.shape[:-2] + s.shape[-1:]:
        raise ValueError(f"variances {v.shape} must match indices {s.shape} without the D axis")
    if np.any(v < 0) or not np.all(v.sum(-1) > 0):
        raise ValueError("variances must be >= 0 with a positive sum")
    return (s * v[..., None, :]).sum(-1) / v.sum(-1)[..., None]


def _keep_index(keep, d: int, names: Sequence[str] | None) -> np.ndarray:
    if isinstance(keep, KeySet):
        keep = keep.index
    keep = list(keep)
    if keep and all(isinstance(k, str) for k in keep):
        if names is None:
            raise ValueError("key errors given by name need the list of names")
        names = list(names)
        bad = [k for k in keep if k not in names]
        if bad:
            raise ValueError(f"unknown error name(s) {bad}; allowed: {', '.join(names)}")
        keep = [names.index(k) for k in keep]
    idx = np.asarray(keep, dtype=int)
    if idx.size and (idx.min() < 0 or idx.max() >= d):
        raise ValueError(f"key error indices must be in [0, {d}), got {sorted(set(keep))}")
    return idx


def zero_non_key(x, keep, names: Sequence[str] | None = None) -> np.ndarray:
    """A copy of the samples ``x`` (n, D) with every column not in ``keep`` set to zero.

    Parameters
    ----------
    x : array (n, D)
        Samples of the errors (mm, rad); not modified.
    keep : KeySet, sequence of int or of str
        The columns kept: a key set, column indices, or error names.
    names : sequence of str (D,), optional
        The column names; needed when ``keep`` names errors.

    Returns
    -------
    array (n, D)
        ``x`` with the other columns zero.
    """
    x = np.asarray(x, dtype=float)
    if x.ndim != 2:
        raise ValueError(f"samples must have shape (n, D), got {x.shape}")
    idx = _keep_index(keep, x.shape[1], names)
    out = np.zeros_like(x)
    out[:, idx] = x[:, idx]
    return out


def reduced_model(model: Callable[[np.ndarray], np.ndarray], keep,
                  names: Sequence[str] | None = None) -> Callable[[np.ndarray], np.ndarray]:
    """The model with every non-key error set to zero: ``x -> model(zero_non_key(x, keep))``.

    Parameters
    ----------
    model : callable
        The full model, ``(n, D) -> (n, q)``.
    keep : KeySet, sequence of int or of str
        The errors kept: a key set, column indices, or error names.
    names : sequence of str (D,), optional
        The column names; needed when ``keep`` names errors.

    Returns
    -------
    callable
        The reduced model, ``(n, D) -> (n, q)``.
    """
    def reduced(x):
        return model(zero_non_key(x, keep, names))
    return reduced


def residual_summary(full, reduced, outputs: Sequence[str] | None = None) -> pd.DataFrame:
    """Per output: the ranges of full, reduced and residual predictions, and the residual's size.

    The residual is ``full - reduced``; its RMS and its RMS and max-abs ratios to the full
    model say how much the reduced model misses.

    Parameters
    ----------
    full, reduced : arrays (n, q) or (n,)
        Predictions of the full and the reduced model on the same n >= 2 samples.
    outputs : sequence of str (q,), optional
        Output names (default ``y0``, ``y1``, ...).

    Returns
    -------
    DataFrame (q, 11)
        One row per output: output, min and max of full, reduced and residual, residual_rms,
        rms_ratio and maxabs_ratio (NaN where the full model is identically zero).
    """
    f = np.asarray(full, dtype=float)
    r = np.asarray(reduced, dtype=float)
    f = f[:, None] if f.ndim == 1 else f
    r = r[:, None] if r.ndim == 1 else r
    if f.shape != r.shape or f.ndim != 2 or f.shape[0] < 2:
        raise ValueError(f"full and reduced predictions must be (n, q) of one shape with n >= 2, "
                         f"got {np.shape(full)} and {np.shape(reduced)}")
    outputs = list(outputs) if outputs is not None else [f"y{k}" for k in range(f.shape[1])]
    if len(outputs) != f.shape[1]:
        raise ValueError(f"{len(outputs)} output names for {f.shape[1]} columns")
    res = f - r
    rms_full = np.sqrt(np.mean(f**2, axis=0))
    rms_res = np.sqrt(np.mean(res**2, axis=0))
    return pd.DataFrame({
        "output": outputs,
        "full_min": f.min(0), "full_max": f.max(0),
        "reduced_min": r.min(0), "reduced_max": r.max(0),
        "residual_min": res.min(0), "residual_max": res.max(0),
        "residual_rms": rms_res,
        "rms_ratio": rms_res / np.where(rms_full > 0, rms_full, np.nan),
        "maxabs_ratio": np.abs(res).max(0) / np.where(np.abs(f).max(0) > 0, np.abs(f).max(0),
                                                      np.nan),
    })


def expected_rms_ratio(share) -> np.ndarray:
    """``sqrt(1 - share)``: the reduced model's residual RMS over the full model's RMS.

    For a model additive in zero-mean errors, when the kept errors carry ``share`` of the sum
    of the total indices (see the module docstring).

    Parameters
    ----------
    share : float or array
        Share of the summed total indices the kept errors carry, in [0, 1].

    Returns
    -------
    array, the shape of ``share``
        The expected ratio of RMS values.
    """
    s = np.asarray(share, dtype=float)
    if np.any((s < 0) | (s > 1 + 1e-9)):
        raise ValueError("share must be in [0, 1]")
    return np.sqrt(np.clip(1.0 - s, 0.0, None))


def threshold_sweep(st, x, model: Callable[[np.ndarray], np.ndarray], *, thresholds,
                    names: Sequence[str], outputs: Sequence[str] | None = None,
                    full=None) -> pd.DataFrame:
    """Key sets and reduced-model residuals as the threshold of the 90 % rule varies.

    For each threshold: the key set of every output (:func:`key_errors_by_output`) and their
    union; the reduced model (non-union errors set to zero) on the samples ``x``; per output
    the residual's ``max |.|`` and RMS, also relative to the full model.  One row per
    (threshold, output).

    Parameters
    ----------
    st : array (D, q)
        Total indices (>= 0), one column per output.
    x : array (n, D)
        Samples of the errors (mm, rad) on which the full and reduced models are compared.
    model : callable
        ``(n, D) -> (n, q)``, the full model.
    thresholds : array (t,)
        The rule's shares, each in (0, 1).
    names : sequence of str (D,)
        Error names, unique.
    outputs : sequence of str (q,), optional
        Output names (default ``y0``, ``y1``, ...).
    full : array (n, q), optional
        ``model(x)`` if already computed (saves one model call).

    Returns
    -------
    DataFrame (t q, 11)
        threshold, output, the key errors of that output and of the union (counts, shares,
        names), the simplification rate and the residual's max-abs and RMS, also as ratios.
    """
    a = _check_indices(st, 2)
    names = _names(names, a.shape[0])
    outputs = list(outputs) if outputs is not None else [f"y{k}" for k in range(a.shape[1])]
    ts = [_check_threshold(t) for t in np.atleast_1d(thresholds)]
    x = np.asarray(x, dtype=float)
    if x.ndim != 2 or x.shape[1] != len(names):
        raise ValueError(f"samples must have shape (n, {len(names)}), got {x.shape}")
    f = np.asarray(model(x), dtype=float) if full is None else np.asarray(full, dtype=float)
    f = f[:, None] if f.ndim == 1 else f
    rows = []
    cache: dict[tuple[str, ...], pd.DataFrame] = {}
    for t in ts:
        sets = key_errors_by_output(a, names=names, outputs=outputs, threshold=t)
        union = union_key_set(sets, names)
        if union not in cache:
            cache[union] = residual_summary(f, np.asarray(model(zero_non_key(x, union, names)))
                                            .reshape(f.shape), outputs)
        summ = cache[union]
        for k, o in enumerate(outputs):
            s = summ.iloc[k]
            rows.append(dict(
                threshold=t, output=o, n_key_output=sets[o].n_key, share_output=sets[o].share,
                n_key=len(union), simplification_rate=simplification_rate(len(union), len(names)),
                residual_maxabs=max(abs(s.residual_min), abs(s.residual_max)),
                residual_rms=s.residual_rms, rms_ratio=s.rms_ratio, maxabs_ratio=s.maxabs_ratio,
                key_errors=" ".join(union)))
    return pd.DataFrame(rows)


def cumulative_share_margin(values, threshold: float) -> np.ndarray:
    """How far the 90 %-type rule is from changing its decision, per output.

    Per column of ``values`` (D, q) (e.g. total indices), clipped at 0 with ties merged
    (:func:`merge_ties`): sort descending and take the cumulative
    shares; the rule stops at the first share above ``threshold``; the margin is the distance
    of the threshold from the nearer of that share and the one before.  A margin far above the
    floating-point resolution of the shares means rounding cannot change the key set.

    Parameters
    ----------
    values : array (D, q) or (D,)
        Total indices (negative estimates count as 0), one column per output.
    threshold : float
        The rule's share, in (0, 1) (0.9 in Rong et al.).

    Returns
    -------
    array (q,)
        The margin per output, a share of the summed indices.
    """
    threshold = _check_threshold(threshold)
    a = merge_ties(np.clip(np.asarray(values, dtype=float), 0, None))
    a = a[:, None] if a.ndim == 1 else a
    s = -np.sort(-a, axis=0)
    share = np.cumsum(s, axis=0) / s.sum(0)
    k = np.argmax(share > threshold, axis=0)
    cols = np.arange(a.shape[1])
    above = share[k, cols] - threshold
    below = np.where(k > 0, threshold - share[np.maximum(k - 1, 0), cols], np.inf)
    return np.minimum(above, below)


class KeySetFrequencies(tuple):
    """How often each error is key over bootstrap resamples, and the sizes of the key sets.

    What :func:`key_set_bootstrap` returns: the pair ``freq, counts`` it has always returned
    (it unpacks as that tuple); :meth:`to_df` is ``freq``.

    Parameters
    ----------
    freq : pandas.DataFrame (D, 2 + q)
        ``symbol``, then the share of resamples in which it is key, per output and in the
        union.
    counts : pandas.DataFrame (n_boot, q + 1)
        The number of key errors per output and in the union, per resample.
    """

    def __new__(cls, freq: pd.DataFrame, counts: pd.DataFrame) -> KeySetFrequencies:
        return super().__new__(cls, (freq, counts))

    @property
    def freq(self) -> pd.DataFrame:
        """pandas.DataFrame: the share of resamples in which each error is key."""
        return self[0]

    @property
    def counts(self) -> pd.DataFrame:
        """pandas.DataFrame: the number of key errors per resample."""
        return self[1]

    def to_df(self) -> pd.DataFrame:
        """The frequencies, one row per error.

        Returns
        -------
        pandas.DataFrame
            A copy of :attr:`freq`.
        """
        return self.freq.copy()


def key_set_bootstrap(st_samples, *, names: Sequence[str], outputs: Sequence[str] | None = None,
                      threshold: float = 0.9) -> KeySetFrequencies:
    """How stable is the key set: :func:`key_errors` applied to each bootstrap re-estimate.

    ``st_samples`` (n_boot, >= D, q) are total indices re-estimated on resamples of the base
    rows, e.g. the second array of :func:`mtaccuracy.sensitivity.sobol_bootstrap_samples` or
    the ``st_boot`` of a bootstrapped ``sobol_indices(..., n_boot=)`` (a
    :class:`~mtaccuracy.sensitivity.SobolIndices` may be given itself), so that the key-set
    frequencies come from the very resamples of the confidence intervals.
    Only the first ``len(names)`` inputs are candidates (further inputs, e.g. the pose, are left
    out of the rule).  Each resample is clipped at 0 and its ties merged
    (:func:`merge_ties`: indices within the floating-point resolution are equal, and equal
    indices go in catalogue order), then :func:`key_errors_by_output` and
    :func:`union_key_set` decide.

    Parameters
    ----------
    st_samples : array (n_boot, >= D, q) or SobolIndices
        Re-estimated total indices, one (D, q) table per resample (of a ``SobolIndices``: its
        ``st_boot``).
    names : sequence of str (D,)
        The candidate inputs (the first ``len(names)`` of axis 1), unique.
    outputs : sequence of str (q,), optional
        Output names (default ``y0``, ``y1``, ...).
    threshold : float
        The rule's share, in (0, 1) (0.9: Rong et al.'s 90 % rule).

    Returns
    -------
    KeySetFrequencies
        Unpacks as ``freq`` (DataFrame (D, 2 + q): symbol, the share of resamples in which
        it is key per output, and in the union) and ``counts`` (DataFrame (n_boot, q + 1):
        key errors per output and in the union, per resample).
    """
    if isinstance(st_samples, SobolIndices):
        if st_samples.st_boot is None:
            raise ValueError("these Sobol indices carry no bootstrap re-estimates: compute "
                             "them with sobol_indices(..., n_boot=, seed=)")
        st_samples = st_samples.st_boot
    st = np.asarray(st_samples, dtype=float)
    names = list(names)
    if st.ndim != 3 or st.shape[0] < 1:
        raise ValueError(f"st_samples must be an (n_boot, D, q) array with n_boot >= 1, "
                         f"got shape {st.shape}")
    if st.shape[1] < len(names):
        raise ValueError(f"{len(names)} names but only {st.shape[1]} inputs in st_samples")
    names = _names(names, len(names))
    outputs = list(outputs) if outputs is not None else [f"y{k}" for k in range(st.shape[2])]
    st = merge_ties(np.clip(st[:, :len(names)], 0, None))
    hits = {o: np.zeros(len(names)) for o in [*outputs, "union"]}
    counts = []
    for b in range(st.shape[0]):  # the rule per resample: a sort of D values, cheap
        sets = key_errors_by_output(st[b], names=names, outputs=outputs, threshold=threshold)
        for o, ks in sets.items():
            hits[o][list(ks.index)] += 1
        union = union_key_set(sets, names)
        hits["union"][[names.index(u) for u in union]] += 1
        counts.append({**{o: ks.n_key for o, ks in sets.items()}, "union": len(union)})
    freq = pd.DataFrame({"symbol": names, **{o: h / st.shape[0] for o, h in hits.items()}})
    return KeySetFrequencies(freq, pd.DataFrame(counts))

