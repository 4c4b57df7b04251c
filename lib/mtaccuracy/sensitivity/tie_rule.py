"""The compendium's one tie rule: when two values count as equal, and rankings built on it.

:func:`ties` says when two values are equal (within a relative and an absolute tolerance); every
ranking in the compendium is built on it.  :func:`merge_ties` applies it to estimated indices
at their floating-point resolution (:data:`TIE_REL`, :data:`TIE_ABS`), so that errors entering
the model identically are ordered by catalogue position on every machine (the 90 % rule's
bootstrap and its margin in :mod:`.screening` merge first); :func:`rank_with_ties` applies it
with a tolerance the caller states (optimiser minima, competing models) and breaks ties by a
canonical key.  Moved from :mod:`.screening` (which still imports every name), unchanged.
"""

from __future__ import annotations

__all__ = ["TIE_REL", "TIE_ABS", "ties", "merge_ties", "rank_with_ties"]

import functools
import numbers

import numpy as np

from .sobol import FLOAT_NOISE

#: Values within ``max(TIE_ABS, TIE_REL * max(|a|, |b|))`` of each other are ties for a
#: ranking of estimated indices (:func:`merge_ties`): far above their floating-point resolution
#: (:data:`~mtaccuracy.sensitivity.FLOAT_NOISE`, 1e-9 of an index of 0.01), far below any
#: difference the sampling can resolve (1e-4 and more).
TIE_REL = 1e-9
TIE_ABS = FLOAT_NOISE


def _check_tolerance(value, name: str) -> float:
    ok = isinstance(value, numbers.Real) and not isinstance(value, bool | np.bool_)
    if not ok or not (np.isfinite(value) and value >= 0):
        raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
    return float(value)


def ties(a, b, *, rtol: float = TIE_REL, atol: float = TIE_ABS) -> np.ndarray:
    """True where ``a`` and ``b`` tie: ``|a - b| <= max(atol, rtol * max(|a|, |b|))``.

    The compendium's one tie rule, and the canonical one: :func:`merge_ties` (estimated
    indices) and :func:`rank_with_ties` (misfits, model-selection errors) group values with it
    and nothing else, so they cannot disagree on whether two values tie.  The rule is symmetric
    in ``a`` and ``b`` (the relative tolerance scales with the larger magnitude).  A group of
    ties is anchored at its first value in rank order: a value joins the group when it ties with
    that value, so a chain of small steps never merges values further apart than the tolerance.

    Parameters
    ----------
    a, b : arrays (broadcastable)
        The values compared, element by element.
    rtol : float
        Relative tolerance, a share of the larger magnitude (default :data:`TIE_REL`, the
        floating-point resolution of estimated indices).
    atol : float
        Absolute tolerance, in the values' unit; it decides near zero (default
        :data:`TIE_ABS`).

    Returns
    -------
    array of bool (broadcast shape)
        True where the two values count as equal.
    """
    rtol, atol = _check_tolerance(rtol, "rtol"), _check_tolerance(atol, "atol")
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return np.abs(a - b) <= np.maximum(atol, rtol * np.maximum(np.abs(a), np.abs(b)))


def _group_starts(s: np.ndarray, rtol: float, atol: float) -> np.ndarray:
    """(..., m, q) True where an entry of ``s``, sorted along axis -2 in rank order, starts a
    group of ties: it does not tie (:func:`ties`) with the first entry of the group before."""
    start = np.ones(s.shape, dtype=bool)
    if s.shape[-2] == 0:
        return start
    lead = s[..., 0, :]
    for j in range(1, s.shape[-2]):  # sequential along the ranking, batched over other axes
        new = ~ties(s[..., j, :], lead, rtol=rtol, atol=atol)
        start[..., j, :] = new
        lead = np.where(new, s[..., j, :], lead)
    return start


