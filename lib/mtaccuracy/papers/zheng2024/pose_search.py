"""The pose behind Table 2: the symmetries of the linear indices and the least-squares search.

Zheng et al. 2024 print Sobol' indices (Table 2) at a pose they do not state; this module
searches for it, written by hand for this paper:

- the 32-element symmetry group of the normalised linear indices (:func:`pose_orbit`,
  :func:`canonical_pose`) and the canonical ranking of an optimiser's minima
  (:func:`rank_poses`), so that which pose is reported depends neither on the order of the
  starts nor on rounding;
- the least-squares search for the pose behind a table of published indices
  (:func:`fit_pose_to_indices`) and for two poses whose mean indices give it
  (:func:`fit_pose_average_to_indices`).

The method is :mod:`mtaccuracy.sensitivity.posefit` (shared with notebook 03), the indices
:mod:`mtaccuracy.sensitivity.linear`, the machine :mod:`mtaccuracy.machines.ac_double_turntable`.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pandas as pd

from ... import sensitivity as S
from ...machines.ac_double_turntable import AXES, TRAVELS, ACDoubleTurntable

__all__ = ["POSE_SYMMETRIES", "pose_orbit", "canonical_pose", "rank_poses",
           "fit_pose_to_indices", "fit_pose_average_to_indices"]


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
