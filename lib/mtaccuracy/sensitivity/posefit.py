"""Which pose explains a published table of indices? One search for every machine and statistic.

Papers print sensitivity indices (Sobol', Spearman) computed at a pose they do not state.  A
reproduction can only choose the pose that best explains the printed numbers, and must then
mark the rows that use it ``fitted``.  The search is the same whatever the statistic:

* a **statistic** maps a batch of poses, ``{axis: (B,) array}`` (mm, rad), to the model's
  values, ``(B, ...)``: the closed-form linear indices (Zheng et al. 2024, notebook 01) or the
  Spearman coefficients of one error design (Guo et al. 2016, notebook 03);
* the **published** values sit at some entries of those trailing axes (``entries``, one index
  array per axis); the residual of a pose is the model's value there minus the published one;
* :func:`screen_poses` evaluates the RMS misfit of many candidate poses in one batched call;
  :func:`fit_pose` refines from start poses: scipy's ``least_squares`` (trust-region
  reflective, a central-difference Jacobian evaluated as one batch) for a smooth statistic, or
  Powell's method for a piecewise-constant one (rank statistics), whose strict comparisons in
  a fixed order resolve exactly equal misfits the same way on every machine.

Canonical choices among symmetric or tied optima depend on the machine's symmetry group and
are the caller's (``papers.zheng2024.rank_poses`` for notebook 01's AC turntable); ties by
misfit within a relative tolerance are broken by :func:`~mtaccuracy.sensitivity.rank_with_ties`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np
import pandas as pd
from scipy.optimize import least_squares, minimize
from threadpoolctl import threadpool_limits

from mtaccuracy import validate

__all__ = ["pose_residuals", "screen_poses", "fit_pose", "least_squares_starts"]


def pose_residuals(statistic: Callable[[dict], np.ndarray], published, entries: Sequence, *,
                   free: Sequence[str], fixed: Mapping | None = None
                   ) -> Callable[[np.ndarray], np.ndarray]:
    """The residual function of a pose search: free-axis vectors to model minus published.

    Parameters
    ----------
    statistic : callable
        ``statistic(pose) -> (B, ...)`` for ``pose = {axis: (B,) array}`` (mm, rad).
    published : array (m,)
        The published values the statistic is compared with.
    entries : sequence of arrays (m,)
        One index array per trailing axis of the statistic: published value ``j`` sits at
        ``statistic(pose)[:, entries[0][j], entries[1][j], ...]``.
    free : sequence of str
        The axes the search moves, in the order of the vectors it passes.
    fixed : mapping, optional
        The other axes' values (mm, rad), the same for every pose; none both free and fixed.

    Returns
    -------
    callable
        ``residuals(v)``: ``v`` (B, len(free)) to (B, m), the model minus the published values.
    """
    published = np.asarray(published, dtype=float)
    entries = tuple(np.asarray(e) for e in entries)
    if any(e.shape != published.shape for e in entries):
        raise ValueError(f"every entries array must match published {published.shape}, got "
                         f"{[e.shape for e in entries]}")
    free, fixed = tuple(free), dict(fixed or {})
    if set(free) & set(fixed):
        raise ValueError(f"axes both free and fixed: {sorted(set(free) & set(fixed))}")

    def residuals(v):
        v = np.atleast_2d(np.asarray(v, dtype=float))
        pose = {a: v[:, i] for i, a in enumerate(free)}
        pose.update({a: np.full(v.shape[0], float(fixed[a])) for a in fixed})
        return statistic(pose)[(slice(None), *entries)] - published

    return residuals


def screen_poses(statistic: Callable[[dict], np.ndarray], published, entries: Sequence, *,
                 poses: Mapping) -> tuple[np.ndarray, np.ndarray]:
    """RMS misfit of many candidate poses, evaluated in one call of ``statistic``.

    Parameters
    ----------
    statistic : callable
        ``statistic(pose) -> (P, ...)`` (see :func:`pose_residuals`).
    published : array (m,)
        The published values the statistic is compared with.
    entries : sequence of arrays (m,)
        Where each published value sits in the statistic's trailing axes.
    poses : mapping
        ``{axis: (P,) array}`` (mm, rad): the candidates, every axis the statistic needs.

    Returns
    -------
    rms : array (P,)
        RMS of the residuals of each candidate.
    statistic : array (P, ...)
        The statistic at every candidate (its values at the published entries are
        ``statistic[:, entries[0], entries[1], ...]``).
    """
    published = np.asarray(published, dtype=float)
    full = statistic(dict(poses))
    values = full[(slice(None), *(np.asarray(e) for e in entries))]
    return np.sqrt(((values - published) ** 2).mean(axis=-1)), full


def least_squares_starts(residuals: Callable[[np.ndarray], np.ndarray], starts, *, lo, hi,
                         scale, ftol: float = 1e-15, xtol: float = 1e-15,
                         max_nfev: int = 500) -> list:
    """scipy's ``least_squares`` from each start, with a batched central-difference Jacobian.

    Trust-region reflective within ``lo``/``hi``; the Jacobian's steps are ``1e-6 * scale`` and
    its 2 k evaluations are one call of ``residuals``; BLAS single-threaded (small matrices:
    threads only cost time, and the result is then the same for any thread count).

    Parameters
    ----------
    residuals : callable
        ``(B, k)`` parameter vectors to ``(B, m)`` residuals, batched.
    starts : array (s, k)
        Start vectors, one fit each (clipped into the bounds).
    lo, hi : arrays (k,)
        Lower and upper bounds of the parameters (``-inf``/``inf`` for none).
    scale : array (k,)
        Typical size of each parameter (``x_scale``; the Jacobian's steps are 1e-6 of it).
    ftol, xtol : float
        Stop when the relative change of the cost or of the step falls below them.
    max_nfev : int
        Evaluations allowed per start (>= 1).

    Returns
    -------
    list of (array (k,), float, int)
        Per start: the optimum, the RMS of its residuals and the optimiser's status.
    """
    max_nfev = validate.integer(max_nfev, "max_nfev", low=1)
    scale = np.asarray(scale, dtype=float)
    n, step = len(scale), 1e-6 * scale

    def fun(v):
        return residuals(v[None])[0]

    def jac(v):
        e = np.eye(n) * step
        r = residuals(np.concatenate([v + e, v - e]))
        return ((r[:n] - r[n:]) / (2 * step[:, None])).T

    out = []
    with threadpool_limits(limits=1, user_api="blas"):
        for v0 in starts:
            r = least_squares(fun, np.clip(v0, lo, hi), jac=jac, bounds=(lo, hi),
                              x_scale=scale, ftol=ftol, xtol=xtol, gtol=None,
                              max_nfev=max_nfev, method="trf")
            out.append((r.x, float(np.sqrt(np.mean(fun(r.x) ** 2))), int(r.status)))
    return out


def _powell(residuals, starts, options) -> list:
    def objective(v):
        return float(np.sqrt((residuals(v[None])[0] ** 2).mean()))

    out = []
    for v0 in starts:
        r = minimize(objective, v0, method="Powell", options=dict(options))
        out.append((r.x, float(r.fun), int(r.status)))
    return out


def fit_pose(statistic: Callable[[dict], np.ndarray], published, entries: Sequence, *, starts,
             free: Sequence[str], fixed: Mapping | None = None, bounds=None, scale=None,
             method: str = "least_squares", ftol: float = 1e-15, xtol: float = 1e-15,
             max_nfev: int = 500, options: Mapping | None = None) -> pd.DataFrame:
    """Fit the pose whose statistic best matches the published values, from each start.

    Parameters
    ----------
    statistic : callable
        ``statistic(pose) -> (B, ...)`` for ``pose = {axis: (B,) array}`` (mm, rad).
    published : array (m,)
        The published values the statistic is fitted to.
    entries : sequence of arrays (m,)
        Where each published value sits in the statistic's trailing axes.
    starts : array (s, len(free))
        Start values of the free axes (mm, rad), one fit each.
    free : sequence of str
        The axes fitted, in the order of the columns of ``starts``.
    fixed : mapping, optional
        The other axes' values (mm, rad), the same for every fit.
    bounds : (lo, hi), optional
        Arrays (len(free),) of bounds (``-inf``/``inf`` for none; least squares only).
    scale : array (len(free),), optional
        Typical size of each free axis (``least_squares``'s ``x_scale``, and the Jacobian's
        steps ``1e-6 * scale``); default 1.
    method : {"least_squares", "powell"}
        Trust-region reflective least squares (a smooth statistic), run until the relative
        change of the cost falls below ``ftol`` or of the step below ``xtol``; or Powell's
        method on the RMS misfit with ``options`` (a piecewise-constant statistic).
    ftol, xtol : float
        Relative changes of the cost and of the step below which ``least_squares`` stops.
    max_nfev : int
        Evaluations per start allowed to ``least_squares``.
    options : mapping, optional
        ``scipy.optimize.minimize`` options of Powell's method.

    Returns
    -------
    DataFrame (s, len(free) + 2)
        One row per start: the fitted free axes, ``misfit`` (RMS of the residuals) and the
        optimiser's ``status``.
    """
    free = tuple(free)
    starts = np.atleast_2d(np.asarray(starts, dtype=float))
    if starts.shape[1] != len(free):
        raise ValueError(f"starts must have {len(free)} columns ({free}), got {starts.shape}")
    residuals = pose_residuals(statistic, published, entries, free=free, fixed=fixed)
    if method == "least_squares":
        scale = np.ones(len(free)) if scale is None else np.asarray(scale, dtype=float)
        lo, hi = ((np.full(len(free), -np.inf), np.full(len(free), np.inf)) if bounds is None
                  else (np.asarray(bounds[0], dtype=float), np.asarray(bounds[1], dtype=float)))
        fits = least_squares_starts(residuals, starts, lo=lo, hi=hi, scale=scale, ftol=ftol,
                                    xtol=xtol, max_nfev=max_nfev)
    elif method == "powell":
        fits = _powell(residuals, starts, options or {})
    else:
        raise ValueError(f"method must be 'least_squares' or 'powell', got {method!r}")
    rows = [{**{a: float(x[i]) for i, a in enumerate(free)}, "misfit": misfit, "status": status}
            for x, misfit, status in fits]
    return pd.DataFrame(rows, columns=[*free, "misfit", "status"])
