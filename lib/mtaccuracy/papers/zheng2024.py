"""Notebook 01's paper code (Zheng et al. 2024): the pose behind Table 2, its checks, figures.

The paper prints Sobol' indices of the AC double turntable (Table 2, Figs. 5-6) computed at a
pose it does not state: it shows test points on the four body diagonals of the workspace
(Fig. 4) but not which point, or which aggregate, Table 2 reports, nor where the rotary axes
stand at those points.  The pose is what the paper omits, so this module searches for it,
written by hand for this paper:

- the 32-element symmetry group of the normalised linear indices (:func:`pose_orbit`,
  :func:`canonical_pose`) and the canonical ranking of an optimiser's minima
  (:func:`rank_poses`), so that which pose is reported depends neither on the order of the
  starts nor on rounding;
- the least-squares search for the pose behind a table of published indices
  (:func:`fit_pose_to_indices`) and for two poses whose mean indices give it
  (:func:`fit_pose_average_to_indices`);
- the necessary conditions every single pose meets: ratios of indices the model fixes at every
  pose (:func:`index_invariants`), with the printed precision carried into a ratio
  (:func:`ratio_interval`), and Table 2 against them (:func:`fixed_ratio_checks`);
- the Fig. 4 test points (:func:`diagonal_test_points`), the sampled and PCE references at a
  test point, Section 3.2's group shares and the figures, with their captions
  (:data:`FIGURES`, in the book's order; :data:`FIG04`, :data:`FIG05`, :data:`FIG06` beside
  the functions that draw them);
- the notebook's parameters (:class:`Parameters`).

The methods are in :mod:`mtaccuracy.sensitivity` (:mod:`~mtaccuracy.sensitivity.posefit`: the
pose search shared with notebook 03; :mod:`~mtaccuracy.sensitivity.linear`: the closed-form
indices) and the machine in :mod:`mtaccuracy.machines.ac_double_turntable`.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pandas as pd
import param

from .. import sensitivity as S
from ..machines.ac_double_turntable import AXES, TRAVELS, ACDoubleTurntable
from ..validate import integer
from .figure import Caption, figures
from .parameters import NotebookParameters, NumberList, OutputFolder

__all__ = ["POSE_SYMMETRIES", "pose_orbit", "canonical_pose", "rank_poses",
           "fit_pose_to_indices", "fit_pose_average_to_indices", "index_invariants",
           "ratio_interval", "diagonal_test_points", "table_indices",
           "tidy", "fmt", "normalise", "sobol_reference", "pce_indices", "group_label",
           "fixed_ratio_checks", "group_head", "converged_at", "bars_figure",
           "fig04_figure", "group_shares", "relative_scatter", "pce_fit_quality",
           "key_relative_difference", "published_relative_difference", "READINGS",
           "both_sizes", "convergence_text", "fluctuation_text"]


# --------------------------------------------------------------------------------------
# The test points of Fig. 4
# --------------------------------------------------------------------------------------

def diagonal_test_points(n_per_diagonal: int = 5, rotary: str = "sweep") -> dict[str, np.ndarray]:
    """Test points equally spaced on the four body diagonals of the X-Y-Z workspace (Fig. 4).

    Each diagonal runs from one corner of the travel box (``ac_double_turntable.TRAVELS``) to
    the opposite one; ``n_per_diagonal`` points split it into equal parts, ends included, so
    every diagonal passes through the centre.  The rotary axes are not given by Fig. 4:
    ``rotary="sweep"`` moves A and C with the same fraction of their travel as the linear
    axes, ``rotary="zero"`` keeps A = C = 0.

    Parameters
    ----------
    n_per_diagonal : int
        Points per diagonal, ends included (at least 2; the paper's Fig. 4 shows 5).
    rotary : {"sweep", "zero"}
        The rule for A and C, which Fig. 4 does not give.

    Returns
    -------
    dict of str to array (4 n_per_diagonal,)
        x, y, z (mm), A, C (rad), ``diagonal`` (0-3) and ``fraction`` (0..1 along it).
    """
    n_per_diagonal = integer(n_per_diagonal, "n_per_diagonal", low=2)
    if rotary not in ("sweep", "zero"):
        raise ValueError(f"unknown rotary rule {rotary!r}; allowed: sweep, zero")
    f = np.linspace(0.0, 1.0, n_per_diagonal)
    signs = [(1, 1, 1), (-1, 1, 1), (1, -1, 1), (1, 1, -1)]
    out = {k: [] for k in ("x", "y", "z", "A", "C", "diagonal", "fraction")}
    for k, s in enumerate(signs):
        for fr in f:
            for ax, sg in zip("xyz", s, strict=True):
                lo, hi = TRAVELS[ax]
                u = fr if sg > 0 else 1.0 - fr
                out[ax].append(lo + u * (hi - lo))
            for ax in "AC":
                lo, hi = TRAVELS[ax]
                out[ax].append(lo + fr * (hi - lo) if rotary == "sweep" else 0.0)
            out["diagonal"].append(k)
            out["fraction"].append(fr)
    return {k: np.asarray(v) for k, v in out.items()}


# --------------------------------------------------------------------------------------
# Symmetries of the linear indices, and the search for the pose behind a table of indices
# --------------------------------------------------------------------------------------

#: Elements of the symmetry group of the normalised linear indices, as (sx, sy, sz, half-turn
#: of the cradle, half-turn of the table); see :func:`pose_orbit`.
POSE_SYMMETRIES = tuple((sx, sy, sz, ka, hc) for sx in (1, -1) for sy in (1, -1)
                        for sz in (1, -1) for ka in (0, 1) for hc in (0, 1))


def pose_orbit(pose: Mapping, fixed_position: bool = False) -> dict[str, np.ndarray]:
    """Every pose with the same normalised linear indices as ``pose``, in symmetry order.

    The indices ``J_ki^2 sd_i^2 / sum_j J_kj^2 sd_j^2`` depend on each error's effect only
    through its square.  Every error is a translation along or a rotation about a coordinate
    axis, so a reflection of the machine in a coordinate plane through the A/C intersection
    maps each error's effect onto plus or minus itself: x -> -x with C -> -C, y -> -y with
    A -> -A and C -> -C, z -> -z with A -> -A (and their products, e.g. the point inversion
    of x, y, z with A and C unchanged).  Two half-turns do the same: of the table,
    C -> C + 180 deg (x and y change sign in the workpiece frame), and of the cradle,
    A -> A + 180 deg with C -> -C (the table's z axis upside down).  The group is (Z2)^5, 32
    poses; ``fixed_position`` keeps the 4 that leave x, y, z alone.  A is wrapped to
    (-180, 180] deg (members outside the A travel remain in the list), C to [0, 360) deg.
    The reflections need the tool tip at the Z carriage's origin: a tool length ``L`` other
    than 0 is refused.

    Parameters
    ----------
    pose : mapping
        x, y, z (mm), A, C (rad).
    fixed_position : bool
        Only the 4 symmetries that keep x, y, z.

    Returns
    -------
    dict of str to array (32,) or (4,)
        x, y, z (mm), A, C (rad) of the group's images, in the order of
        :data:`POSE_SYMMETRIES`.
    """
    if np.any(np.asarray(pose.get("L", 0.0)) != 0):
        raise ValueError("pose_orbit: the symmetries hold for tool length L = 0 only (the "
                         "reflections would also have to reverse the tool)")
    p = {k: np.asarray(pose[k], dtype=float) for k in AXES}
    out = {k: [] for k in AXES}
    for sx, sy, sz, ka, hc in POSE_SYMMETRIES:
        if fixed_position and (sx, sy, sz) != (1, 1, 1):
            continue
        a = sy * sz * p["A"] + ka * np.pi
        c = sx * sy * p["C"] * (-1 if ka else 1) + hc * np.pi
        out["x"].append(sx * p["x"])
        out["y"].append(sy * p["y"])
        out["z"].append(sz * p["z"])
        out["A"].append(np.pi - np.mod(np.pi - a, 2 * np.pi))          # (-pi, pi]
        out["C"].append(np.mod(c, 2 * np.pi))
    return {k: np.asarray(v) for k, v in out.items()}


def _canonical_key(x, y, z, a, c):
    """The criteria of the canonical member of an orbit, each to be maximised in turn.

    x, y, z >= 0, then |A| <= 90 deg, C in [0, 180) deg (then the sign of A and C = 0 over
    180 deg, which matter only on the boundaries)."""
    return np.stack([x, y, z, np.cos(a), np.sin(c), np.cos(c), np.sin(a)], axis=-1)


def canonical_pose(pose: Mapping, *, fixed_position: bool = False, pos_tol: float = 1e-2,
                   ang_tol: float = 1e-4) -> dict[str, float]:
    """The canonical member of the orbit of ``pose`` (:func:`pose_orbit`).

    The member with the largest x, then y, then z, then cos A, sin C, cos C, sin A, where
    values within ``pos_tol`` or ``ang_tol`` count as equal, so that a coordinate that is zero
    up to rounding does not decide.  For a generic pose this is the member with x, y, z >= 0,
    -90 < A <= 90 deg and 0 <= C < 180 deg, which always lies inside the travels (they are
    symmetric in x, y, z and contain that A range).

    Parameters
    ----------
    pose : mapping
        x, y, z (mm), A, C (rad), scalars.
    fixed_position : bool
        Only the symmetries that keep x, y, z.
    pos_tol : float
        x, y, z closer than this (mm) count as equal.
    ang_tol : float
        Cosines and sines of A and C closer than this count as equal.

    Returns
    -------
    dict of str to float
        x, y, z (mm), A, C (rad).
    """
    orbit = pose_orbit(pose, fixed_position)
    if orbit["x"].ndim != 1:
        raise ValueError("canonical_pose takes one pose (scalar values)")
    keys = _canonical_key(*(orbit[k] for k in AXES))
    tol = np.array([pos_tol] * 3 + [ang_tol] * 4)
    best = S.rank_with_ties(np.zeros(len(keys)), keys=-keys, key_tol=tol)[0]
    return {k: float(orbit[k][best]) for k in AXES}


def rank_poses(candidates, *, misfit: str = "misfit", rtol: float = 1e-6,
               fixed_position: bool = False, pos_tol: float = 1e-2, ang_tol: float = 1e-4):
    """The canonical ranking of the poses an optimiser returned (one row per start).

    Each pose is mapped to its canonical member (:func:`canonical_pose`); candidates whose
    canonical poses agree within ``pos_tol`` and ``ang_tol`` are one minimum (the one with the
    smallest misfit stands for it; ``n_starts`` counts them); minima are ranked by misfit,
    misfits within ``rtol`` of the best remaining one being ties, broken by the canonical pose
    (largest x, y, z first, then smallest A, C; see
    :func:`~mtaccuracy.sensitivity.rank_with_ties`): which pose comes first depends neither
    on the order of the starts nor on rounding noise.

    Parameters
    ----------
    candidates : DataFrame
        x, y, z (mm), A, C (rad) and the misfit column, one row per start.
    misfit : str
        Name of the misfit column.
    rtol : float
        Misfits closer than this, relative to the best remaining one, are ties.
    fixed_position : bool
        Only the symmetries that keep x, y, z.
    pos_tol : float
        Canonical x, y, z closer than this (mm) are one minimum.
    ang_tol : float
        Canonical A and C closer than this (rad) are one minimum.

    Returns
    -------
    DataFrame
        One row per minimum, best first: x, y, z, A, C, the misfit column and ``n_starts``.
    """
    df = pd.DataFrame(candidates)
    missing = [c for c in (*AXES, misfit) if c not in df.columns]
    if missing:
        raise ValueError(f"candidates lack column(s) {missing}")
    if df.empty:
        raise ValueError("no candidates to rank")
    canon = pd.DataFrame([canonical_pose(r, fixed_position=fixed_position, pos_tol=pos_tol,
                                         ang_tol=ang_tol)
                          for r in df[list(AXES)].to_dict("records")])
    canon[misfit] = df[misfit].to_numpy(dtype=float)
    order = S.rank_with_ties(canon[misfit].to_numpy(), rtol=0.0)
    reps, counts = [], []
    for i in order:  # smallest misfit first: it stands for its minimum
        r = canon.iloc[i]
        for j, q in enumerate(reps):
            if (max(abs(r.x - q.x), abs(r.y - q.y), abs(r.z - q.z)) <= pos_tol
                    and abs(np.angle(np.exp(1j * (r.A - q.A)))) <= ang_tol
                    and abs(np.angle(np.exp(1j * (r.C - q.C)))) <= ang_tol):
                counts[j] += 1
                break
        else:
            reps.append(r)
            counts.append(1)
    minima = pd.DataFrame(reps).reset_index(drop=True)
    minima["n_starts"] = counts
    keys = np.c_[-minima[["x", "y", "z"]].to_numpy(), minima[["A", "C"]].to_numpy()]
    tol = [pos_tol] * 3 + [ang_tol] * 2
    ranked = S.rank_with_ties(minima[misfit].to_numpy(), keys=keys, rtol=rtol, key_tol=tol)
    return minima.iloc[ranked].reset_index(drop=True)


def fit_pose_to_indices(machine: ACDoubleTurntable, sd, target, *, rows, cols, starts,
                        free=AXES, fixed: Mapping | None = None, ftol: float = 1e-15,
                        xtol: float = 1e-15, max_nfev: int = 500):
    """Least-squares fits of the pose whose normalised linear indices best match ``target``.

    The indices are :func:`~mtaccuracy.sensitivity.linear_indices` of
    :meth:`ACDoubleTurntable.jacobian`, compared at the (component, error) pairs
    ``rows``, ``cols``.  x, y, z and A stay within their travels, C is free (periodic).
    scipy's ``least_squares`` (trust-region reflective, :func:`~mtaccuracy.sensitivity.
    fit_pose`) with a central-difference Jacobian evaluated in one batched call, run until the
    relative change of the cost falls below ``ftol`` or of the step below ``xtol``.  BLAS runs
    single-threaded (small matrices: threads only cost time, and the result is then the same
    for any thread count).

    Parameters
    ----------
    machine : ACDoubleTurntable
        The machine whose Jacobian gives the indices.
    sd : array (41,)
        Error standard deviations (mm, rad).
    target : array (m,)
        The published indices.
    rows, cols : arrays of int (m,)
        The (component, error) entries of ``target``.
    starts : array (s, len(free))
        Start values of the free axes (mm, rad), one row per start.
    free : sequence of str
        The axes fitted.
    fixed : mapping, optional
        Values of the axes not in ``free`` (mm, rad).
    ftol, xtol : float
        Relative changes of the cost and of the step below which a fit stops.
    max_nfev : int
        Evaluations per start.

    Returns
    -------
    DataFrame (s, 7)
        One row per start: x, y, z (mm), A, C (rad, C in [0, 2 pi)), ``misfit`` (RMS of the
        residuals) and the optimiser's ``status``.
    """
    free = tuple(free)
    fixed = dict(fixed or {})
    if set(free) | set(fixed) != set(AXES) or set(free) & set(fixed):
        raise ValueError(f"free {free} and fixed {tuple(fixed)} must split the axes {AXES}")
    bounds = (np.array([TRAVELS[a][0] if a != "C" else -np.inf for a in free]),
              np.array([TRAVELS[a][1] if a != "C" else np.inf for a in free]))
    fits = S.fit_pose(lambda pose: S.linear_indices(machine.jacobian(pose), sd=sd), target,
                      (cols, rows), starts=starts, free=free, fixed=fixed, bounds=bounds,
                      scale=np.array([100.0 if a in "xyz" else 1.0 for a in free]),
                      ftol=ftol, xtol=xtol, max_nfev=max_nfev)
    for a in fixed:
        fits[a] = float(fixed[a])
    fits["C"] = np.mod(fits["C"].to_numpy(dtype=float), 2 * np.pi)
    return fits[[*AXES, "misfit", "status"]]


def fit_pose_average_to_indices(machine: ACDoubleTurntable, sd, target, *, rows, cols, starts,
                                ftol: float = 1e-12, xtol: float = 1e-12,
                                max_nfev: int = 300):
    """Least-squares fits of several poses whose *mean* normalised linear indices match ``target``.

    The hypothesis that a table reports indices averaged over several poses, equal weights.
    As :func:`fit_pose_to_indices` otherwise (x, y, z, A within their travels, batched
    central-difference Jacobian, single-threaded BLAS).  Each fitted pose is reported as its
    canonical image (:func:`canonical_pose`), the poses of one fit ordered by decreasing A
    (the mean does not depend on their order).

    Parameters
    ----------
    machine : ACDoubleTurntable
        The machine whose Jacobian gives the indices.
    sd : array (41,)
        Error standard deviations (mm, rad).
    target : array (m,)
        The published indices.
    rows, cols : arrays of int (m,)
        The (component, error) entries of ``target``.
    starts : array (s, poses, 5)
        x, y, z (mm), A, C (rad) of each pose, one block per start.
    ftol, xtol : float
        Relative changes of the cost and of the step below which a fit stops.
    max_nfev : int
        Evaluations per start.

    Returns
    -------
    DataFrame
        One row per start and pose: ``start``, ``pose`` (0..poses-1), x, y, z (mm), A, C
        (rad), ``misfit`` (RMS over the entries) and the optimiser's ``status``.
    """
    starts = np.asarray(starts, dtype=float)
    if starts.ndim != 3 or starts.shape[2] != 5:
        raise ValueError(f"starts must be (starts, poses, 5), got {starts.shape}")
    m = starts.shape[1]
    target = np.asarray(target, dtype=float)
    rows, cols = np.asarray(rows), np.asarray(cols)
    scale = np.tile([100.0, 100.0, 100.0, 1.0, 1.0], m)
    lo = np.tile([TRAVELS["x"][0], TRAVELS["y"][0], TRAVELS["z"][0], TRAVELS["A"][0], -np.inf], m)
    hi = np.tile([TRAVELS["x"][1], TRAVELS["y"][1], TRAVELS["z"][1], TRAVELS["A"][1], np.inf], m)

    def residuals(v):  # v: (B, 5 m) -> (B, entries)
        p = v.reshape(-1, 5)
        pose = {a: p[:, i] for i, a in enumerate(AXES)}
        s = S.linear_indices(machine.jacobian(pose), sd=sd)[:, cols, rows]
        return s.reshape(v.shape[0], m, -1).mean(axis=1) - target

    out = []
    fits = S.least_squares_starts(residuals, starts.reshape(len(starts), -1), lo=lo, hi=hi,
                                  scale=scale, ftol=ftol, xtol=xtol, max_nfev=max_nfev)
    for k, (x, misfit, status) in enumerate(fits):
        poses = [canonical_pose(dict(zip(AXES, p, strict=True))) for p in x.reshape(m, 5)]
        poses.sort(key=lambda p: -p["A"])
        out += [dict(start=k, pose=j, **p, misfit=misfit, status=status)
                for j, p in enumerate(poses)]
    return pd.DataFrame(out)


# --------------------------------------------------------------------------------------
# Necessary conditions on a table of indices: ratios the model fixes at every pose
# --------------------------------------------------------------------------------------

def index_invariants(machine: ACDoubleTurntable, sd, *, rows, cols, poses: Mapping,
                     rtol: float = 1e-9):
    """Ratios of normalised linear indices that the model fixes at every pose.

    The normalised linear index is ``S_ki = J_ki^2 sd_i^2 / V_k``, so

    - within a component, two errors whose Jacobian entries stay proportional at every pose
      (the same structure: e.g. translations along one direction of one moving frame) have
      ``S_ki / S_kj`` fixed by their variance ratio, whatever the pose: they form a *group*;
    - across components, a ratio of two groups in component k and one in component l can be
      the same function of the pose (e.g. ``sin^2 A`` in Vx and in Vy), so their quotient is
      fixed too (``V_k``, ``V_l`` cancel).

    A ratio counts as fixed when its largest relative spread over ``poses`` is below
    ``rtol``; entries whose index is zero at some pose are left alone (no ratio).

    Parameters
    ----------
    machine : ACDoubleTurntable
        The machine whose Jacobian gives the indices.
    sd : array (41,)
        Error standard deviations (mm, rad).
    rows, cols : arrays of int (m,)
        The table's (component, error) entries (e.g. Table 2).
    poses : mapping
        Pose arrays (P,), P >= 3: many random poses, x, y, z (mm), A, C (rad).
    rtol : float
        Largest relative spread over the poses of a ratio that counts as fixed.

    Returns
    -------
    groups : DataFrame
        One row per entry: ``entry``, ``component``, ``error``, ``group`` (an integer, -1 for
        an entry left alone; entries of one group share a component) and ``factor``, the fixed
        ratio ``S_entry / S_head`` (head: the group's first entry).
    cross : DataFrame
        The groups ``num_k, den_k, num_l, den_l`` and ``value``, the fixed quotient
        ``(S_num_k / S_den_k) / (S_num_l / S_den_l)`` of their heads.
    """
    rows, cols = np.asarray(rows), np.asarray(cols)
    s = S.linear_indices(machine.jacobian(poses), sd=sd)[:, cols, rows]   # (P, entries)
    if s.shape[0] < 3:
        raise ValueError("index_invariants needs at least 3 poses to tell a fixed ratio")
    ok = (s > 0).all(axis=0)
    logs = np.log(np.where(s > 0, s, 1.0))

    def fixed(r):
        return float(np.abs(np.expm1(r - r.mean())).max()) < rtol

    group = -np.ones(len(rows), dtype=int)
    factor = np.full(len(rows), np.nan)
    heads = []
    for a in range(len(rows)):
        if group[a] >= 0 or not ok[a]:
            continue
        group[a], factor[a] = len(heads), 1.0
        for b in range(a + 1, len(rows)):
            if group[b] < 0 and ok[b] and rows[b] == rows[a] and fixed(logs[:, b] - logs[:, a]):
                group[b], factor[b] = len(heads), float(np.exp((logs[:, b] - logs[:, a]).mean()))
        heads.append(a)
    pairs = [(g, h) for g in range(len(heads)) for h in range(g + 1, len(heads))
             if rows[heads[g]] == rows[heads[h]]]
    cross = []
    for i, (g, h) in enumerate(pairs):
        rk = logs[:, heads[g]] - logs[:, heads[h]]
        for g2, h2 in pairs[i + 1:]:
            if rows[heads[g2]] == rows[heads[g]]:
                continue
            for num, den in ((g2, h2), (h2, g2)):
                q = rk - (logs[:, heads[num]] - logs[:, heads[den]])
                if fixed(q):
                    cross.append(dict(num_k=g, den_k=h, num_l=num, den_l=den,
                                      value=float(np.exp(q.mean()))))
    groups = pd.DataFrame({"entry": np.arange(len(rows)), "component": rows, "error": cols,
                           "group": group, "factor": factor})
    return groups, pd.DataFrame(cross, columns=["num_k", "den_k", "num_l", "den_l", "value"])


def ratio_interval(num, den):
    """The interval of ``num / den`` for two positive intervals (interval arithmetic).

    How the printed precision of two published values propagates into their ratio.

    Parameters
    ----------
    num, den : pair of float
        ``(lo, hi)`` of the numerator and of the denominator; ``den`` strictly positive,
        ``num`` not negative.

    Returns
    -------
    lo, hi : float
        ``num_lo / den_hi`` and ``num_hi / den_lo``.
    """
    (num_lo, num_hi), (den_lo, den_hi) = num, den
    if np.any(np.asarray(den_lo) <= 0) or np.any(np.asarray(num_lo) < 0):
        raise ValueError("ratio_interval needs positive intervals")
    return np.asarray(num_lo) / np.asarray(den_hi), np.asarray(num_hi) / np.asarray(den_lo)


# --------------------------------------------------------------------------------------
# Table 2's checks, the references at a test point, and figures
# --------------------------------------------------------------------------------------

def tidy(df: pd.DataFrame) -> pd.DataFrame:
    """Floats rounded to 6 decimals, and a rounded -0 written as 0 (its sign is rounding noise).

    Parameters
    ----------
    df : pandas.DataFrame
        A table about to be saved.

    Returns
    -------
    pandas.DataFrame
        The same table, its float columns rounded; other columns unchanged.
    """
    return df.apply(lambda s: s.round(6) + 0.0 if s.dtype.kind == "f" else s)


def fmt(v: float) -> str:
    """One decimal for values above 0.1 in magnitude, four below (poses, misfits).

    Parameters
    ----------
    v : float
        The value printed.

    Returns
    -------
    str
        ``"102.5"``, ``"0.0046"``.
    """
    return f"{v:.1f}" if abs(v) > 0.1 else f"{v:.4f}"


def table_indices(jacobian, *, sd) -> np.ndarray:
    """Closed-form indices as the paper's Table 2 lays them out: components by errors.

    The library's index arrays are input by output, ``(..., d, q)``
    (:func:`mtaccuracy.sensitivity.linear_indices`); the paper's tables, this notebook's
    ``rows, cols`` and its figures read a component's row of 41 errors.

    Parameters
    ----------
    jacobian : array (..., 6, 41)
        ``machine.jacobian(pose)``.
    sd : array (41,)
        Standard deviations of the errors (mm, rad).

    Returns
    -------
    array (..., 6, 41)
    """
    return np.swapaxes(S.linear_indices(jacobian, sd=sd), -1, -2)


def normalise(st):
    """Table 2's normalised total indices: ``st`` clipped at 0, over their sum.

    Parameters
    ----------
    st : array (..., d)
        Total indices of the d errors (a sampled estimate may be slightly negative).

    Returns
    -------
    array (..., d)
        Non-negative, summing to 1 over the last axis.
    """
    st = np.clip(st, 0, None)
    return st / st.sum(axis=-1, keepdims=True)


def sobol_reference(machine, pose, sd, method: str, n: int, rng_seed: int, progress=False):
    """Sampled Sobol' indices (s1, st) of the six pose-error components at ``pose``.

    Errors normal with standard deviations ``sd``: ``method`` "mc" or "lhs" designs of ``n``
    base rows, streamed (``sensitivity.sobol_indices`` on a ``SobolDesign``: base rows drawn
    block by block, the AB runs reduced to per-error sums as they come, never stored).

    Parameters
    ----------
    machine : ACDoubleTurntable
        The machine (its ``pose_error``).
    pose : mapping
        x, y, z (mm), A, C (rad).
    sd : array (41,)
        Error standard deviations (mm, rad).
    method : {"mc", "lhs"}
        Independent uniforms, or two Latin hypercubes.
    n : int
        Base sample size N (43 N model runs).
    rng_seed : int
        Seed of the design.
    progress : bool
        Print a line per quarter of the runs.

    Returns
    -------
    s1, st : array (41, 6)
        First-order and total indices, errors by components.
    """
    design = S.SobolDesign(n, S.Inputs.normal(0.0, sd), method=method, seed=rng_seed)
    marks = set()

    def report(done, total):
        q = int(4 * done / total)
        if progress and q not in marks:
            marks.add(q)
            print(f"  {method.upper()}: {done:,} / {total:,} model runs", flush=True)

    # an LHS design is held whole: see sensitivity.SobolDesign
    return S.sobol_indices(lambda x: machine.pose_error(x, pose), design, chunk=250_000,
                           progress=report)


def pce_indices(machine, pose, sd, n: int, degree: int, rng_seed: int, q_norm: float = 1.0,
                comps=tuple(range(6))) -> dict:
    """Sparse PCE fits of the pose-error components ``comps`` at ``pose``.

    ``sensitivity.fit_pce_outputs`` on a Latin hypercube of ``n`` standard normals (errors =
    xi * sd).

    Parameters
    ----------
    machine : ACDoubleTurntable
        The machine (its ``pose_error``).
    pose : mapping
        x, y, z (mm), A, C (rad).
    sd : array (41,)
        Error standard deviations (mm, rad).
    n : int
        Design size.
    degree : int
        Total degree of the Hermite basis.
    rng_seed : int
        Seed of the Latin hypercube.
    q_norm : float
        Hyperbolic truncation of the basis (1: the full total-degree basis).
    comps : sequence of int
        The components fitted (0-5: Px, Py, Pz, Vx, Vy, Vz).

    Returns
    -------
    dict of int to PCE fit
        ``{component: fit}``.
    """
    u = S.base_samples(n, 41, method="lhs", seed=rng_seed)[0]
    xi = S.Inputs.normal(0.0, np.ones(41)).from_unit(u)
    y = machine.pose_error(xi * sd, pose)
    fits = S.fit_pce_outputs(xi, y[:, list(comps)], degree=degree, q_norm=q_norm)
    return dict(zip(comps, fits, strict=True))


def group_label(groups, t2, g) -> str:
    """A group of Table 2 entries fixed equal by the model: its component and symbols.

    Parameters
    ----------
    groups : pandas.DataFrame
        The groups of :func:`index_invariants` (``entry``, ``group``).
    t2 : pandas.DataFrame
        Table 2, one row per entry (``comp``, ``symbol``).
    g : int
        The group.

    Returns
    -------
    str
        ``"Py d_xx/d_xz/d_xa/d_xAM"``.
    """
    m = groups[groups.group == g].entry
    return f"{t2.comp.iloc[m.iloc[0]]} " + "/".join(t2.symbol.iloc[m])


def group_head(groups, ci, ei, g):
    """(component, error) index of a group's first entry.

    Parameters
    ----------
    groups : pandas.DataFrame
        The groups of :func:`index_invariants` (``entry``, ``group``).
    ci, ei : array of int
        Component and error index of each Table 2 entry.
    g : int
        The group.

    Returns
    -------
    (int, int)
        Component and error index of the group's first entry.
    """
    j = groups.entry[groups.group == g].iloc[0]
    return ci[j], ei[j]


def fixed_ratio_checks(t2, *, half, groups, cross, any_sd, methods=("pce", "mcs", "lhs")):
    """Table 2 against the equalities and quotients the model fixes at every pose.

    Parameters
    ----------
    t2 : pandas.DataFrame
        Table 2, one row per entry, a float column per method (and ``comp``, ``symbol``).
    half : pandas.DataFrame
        Half a unit of each printed value's last digit, the same columns.
    groups, cross : pandas.DataFrame
        :func:`index_invariants`: entries equal at every pose up to fixed factors, and
        quotients of four groups fixed at every pose.
    any_sd : set of tuple
        The quotients ``(num_k, den_k, num_l, den_l)`` that hold for any error variances.
    methods : sequence of str
        The columns of ``t2`` checked.

    Returns
    -------
    equalities : pandas.DataFrame
        Per group of two or more entries, the spread of the printed values (percent) and
        whether their printed intervals meet, per method.
    quotients : pandas.DataFrame
        Per fixed quotient, the model's value, the printed value's interval (printed precision
        propagated, widened by twice the paper's own scatter) and whether it holds the model's
        value, per method.
    floor : float
        The noise floor: RMS of the published PCE values around the group means.
    scatter : dict of str to float
        Per method, the relative scatter of one published value around its group mean.
    """
    def group_interval(g, m):
        """(lo, hi) of a group's mean published value (divided by the fixed factors)."""
        e = groups[groups.group == g]
        v, h = t2[m].to_numpy()[e.entry] / e.factor, half[m].to_numpy()[e.entry] / e.factor
        return float((v - h).mean()), float((v + h).mean())

    def label(g):
        return group_label(groups, t2, g)

    # the paper's own scatter: relative deviations of its values from the group means
    fixed = groups[groups.group >= 0]

    def rel_dev(m):
        v = t2[m].to_numpy()[fixed.entry] / fixed.factor.to_numpy()
        return v / pd.Series(v).groupby(fixed.group.to_numpy()).transform("mean").to_numpy() - 1

    multi = fixed.group.map(fixed.group.value_counts()).to_numpy() > 1
    scatter = {m: float(np.sqrt(np.mean(rel_dev(m)[multi] ** 2) * multi.sum()
                                / (multi.sum() - fixed[multi].group.nunique())))
               for m in methods}  # RMS relative deviation, corrected for the fitted group means
    size = fixed.group.value_counts()
    eq_rows = []
    for g, e in fixed.groupby("group"):
        if len(e) < 2:
            continue
        row = dict(group=label(g))
        for m in methods:
            v, h = t2[m].to_numpy()[e.entry] / e.factor, half[m].to_numpy()[e.entry] / e.factor
            row[f"{m}_spread_percent"] = 100 * (v.max() / v.min() - 1)
            row[f"{m}_holds"] = bool((v - h).max() <= (v + h).min())   # printed intervals meet
        eq_rows.append(row)
    cr_rows = []
    for r in cross.itertuples():
        row = dict(quotient=f"({label(r.num_k)}) / ({label(r.den_k)})  over  "
                            f"({label(r.num_l)}) / ({label(r.den_l)})",
                   model=r.value, any_variances=(r.num_k, r.den_k, r.num_l, r.den_l) in any_sd)
        for m in methods:
            iv = [group_interval(g, m) for g in (r.num_k, r.den_k, r.num_l, r.den_l)]
            lo, hi = ratio_interval(ratio_interval(iv[0], iv[1]), ratio_interval(iv[2], iv[3]))
            row[m] = 0.5 * (lo + hi)
            # widened by twice the paper's own scatter of a quotient of four group means
            s = scatter[m] * np.sqrt(sum(1 / size[g] for g in (r.num_k, r.den_k, r.num_l, r.den_l)))
            lo, hi = lo * (1 - 2 * s), hi * (1 + 2 * s)
            row[f"{m}_interval"] = f"[{lo:.3f}, {hi:.3f}]"
            row[f"{m}_holds"] = bool(lo <= r.value <= hi)
        cr_rows.append(row)
    # the noise floor: RMS of the published PCE values around the equalities the model fixes
    scaled = t2.pce.to_numpy()[fixed.entry] / fixed.factor.to_numpy()
    means = pd.Series(scaled).groupby(fixed.group.to_numpy()).transform("mean").to_numpy()
    floor = float(np.sqrt(np.mean((scaled - means) ** 2)))
    return pd.DataFrame(eq_rows), pd.DataFrame(cr_rows), floor, scatter


def converged_at(g, r_max: float = 3.0, assign: str = "larger"):
    """The first sample size from which the fluctuation R (Eq. 24) stays small; NaN if never.

    R is ``g.R_percent``, the change from the previous size (so NaN at the first); "small" is
    at or below ``r_max`` percent; ``g.n`` ascending.

    Eq. 24, R = |S_(l+1) - S_l| / S_l, does not say to which of the two sizes R belongs:
    ``assign="larger"`` gives it to size l+1 (the reading under which the largest size of a
    series can be the one that converges, as the paper says of MCS and LHS at 1e5),
    ``assign="smaller"`` to size l (Eq. 24 literally; the largest size then has no R).

    Parameters
    ----------
    g : pandas.DataFrame
        One series: ``n`` (ascending) and ``R_percent``.
    r_max : float
        The criterion (percent).
    assign : {"larger", "smaller"}
        The size R belongs to.

    Returns
    -------
    int or float
        The sample size, or NaN if R does not stay small within the sizes run.
    """
    if assign not in ("larger", "smaller"):
        raise ValueError(f"assign must be 'larger' or 'smaller', got {assign!r}")
    r = g.R_percent.to_numpy(dtype=float)[1:]
    n = g.n.to_numpy()
    n = n[:-1] if assign == "smaller" else n[1:]   # "smaller": R of step l -> l+1 is size l's
    fails = np.flatnonzero(~(r <= r_max))
    first = fails[-1] + 1 if fails.size else 0     # from here on R stays small
    return int(n[first]) if first < len(n) else np.nan


def group_shares(s, catalogue, comps) -> pd.DataFrame:
    """Section 3.2's comparisons of groups of errors, from normalised total indices.

    Parameters
    ----------
    s : array (6, 41)
        Indices of the components ``comps``, summing to 1 over the errors.
    catalogue : sequence of errors
        The machine's 41 errors (``translational``, ``axis``, ``kind``).
    comps : sequence of str
        Names of the components, the rows of ``s``.

    Returns
    -------
    pandas.DataFrame
        One row per component: the summed index of the translational and of the angular
        errors, of the errors of the rotary axes (A, C: their error motions and location
        errors) and of the linear axes (X, Y, Z and the squareness errors), and the mean index
        per error of the location errors (PIGEs) and of the error motions (PDGEs, squareness
        counted as PIGE as in Table 1).
    """
    s = np.asarray(s, dtype=float)
    trans = np.array([e.translational for e in catalogue])
    rotary = np.array([e.axis in ("A", "C") for e in catalogue])
    pige = np.array([e.kind != "error motion" for e in catalogue])
    return pd.DataFrame({"component": list(comps),
                         "translational": s[:, trans].sum(axis=1),
                         "angular": s[:, ~trans].sum(axis=1),
                         "rotary_axes": s[:, rotary].sum(axis=1),
                         "linear_axes": s[:, ~rotary].sum(axis=1),
                         "pige_mean": s[:, pige].mean(axis=1),
                         "pdge_mean": s[:, ~pige].mean(axis=1)})


def relative_scatter(estimate, exact, threshold: float = 0.05) -> float:
    """RMS relative deviation of sampled indices ``estimate`` from the ``exact`` ones (key errors).

    Over the entries (same shape) whose exact index exceeds ``threshold`` (the key errors):
    the sampling scatter of one printed value, comparable with the paper's own scatter around
    the equalities its model fixes.

    Parameters
    ----------
    estimate, exact : array
        Sampled and exact indices, the same shape.
    threshold : float
        Entries whose exact index exceeds this are compared.

    Returns
    -------
    float
        The RMS relative deviation (a fraction).
    """
    estimate, exact = np.asarray(estimate, dtype=float), np.asarray(exact, dtype=float)
    key = exact > threshold
    if not key.any():
        raise ValueError(f"no exact index above {threshold}")
    return float(np.sqrt(np.mean((estimate[key] / exact[key] - 1) ** 2)))


def pce_fit_quality(fits, comps) -> pd.DataFrame:
    """How sparse each component's PCE came out: terms kept of the basis, and its corrected LOO.

    Parameters
    ----------
    fits : mapping of int to PCE fit
        ``{component index: fit}`` (:func:`pce_indices`); a fit has ``coef``, ``n_candidates``
        and ``loo``.
    comps : sequence of str
        Names of the components, in the order of ``range(len(comps))``.

    Returns
    -------
    pandas.DataFrame
        One row per component: ``component``, ``terms_kept`` (terms the OMP path chose),
        ``basis_size`` (terms of the full basis) and ``corrected_LOO`` (relative error).
    """
    k = range(len(comps))
    return pd.DataFrame({"component": list(comps), "terms_kept": [len(fits[i].coef) for i in k],
                         "basis_size": [fits[i].n_candidates for i in k],
                         "corrected_LOO": [fits[i].loo for i in k]})


def key_relative_difference(st, *, keys, comps, names, of: str = "PCE",
                            against=("MCS", "LHS")) -> float:
    """Section 3.3's check on our estimates: the largest relative difference over the key errors.

    ``|st[of] / st[m] - 1|`` over the entries ``keys`` and the methods ``m`` of ``against``:
    relative to the sampled value, as the paper states its "< 5 %".

    Parameters
    ----------
    st : mapping of str to array (len(comps), len(names))
        Normalised total indices by method, components by errors (as Table 2).
    keys : iterable of (str, str)
        The (component, error symbol) entries compared: the key errors.
    comps : sequence of str
        Component names, the rows of each array.
    names : sequence of str
        Error symbols, the columns of each array.
    of : str
        The method compared (the paper's PCE).
    against : sequence of str
        The methods it is compared with, each value the reference of its ratio.

    Returns
    -------
    float
        The largest relative difference (a fraction, not percent).
    """
    rows, cols = np.array([[comps.index(c), names.index(s)] for c, s in sorted(keys)],
                          dtype=int).reshape(-1, 2).T
    if rows.size == 0:
        raise ValueError("key_relative_difference needs at least one key error")
    return max(np.abs(np.asarray(st[of])[rows, cols] / np.asarray(st[m])[rows, cols] - 1).max()
               for m in against)


def published_relative_difference(t2: pd.DataFrame) -> tuple[pd.Series, int]:
    """The same check on the paper's own Table 2: each row's PCE value against MCS and LHS.

    Parameters
    ----------
    t2 : pandas.DataFrame
        Table 2 with float columns ``pce``, ``mcs`` and ``lhs`` (normalised total indices).

    Returns
    -------
    rel : pandas.Series
        Per row, the larger of ``|pce / mcs - 1|`` and ``|pce / lhs - 1|`` (a fraction).
    worst : int
        Position of the row where it is largest (the first of equal ones).
    """
    rel = np.maximum(np.abs(t2.pce / t2.mcs - 1), np.abs(t2.pce / t2.lhs - 1))
    return rel, int(np.argmax(rel.to_numpy()))


#: The two readings of a sample size in Fig. 7: base samples N, or model runs 43 N.
READINGS = ("base samples", "model runs")


def both_sizes(larger, smaller) -> str:
    """A Fig. 7 result under both readings of Eq. 24: R given to the larger or the smaller size.

    Parameters
    ----------
    larger, smaller : str
        The result with R given to the larger of the two sizes, and to the smaller.

    Returns
    -------
    str
        ``"<larger> (R at the larger size), <smaller> (at the smaller)"``.
    """
    return f"{larger} (R at the larger size), {smaller} (at the smaller)"


def convergence_text(conv_txt: pd.DataFrame, *, method: str, symbol: str,
                     readings=READINGS) -> str:
    """Where a sampled method converged in Fig. 7, under each reading of the sample size.

    Parameters
    ----------
    conv_txt : pandas.DataFrame
        Indexed by (method, reading, symbol), two columns: the converged size as text with R
        given to the larger size, then to the smaller (:func:`converged_at`).
    method : str
        "MCS" or "LHS".
    symbol : str
        The error whose index converges.
    readings : sequence of str
        Readings of a sample size, each a level of the index (:data:`READINGS`).

    Returns
    -------
    str
        ``"<reading>: <both sizes>"`` per reading (:func:`both_sizes`), joined by ``"; "``.
    """
    return "; ".join(f"{rd}: {both_sizes(*conv_txt.loc[(method, rd, symbol)])}"
                     for rd in readings)


def fluctuation_text(r_steps: pd.DataFrame, *, method: str, sizes=(1000, 2000),
                     readings=READINGS) -> str:
    """The range of Fig. 7's fluctuation R (percent) over the errors at one sample size.

    R at a size is read both ways (Eq. 24): the step that ends there (R at the larger size,
    column ``sizes[0]``) and the step that starts there (R at the smaller, column
    ``sizes[1]``, the next size).

    Parameters
    ----------
    r_steps : pandas.DataFrame
        R (percent) indexed by (method, reading, symbol), one column per sample size.
    method : str
        "MCS" or "LHS".
    sizes : (int, int)
        The size and the next one run.
    readings : sequence of str
        Readings of a sample size, each a level of the index (:data:`READINGS`).

    Returns
    -------
    str
        ``"<reading>: <min> to <max> % (R at the larger size), <min> to <max> % (at the
        smaller)"`` per reading, one decimal, joined by ``"; "``.
    """
    def span(v):
        return f"{v.min():.1f} to {v.max():.1f} %"

    return "; ".join(f"{rd}: " + both_sizes(*(span(r_steps.loc[(method, rd)][n]) for n in sizes))
                     for rd in readings)


#: Fig. 5's caption (:func:`bars_figure` of Px, Py, Pz); fields: ``n_pce``, ``n_reference``,
#: ``key_threshold``, ``where`` (the test point) and ``gap_pce``, ``gap_mcs``, ``gap_lhs`` (the
#: largest difference of a drawn index from the exact one, per method).
FIG05 = Caption(
    "fig05_position_total_sobol", "Fig. 5",
    "Normalised total Sobol indices of the position error Px, Py, Pz for the 41 errors: sparse "
    "PCE ({n_pce} samples), MCS and LHS ({n_reference:,} base samples each); dashed: key "
    "threshold {key_threshold:g}. Drawn at Fig. 4 {where}, a point chosen by a fixed rule, not "
    "fitted. The published Table 2 belongs to another pose or mean of poses and is not drawn; "
    "it is scored against a two-pose mean. Largest difference of a drawn index from the exact "
    "(closed-form) one: {gap_pce:.0e} (PCE), {gap_mcs:.0e} (MCS), {gap_lhs:.0e} (LHS).",
    rows=("Section 3.3",))

#: Fig. 6's caption (:func:`bars_figure` of Vx, Vy, Vz); the fields of :data:`FIG05`.
FIG06 = Caption(
    "fig06_attitude_total_sobol", "Fig. 6",
    "As Fig. 5, for the error of the tool-axis direction Vx, Vy, Vz (radians to first order), "
    "at the same test point. Only angular and squareness errors enter. Largest difference of a "
    "drawn index from the exact one: {gap_pce:.0e} (PCE), {gap_mcs:.0e} (MCS), {gap_lhs:.0e} "
    "(LHS).",
    rows=("Section 3.3",))


def bars_figure(st, *, comps, all_comps, names, t2, key_threshold: float, title: str,
                published_colour):
    """Figs. 5-6: normalised total indices of every error by method (bars).

    For the components ``comps``, beside Table 2's PCE values (diamonds) unless ``t2`` is
    None (the bars drawn at a pose other than Table 2's).  Captions: :data:`FIG05`,
    :data:`FIG06`.

    Parameters
    ----------
    st : mapping of str to array (6, 41)
        Normalised total indices by method (three methods), components by errors.
    comps : sequence of str
        The components drawn, one panel each.
    all_comps : sequence of str
        Names of the rows of each array of ``st``.
    names : sequence of str
        The 41 error symbols.
    t2 : pandas.DataFrame or None
        Table 2 (``comp``, ``symbol``, ``pce``), drawn as diamonds; None draws none.
    key_threshold : float
        The key-error threshold (a dashed line).
    title : str
        The figure's title.
    published_colour : colour
        The colour of the published values.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt  # local: heavy, needed only by the figures

    fig, axes = plt.subplots(len(comps), 1, figsize=(13, 3.2 * len(comps)), sharex=True)
    w = 0.27
    xpos = np.arange(41)
    for ax, c in zip(axes, comps, strict=True):
        k = all_comps.index(c)
        for j, (m, col) in enumerate(zip(st, ("#1b9e77", "#7570b3", "#66a61e"), strict=True)):
            ax.bar(xpos + (j - 1) * w, st[m][k], w, label=m, color=col)
        if t2 is not None:
            p = t2[t2.comp == c]
            ax.scatter([names.index(s) for s in p.symbol], p.pce, marker="D",
                       color=published_colour, zorder=3, label="published (Table 2, PCE)")
        ax.axhline(key_threshold, color="k", lw=0.7, ls="--")
        ax.set_ylabel(f"{c}: normalised ST")
    axes[0].legend(ncol=4, fontsize=8)
    axes[-1].set_xticks(xpos, names, rotation=90)
    fig.suptitle(title)
    fig.tight_layout()
    return fig


#: Fig. 4's caption (:func:`fig04_figure` at its default colour scale); fields: ``n_points``,
#: ``n_per_diagonal``, ``rms_mean`` (RMS difference of the points' mean indices to Table 2) and
#: ``rms_single`` (the same at the best single pose).
FIG04 = Caption(
    "fig04_indices_per_test_point", "Fig. 4",
    "Closed-form (linear) normalised total Sobol indices of the 41 errors (rows) for the "
    "position error Px, Py, Pz and the tool-axis direction error Vx, Vy, Vz, at the {n_points} "
    "test points on the four workspace diagonals (columns, {n_per_diagonal} per diagonal, white "
    "lines between diagonals); colour scale 0 to 0.3. The paper's Fig. 4 only shows where the "
    "points lie; the rotary angles are not given, so A and C sweep the same fraction of their "
    "travel as x, y, z (an assumption). The key errors change from point to point; their mean "
    "does not fit Table 2 (RMS difference {rms_mean:.4f}, against {rms_single:.4f} at the best "
    "single pose).",
    rows=("Section 3.2",))


def fig04_figure(s_tp, *, comps, names, diagonal, vmax: float = 0.3):
    """Fig. 4's test points: the linear total index of every error at every test point.

    Errors are rows (named), test points columns (numbered 1..N along the diagonals, which
    white lines separate), one heat map per component, two rows of three; the first point of
    each diagonal and the last point are numbered, and every point has a tick (up to 60
    points).  Caption: :data:`FIG04`.

    Parameters
    ----------
    s_tp : array (N, len(comps), 41)
        Indices per test point.
    comps : sequence of str
        The components, one panel each (six).
    names : sequence of str
        The 41 error names.
    diagonal : array of int (N,)
        The diagonal (0-3) of each point, points of one diagonal consecutive.
    vmax : float
        The top of the colour scale.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt  # local: heavy, needed only by the figures

    n_pts = s_tp.shape[0]
    firsts = np.r_[0, np.flatnonzero(np.diff(diagonal)) + 1]   # first point of each diagonal
    numbered = np.unique(np.r_[firsts + 1, n_pts])
    fig, axes = plt.subplots(2, 3, figsize=(13, 14), sharex=True, sharey=True,
                             layout="constrained")
    fig.get_layout_engine().set(wspace=0.05)
    for k, ax in enumerate(axes.flat):
        im = ax.imshow(s_tp[:, k, :].T, aspect="auto", cmap="viridis", vmin=0, vmax=vmax,
                       extent=(0.5, n_pts + 0.5, len(names) - 0.5, -0.5), interpolation="nearest")
        for f in firsts[1:]:
            ax.axvline(f + 0.5, color="w", lw=1.5)
        ax.set_title(comps[k], fontsize=11)
        ax.set_xticks(numbered, [str(t) for t in numbered])
        if n_pts <= 60:   # a tick at every point while they stay apart
            ax.set_xticks(np.arange(1, n_pts + 1), minor=True)
        ax.set_yticks(range(len(names)), names, fontsize=8)
        left, right = k % 3 == 0, k % 3 == 2   # error names beside the outer panels
        ax.tick_params(axis="y", left=left, labelleft=left, right=right, labelright=right)
        ax.tick_params(axis="x", labelbottom=True)
        ax.grid(False)
        ax.set_xlabel("test point (white lines: next diagonal)")
    fig.colorbar(im, ax=axes, orientation="horizontal", shrink=0.5, aspect=40,
                 label="normalised linear total index")
    fig.suptitle("Linear total index of each error at each test point on the four workspace "
                 "diagonals")
    return fig


# --- the chapter's figures, in the book's order ----------------------------------------------

FIGURES = figures(
    FIG04,
    FIG05,
    FIG06,
    Caption("fig07_convergence", "Fig. 7",
            "Convergence of d_xc in Px (a), d_yc in Py (b) and d_za in Pz (c) at Fig. 4 "
            "{where}, with a new seeded design at each size (PCE up to {pce_largest}). MCS and "
            "LHS are shown with the size read as base samples N (solid) and as model runs 43 N "
            "(dashed, from 10 base samples); dotted: the exact index. Bottom: fluctuation R "
            "(Eq. 24) given to the larger size, with the paper's 3 % criterion dashed. R at 1e3 "
            "(the step that ends there) is {r_base} read as base samples and {r_runs} read as "
            "model runs; the paper reports above 10 %."),
    Caption("pce_benchmarks", "Beyond the paper",
            "Sparse PCE on benchmark functions with exact Sobol indices, not the machine model. "
            "(a) Ishigami, n = {n_ishigami}: exact total indices, recovered by a Legendre PCE "
            "(the uniform inputs' basis; largest error {err_legendre:.0e}) but not by a Hermite "
            "PCE after a normal transform (largest error {err_hermite:.2f}). (b) Sobol's G "
            "function in 41 inputs, n = {n_g}, degree at most 3: the first 10 of the 41 total "
            "indices, {n_below} of them below the exact ones (largest error {err_g:.2f}); the "
            "validation error {validation_g:.2f} {warned}. (c) G function in 16 inputs, n = 200: "
            "along the OMP path the corrected leave-one-out error keeps falling (to "
            "{loo_last:.3f} at {terms_last} terms) while the 5-fold validation error is smallest "
            "at {terms_best} terms and then turns up."),
)


class Parameters(NotebookParameters):
    """Notebook 01: Zheng et al. 2024, sparse PCE against MCS and LHS Sobol' indices."""

    stem = "01_zheng2024_pce_sobol_41_errors"
    seed = param.Integer(2024, bounds=(0, None), doc="seed of every random draw")
    position_range_um = param.Number(15.0, bounds=(0.0, 1000.0), inclusive_bounds=(False, True),
                                     doc="translational errors: +/- this range (paper: 15 µm)")
    angular_range_arcsec = param.Number(10.0, bounds=(0.0, 3600.0),
                                        inclusive_bounds=(False, True),
                                        doc="angular errors: +/- this (paper: 10 arcsec)")
    range_in_sigmas = param.Number(3.0, bounds=(0.5, 10.0),
                                   doc="the range is this many sd (not stated in the paper)")
    # its design matrix has n_pce x 13244 entries at degree 3
    n_pce = param.Integer(1000, bounds=(50, 5000), doc="PCE design size (paper: 1000)")
    # degree 4 has 148995 terms: minutes per fit
    pce_degree = param.Integer(3, bounds=(1, 4), doc="total degree of the PCE basis (paper: 3)")
    # 43 N model runs each, streamed in blocks of 131072 base rows (an LHS design, 1.6 kB a row,
    # is held whole)
    n_reference = param.Integer(100000, bounds=(100, 1000000),
                                doc="MCS and LHS base sample size N (paper: 1e5)")
    n_per_diagonal = param.Integer(5, bounds=(2, 50),
                                   doc="test points per workspace diagonal (paper: 5, Fig. 4)")
    search_starts = param.Integer(32, bounds=(1, 2000),
                                  doc="random starts of the Table 2 pose search")
    check_poses = param.Integer(200, bounds=(10, 100000),
                                doc="random poses checking the ratios the model fixes")
    average_starts = param.Integer(6, bounds=(1, 200),
                                   doc="random starts of the two-pose mean search")
    # the sample sizes of Fig. 7 (paper: up to 1e5); the help is short so that the parameters
    # cell's line stays within 100 characters
    convergence_sizes = NumberList([100, 200, 500, 1000, 2000, 5000, 10000, 20000, 50000,
                                    100000], item_type=int, item_bounds=(10, 100000),
                                   doc="Fig. 7")
    # above the paper's 1000, so that R at 1000 exists under both readings of Eq. 24
    pce_convergence_max = param.Integer(2000, bounds=(100, 5000),
                                        doc="largest PCE design in Fig. 7")
    select_degrees = NumberList([1, 2, 3], item_type=int, item_bounds=(1, 3),
                                doc="degrees tried by the corrected-LOO selection")
    select_q_norms = NumberList([0.5, 0.75, 1.0], item_type=float, item_bounds=(0.0, 1.0),
                                item_inclusive=(False, True),
                                doc="q-norms tried by the corrected-LOO selection")
    bench_n_ishigami = param.Integer(300, bounds=(50, 5000),
                                     doc="samples of the Ishigami benchmark")
    bench_max_degree = param.Integer(14, bounds=(1, 20),
                                     doc="highest degree tried on the Ishigami benchmark")
    bench_n_g = param.Integer(1000, bounds=(100, 5000),
                              doc="samples of the 41-input G-function benchmark")
    key_threshold = param.Number(0.05, bounds=(0.0, 1.0), inclusive_bounds=(False, False),
                                 doc="key error: normalised total index above this (paper: 0.05)")
    output_dir = OutputFolder("figures/01_zheng2024_pce_sobol_41_errors",
                              doc="where figures and tables are written")

    def memory_bytes(self) -> float:
        # libraries and figures, then the larger of the Sobol runs (one block of at most 131072
        # base rows: inputs, 41 x 6 outputs and the estimator's temporaries, about 8 kB a row;
        # plus the whole LHS design) and the PCE fits (five copies of the design matrix: 13244
        # columns at degree 3, 11.25 times more at degree 4; the G-function benchmark: three)
        sobol = 8000 * min(max(self.n_reference, 100000), 131072) + 1600 * self.n_reference
        pce = (40 * 13244 * max(self.n_pce, self.pce_convergence_max)
               * max(1.0, 11.25 ** (self.pce_degree - 3)))
        return 4e8 + max(sobol, pce, 24 * 13244 * self.bench_n_g)
