"""The AC double-turntable five-axis machine of Zheng et al. 2024 (Fig. 1, Table 1, Eqs. 1-12).

Topology: tool chain bed - Y - X - Z - tool, workpiece chain bed - A - C - workpiece; the
machine frame sits at the intersection of the A (about x) and C (about z) axes, and the tool
tip is at the machine origin when x = y = z = 0 (the optional pose value ``L`` adds a tool
length along the tool axis).  Product of exponentials (screw theory, Eqs. 5-9):

    g_bt = T_Y T_X T_Z g_bt(0),    g_bw = T_A T_C,    g_wt = g_bw^-1 g_bt  (Eqs. 7-8)

With the paper's Eq. 9 read literally (it writes the *inverse* of each actual axis motion as
``e^-xi_I e^-xi_D e^-xi_i theta``), each axis transform is ideal motion, then the error motion
(PDGEs), then the location errors (PIGEs), all in the moving frame:

    T_j = exp(xi_j theta_j) . D_j . L_j                     (convention="moving", default)

This ordering is what the published Table 2 needs (e_za, e_zc and g_AM enter identically, as
do e_yc and b_CA).  ``convention="fixed"`` is the textbook alternative: location errors fixed
in the frame before the motion, error motions after it (``T_j = L_j exp(xi_j theta_j) D_j``),
squareness as tilted axis directions.

Each D_j (and L_A) is a product of six unit-twist exponentials, translations along x, y, z
then rotations about x, y, z through the frame origin; translations commute and rotations
about one point compose, so the product equals ``[Rx Ry Rz | delta]`` exactly: the ``euler``
block of the generic chain (:mod:`.chain`), which evaluates this machine from its topology
``w C A b Y X Z t`` and :func:`placements` (tests compare it with the literal 41-exponential
product and with an independent homogeneous-transform formulation).  Squareness (convention
"moving"): S_xy rotates the X carriage frame about z on the Y carriage (X is then out of square
with Y); S_yz and S_xz rotate the Z carriage frame about x and y on the X carriage.

Pose error (the paper's Eqs. 11-12 are garbled; Eq. 12 repeats Eq. 11): ``Px, Py, Pz`` is the
tool-tip position error in the workpiece frame (mm); ``Vx, Vy, Vz`` is the error of the
tool-axis direction (unit vector, so rad to first order) in the workpiece frame.  With the tool
along z, an angular error about x reaches Vz through sin A, which is how the paper's Vz key
errors (e_xx, e_xy, e_xz, e_xa, a_AM) arise.

Also here: the 32-element symmetry group of the normalised linear indices
(:func:`pose_orbit`, :func:`canonical_pose`), and the search for the pose behind a table of
published indices with its canonical ranking (:func:`fit_pose_to_indices`,
:func:`rank_poses`), written by hand because the pose is what the paper omits.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .. import errors as _errors
from .chain import ChainMachine, Placement

AXES = ("x", "y", "z", "A", "C")
TOOL_OFFSETS = ("L",)
TRAVELS = {"x": (-400.0, 400.0), "y": (-425.0, 425.0), "z": (-275.0, 275.0),
           "A": (np.deg2rad(-130.0), np.deg2rad(130.0)), "C": (0.0, 2 * np.pi)}


class ACDoubleTurntable(ChainMachine):
    """Zheng et al. 2024's AC double-turntable machine; pose keys x, y, z (mm), A, C (rad),
    optional tool length L (mm).  A description for :class:`~mtaccuracy.machines.chain.
    ChainMachine` (:data:`TOPOLOGY`, :func:`placements`): the generic chain evaluates it
    (2 M samples/s and more) and gives its closed-form Jacobian (:meth:`linear_jacobian`).

    Parameters
    ----------
    convention : {"moving", "fixed"}
        Where the location errors of A and C enter (:func:`placements`).
    """

    travels = TRAVELS

    def __init__(self, convention: str = "moving"):
        if convention not in ("moving", "fixed"):
            raise ValueError(f"unknown convention {convention!r}; allowed: moving, fixed")
        self.convention = convention
        super().__init__(TOPOLOGY, _errors.five_axis_ac_catalogue(), placements(convention),
                         name="ac_double_turntable", form="euler",
                         tilt="exact" if convention == "moving" else "first_order",
                         tool_offsets=TOOL_OFFSETS, orientation="tool_axis",
                         travels=TRAVELS, axis_names=AXES)
        self._idx = {s: j for j, s in enumerate(self.error_names)}


#: the machine read from the workpiece to the tool (see :mod:`.chain`)
TOPOLOGY = "w C A b Y X Z t"


def placements(convention: str = "moving") -> dict[str, Placement]:
    """Where each of the 41 errors enters the chain :data:`TOPOLOGY`.

    Error motions: the block after each axis' motion.  ``moving`` (the paper's Eq. 9 read
    literally): the location errors of A (``d_xAM ... g_AM``) and of C (``d_yCA``, ``b_CA``)
    are blocks after the motion of A and of C; S_xy turns the X carriage frame on the Y
    carriage (a block after Y's motion), S_yz and S_xz the Z carriage frame on X.
    ``fixed``: the location errors before the motion, the squareness errors as first-order
    tilts of the directions of Y (S_xy) and Z (S_yz, S_xz).

    Parameters
    ----------
    convention : {"moving", "fixed"}
        Where the location errors enter.

    Returns
    -------
    dict of str to Placement
    """
    if convention not in ("moving", "fixed"):
        raise ValueError(f"unknown convention {convention!r}; allowed: moving, fixed")
    pl = {}
    for a in "xyzac":
        for c, d in enumerate("xyz"):
            pl[f"d_{d}{a}"] = Placement(a.upper(), "motion", c)
            pl[f"e_{d}{a}"] = Placement(a.upper(), "motion", 3 + c)
    loc = "post" if convention == "moving" else "pre"
    for c, sym in enumerate(["d_xAM", "d_yAM", "d_zAM", "a_AM", "b_AM", "g_AM"]):
        pl[sym] = Placement("A", loc, c)
    pl["d_yCA"] = Placement("C", loc, 1)
    pl["b_CA"] = Placement("C", loc, 4)
    if convention == "moving":
        pl["S_xy"] = Placement("Y", "post", 5)
        pl["S_yz"] = Placement("X", "post", 3)
        pl["S_xz"] = Placement("X", "post", 4)
    else:
        pl["S_xy"] = Placement("Y", "tilt", 5)
        pl["S_yz"] = Placement("Z", "tilt", 3)
        pl["S_xz"] = Placement("Z", "tilt", 4)
    return pl


def diagonal_test_points(n_per_diagonal: int = 5, rotary: str = "sweep") -> dict[str, np.ndarray]:
    """Test points equally spaced on the four body diagonals of the X-Y-Z workspace (Fig. 4).

    Each diagonal runs from one corner of the travel box to the opposite one; ``n_per_diagonal``
    points split it into equal parts, ends included, so every diagonal passes through the
    centre.  The rotary axes are not given by Fig. 4: ``rotary="sweep"`` moves A and C with the
    same fraction of their travel as the linear axes, ``rotary="zero"`` keeps A = C = 0.
    Returns pose arrays and ``diagonal`` (0-3) and ``fraction`` (0..1) per point.

    Parameters
    ----------
    n_per_diagonal : int
        Points per diagonal, ends included.
    rotary : {"sweep", "zero"}
        The rule for A and C.

    Returns
    -------
    dict of str to array
        x, y, z (mm), A, C (rad), ``diagonal``, ``fraction``.
    """
    if n_per_diagonal < 2:
        raise ValueError(f"n_per_diagonal must be >= 2, got {n_per_diagonal}")
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
    """Every pose with the same normalised linear indices as ``pose`` (x, y, z in mm, A, C in
    rad): arrays with a leading axis over the group elements (32, or 4 with
    ``fixed_position``), in the order of :data:`POSE_SYMMETRIES`.

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
    """Criteria of the canonical member, each to be maximised in turn: x, y, z >= 0, then
    |A| <= 90 deg, C in [0, 180) deg (then the sign of A and C = 0 over 180 deg, which
    matter only on the boundaries)."""
    return np.stack([x, y, z, np.cos(a), np.sin(c), np.cos(c), np.sin(a)], axis=-1)


def canonical_pose(pose: Mapping, fixed_position: bool = False, pos_tol: float = 1e-2,
                   ang_tol: float = 1e-4) -> dict[str, float]:
    """The canonical member of the orbit of ``pose`` (:func:`pose_orbit`): the one with the
    largest x, then y, then z, then cos A, sin C, cos C, sin A, where values within
    ``pos_tol`` (mm) or ``ang_tol`` (on the cosines and sines) count as equal, so that a
    coordinate that is zero up to rounding does not decide.  For a generic pose this is the
    member with x, y, z >= 0, -90 < A <= 90 deg and 0 <= C < 180 deg, which always lies inside
    the travels (they are symmetric in x, y, z and contain that A range).

    Parameters
    ----------
    pose : mapping
        x, y, z (mm), A, C (rad).
    fixed_position : bool
        Only the symmetries that keep x, y, z.
    pos_tol, ang_tol : float
        Tolerances (mm; on cosines and sines).

    Returns
    -------
    dict of str to float
    """
    orbit = pose_orbit(pose, fixed_position)
    if orbit["x"].ndim != 1:
        raise ValueError("canonical_pose takes one pose (scalar values)")
    keys = _canonical_key(*(orbit[k] for k in AXES))
    tol = np.array([pos_tol] * 3 + [ang_tol] * 4)
    from ..sensitivity.screening import rank_with_ties
    best = rank_with_ties(np.zeros(len(keys)), -keys, key_tol=tol)[0]
    return {k: float(orbit[k][best]) for k in AXES}


def rank_poses(candidates, misfit: str = "misfit", rtol: float = 1e-6,
               fixed_position: bool = False, pos_tol: float = 1e-2, ang_tol: float = 1e-4):
    """The canonical ranking of the poses an optimiser returned (one row per start).

    ``candidates``: a DataFrame with columns x, y, z (mm), A, C (rad) and ``misfit``.  Each
    pose is mapped to its canonical member (:func:`canonical_pose`); candidates whose
    canonical poses agree within ``pos_tol`` (mm) and ``ang_tol`` (rad) are one minimum
    (the one with the smallest misfit stands for it; ``n_starts`` counts them); minima are
    ranked by misfit, misfits within ``rtol`` (relative) of the best remaining one being
    ties, broken by the canonical pose (largest x, y, z first, then smallest A, C; see
    :func:`~mtaccuracy.sensitivity.rank_with_ties`).  Returns one row per minimum, best
    first, with x, y, z, A, C, ``misfit`` and ``n_starts``: which pose comes first depends
    neither on the order of the starts nor on rounding noise.

    Parameters
    ----------
    candidates : DataFrame
        x, y, z (mm), A, C (rad) and the misfit column.
    misfit : str
        Name of the misfit column.
    rtol : float
        Relative tie window of misfits.
    fixed_position : bool
        Only the symmetries that keep x, y, z.
    pos_tol, ang_tol : float
        One minimum within these (mm, rad).

    Returns
    -------
    DataFrame
        One row per minimum, best first.
    """
    import pandas as pd

    from ..sensitivity.screening import rank_with_ties

    df = pd.DataFrame(candidates)
    missing = [c for c in (*AXES, misfit) if c not in df.columns]
    if missing:
        raise ValueError(f"candidates lack column(s) {missing}")
    if df.empty:
        raise ValueError("no candidates to rank")
    canon = pd.DataFrame([canonical_pose(r, fixed_position, pos_tol, ang_tol)
                          for r in df[list(AXES)].to_dict("records")])
    canon[misfit] = df[misfit].to_numpy(dtype=float)
    order = rank_with_ties(canon[misfit].to_numpy(), rtol=0.0)
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
    ranked = rank_with_ties(minima[misfit].to_numpy(), keys, rtol=rtol, key_tol=tol)
    return minima.iloc[ranked].reset_index(drop=True)


def fit_pose_to_indices(machine: ACDoubleTurntable, sd, target, rows, cols, starts,
                        free=AXES, fixed: Mapping | None = None, ftol: float = 1e-15,
                        xtol: float = 1e-15, max_nfev: int = 500):
    """Least-squares fits of the pose whose normalised linear indices
    (:func:`~mtaccuracy.sensitivity.linear_indices` of :meth:`ACDoubleTurntable.linear_jacobian`)
    best match ``target`` at the (component, error) pairs ``rows``, ``cols``.

    ``starts`` (m, len(free)): start values of the ``free`` axes (mm, rad); ``fixed`` gives
    the other axes.  x, y, z and A stay within their travels, C is free (periodic).  scipy's
    ``least_squares`` (trust-region reflective) with a central-difference Jacobian evaluated
    in one batched call, run until the relative change of the cost falls below ``ftol`` or
    of the step below ``xtol``.  Returns a DataFrame, one row per start: x, y, z, A, C,
    ``misfit`` (RMS of the residuals) and the optimiser's ``status``.  BLAS runs
    single-threaded (small matrices: threads only cost time, and the result is then the same
    for any thread count).

    Parameters
    ----------
    machine : ACDoubleTurntable
    sd : array (41,)
        Error standard deviations (mm, rad).
    target : array (m,)
        The published indices.
    rows, cols : arrays of int (m,)
        Their (component, error) entries.
    starts : array (s, len(free))
        Start values of the free axes.
    free : sequence of str
        The axes fitted.
    fixed : mapping, optional
        The other axes' values.
    ftol, xtol : float
        Stopping rules.
    max_nfev : int
        Evaluations per start.

    Returns
    -------
    DataFrame (s, 7)
        x, y, z, A, C, misfit, status.
    """
    from ..sensitivity.linear import linear_indices
    from ..sensitivity.posefit import fit_pose

    free = tuple(free)
    fixed = dict(fixed or {})
    if set(free) | set(fixed) != set(AXES) or set(free) & set(fixed):
        raise ValueError(f"free {free} and fixed {tuple(fixed)} must split the axes {AXES}")
    bounds = (np.array([TRAVELS[a][0] if a != "C" else -np.inf for a in free]),
              np.array([TRAVELS[a][1] if a != "C" else np.inf for a in free]))
    fits = fit_pose(lambda pose: linear_indices(machine.linear_jacobian(pose), sd), target,
                    (rows, cols), starts, free, fixed=fixed, bounds=bounds,
                    scale=np.array([100.0 if a in "xyz" else 1.0 for a in free]),
                    ftol=ftol, xtol=xtol, max_nfev=max_nfev)
    for a in fixed:
        fits[a] = float(fixed[a])
    fits["C"] = np.mod(fits["C"].to_numpy(dtype=float), 2 * np.pi)
    return fits[[*AXES, "misfit", "status"]]


# --------------------------------------------------------------------------------------
# Necessary conditions on a table of indices: ratios the model fixes at every pose
# --------------------------------------------------------------------------------------

def index_invariants(machine: ACDoubleTurntable, sd, rows, cols, poses: Mapping,
                     rtol: float = 1e-9):
    """Ratios of normalised linear indices that the model fixes at every pose.

    ``rows``, ``cols``: the (component, error) entries of a table (e.g. Table 2); ``poses``:
    pose arrays (many random poses).  The normalised linear index is
    ``S_ki = J_ki^2 sd_i^2 / V_k``, so

    - within a component, two errors whose Jacobian entries stay proportional at every pose
      (the same structure: e.g. translations along one direction of one moving frame) have
      ``S_ki / S_kj`` fixed by their variance ratio, whatever the pose: they form a *group*;
    - across components, a ratio of two groups in component k and one in component l can be
      the same function of the pose (e.g. ``sin^2 A`` in Vx and in Vy), so their quotient is
      fixed too (``V_k``, ``V_l`` cancel).

    Returns ``(groups, cross)``: ``groups`` a DataFrame, one row per entry, with ``group``
    (an integer; entries of one group share a component) and ``factor``, the fixed ratio
    ``S_entry / S_head`` (head: the group's first entry); ``cross`` a DataFrame with the
    groups ``num_k, den_k, num_l, den_l`` and ``value``, the fixed quotient
    ``(S_num_k / S_den_k) / (S_num_l / S_den_l)`` of the heads.  A ratio counts as fixed when
    its largest relative spread over ``poses`` is below ``rtol``; entries whose index is zero
    at some pose are left alone (no ratio).

    Parameters
    ----------
    machine : ACDoubleTurntable
    sd : array (41,)
        Error standard deviations.
    rows, cols : arrays of int (m,)
        The table's (component, error) entries.
    poses : mapping
        Pose arrays (many random poses).
    rtol : float
        Ratios constant within it count as fixed.

    Returns
    -------
    groups, cross : DataFrame
    """
    import pandas as pd

    from ..sensitivity.linear import linear_indices

    rows, cols = np.asarray(rows), np.asarray(cols)
    s = linear_indices(machine.linear_jacobian(poses), sd)[:, rows, cols]   # (P, entries)
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


def ratio_interval(num_lo, num_hi, den_lo, den_hi):
    """The interval of ``num / den`` for positive intervals (interval arithmetic): how the
    printed precision of two published values propagates into their ratio.

    Parameters
    ----------
    num_lo, num_hi, den_lo, den_hi : float
        Positive intervals.

    Returns
    -------
    lo, hi : float
    """
    if np.any(np.asarray(den_lo) <= 0) or np.any(np.asarray(num_lo) < 0):
        raise ValueError("ratio_interval needs positive intervals")
    return np.asarray(num_lo) / np.asarray(den_hi), np.asarray(num_hi) / np.asarray(den_lo)


def fit_pose_average_to_indices(machine: ACDoubleTurntable, sd, target, rows, cols, starts,
                                ftol: float = 1e-12, xtol: float = 1e-12,
                                max_nfev: int = 300):
    """Least-squares fits of ``m`` poses whose *mean* normalised linear indices best match
    ``target`` (the hypothesis that a table reports indices averaged over several poses,
    equal weights).  ``starts`` (s, m, 5): x, y, z (mm), A, C (rad) of each pose.  As
    :func:`fit_pose_to_indices` otherwise (x, y, z, A within their travels, batched
    central-difference Jacobian, single-threaded BLAS).  Each fitted pose is reported as its
    canonical image (:func:`canonical_pose`), the poses of one fit ordered by decreasing A
    (the mean does not depend on their order).  Returns a DataFrame, one row per start and
    pose: ``start``, ``pose`` (0..m-1), x, y, z, A, C, ``misfit`` (RMS over the entries)
    and ``status``.

    Parameters
    ----------
    machine : ACDoubleTurntable
    sd : array (41,)
        Error standard deviations (mm, rad).
    target : array (m,)
        The published indices.
    rows, cols : arrays of int (m,)
        Their (component, error) entries.
    starts : array (s, poses, 5)
        Start poses.
    ftol, xtol : float
        Stopping rules.
    max_nfev : int
        Evaluations per start.

    Returns
    -------
    DataFrame
        One row per start and pose.
    """
    import pandas as pd

    from ..sensitivity.linear import linear_indices
    from ..sensitivity.posefit import least_squares_starts

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
        s = linear_indices(machine.linear_jacobian(pose), sd)[:, rows, cols]
        return s.reshape(v.shape[0], m, -1).mean(axis=1) - target

    out = []
    fits = least_squares_starts(residuals, starts.reshape(len(starts), -1), lo, hi, scale, ftol,
                                xtol, max_nfev)
    for k, (x, misfit, status) in enumerate(fits):
        poses = [canonical_pose(dict(zip(AXES, p, strict=True))) for p in x.reshape(m, 5)]
        poses.sort(key=lambda p: -p["A"])
        out += [dict(start=k, pose=j, **p, misfit=misfit, status=status)
                for j, p in enumerate(poses)]
    return pd.DataFrame(out)