def merge_ties(values, *, rtol: float = TIE_REL, atol: float = TIE_ABS) -> np.ndarray:
    """A copy of ``values`` in which every group of ties takes its largest value.

    Along axis -2 (per column, per leading index): sort descending; each group of values that
    tie (:func:`ties`) with the group's largest takes that value, so that a stable descending
    sort orders the group by position (catalogue order) instead of by rounding noise.  Errors
    that enter the model identically have equal indices in exact arithmetic; this makes equal
    mean equal within the floating-point resolution of the estimates, so the 90 % rule and the
    rankings are the same on every machine.

    Parameters
    ----------
    values : array (D,), (D, q) or (..., D, q)
        Indices, candidates along axis 0 of a 1-D array or along axis -2 (leading axes, e.g.
        bootstrap resamples, are handled independently).
    rtol, atol : float
        The tie tolerances of :func:`ties` (default: the floating-point resolution of
        estimated indices, :data:`TIE_REL` and :data:`TIE_ABS`).

    Returns
    -------
    array, the shape of ``values``
        Each value replaced by the largest value of its group of ties.
    """
    rtol, atol = _check_tolerance(rtol, "rtol"), _check_tolerance(atol, "atol")
    a = np.array(values, dtype=float)
    flat = a.ndim == 1
    if flat:
        a = a[:, None]
    order = np.argsort(-a, axis=-2, kind="stable")
    s = np.take_along_axis(a, order, axis=-2)
    leader = np.where(_group_starts(s, rtol, atol), np.arange(s.shape[-2])[:, None], 0)
    merged = np.take_along_axis(s, np.maximum.accumulate(leader, axis=-2), axis=-2)
    out = np.empty_like(a)
    np.put_along_axis(out, order, merged, axis=-2)
    return out[:, 0] if flat else out


def rank_with_ties(values, keys=None, *, rtol: float = 0.0, atol: float = 0.0,
                   key_tol=0.0) -> np.ndarray:
    """Candidate indices by ascending ``values``, ties (:func:`ties`) broken by ``keys``.

    The canonical ranking of, e.g., the local minima of an optimiser or competing models,
    independent of rounding noise.  Sorted ascending, the smallest value leads a group of every
    value that ties with it (:func:`ties` with ``rtol``, ``atol``); the group is ordered by
    ``keys``, compared lexicographically, two key entries counting as equal when they differ by
    at most ``key_tol``; then by the original order.  Then the next group.  NaN values are
    refused.

    Parameters
    ----------
    values : array (m,)
        What is ranked (e.g. misfits), smallest first.
    keys : array (m,) or (m, p), optional
        Tie-breaking keys, compared lexicographically, smallest first (default: the original
        order breaks every tie).
    rtol, atol : float
        The tolerances of :func:`ties`; both 0 (the default) make only equal values ties.
    key_tol : float or array (p,)
        Key entries that differ by at most this count as equal (per key column).

    Returns
    -------
    array of int (m,)
        Candidate indices in rank order.
    """
    v = np.asarray(values, dtype=float)
    if v.ndim != 1:
        raise ValueError(f"values must be one-dimensional, got shape {v.shape}")
    if not np.all(np.isfinite(v)):
        raise ValueError("values contain NaN or infinite entries: nothing to rank them by")
    rtol, atol = _check_tolerance(rtol, "rtol"), _check_tolerance(atol, "atol")
    m = v.size
    k = np.zeros((m, 0)) if keys is None else np.asarray(keys, dtype=float)
    k = k[:, None] if k.ndim == 1 else k
    if k.ndim != 2 or k.shape[0] != m:
        raise ValueError(f"{k.shape[0]} keys for {m} values")
    ktol = np.broadcast_to(np.asarray(key_tol, dtype=float), (k.shape[1],))

    def cmp(i, j):
        for a, b, t in zip(k[i], k[j], ktol, strict=True):
            if abs(a - b) > t:
                return -1 if a < b else 1
        return (i > j) - (i < j)

    ascending = np.argsort(v, kind="stable")
    starts = np.flatnonzero(_group_starts(v[ascending][:, None], rtol, atol)[:, 0])
    order = []
    for members in np.split(ascending, starts[1:]):  # per group of ties: order by the keys
        order += sorted((int(i) for i in members), key=functools.cmp_to_key(cmp))
    return np.asarray(order, dtype=int)
