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
about one point compose, so the product equals ``[Rx Ry Rz | delta]`` exactly, which is how it
is evaluated (tests compare it with the literal 41-exponential product and with an independent
homogeneous-transform formulation).  Squareness (convention "moving"): S_xy rotates the X
carriage frame about z on the Y carriage (X is then out of square with Y); S_yz and S_xz rotate
the Z carriage frame about x and y on the X carriage.

Pose error (the paper's Eqs. 11-12 are garbled; Eq. 12 repeats Eq. 11): ``Px, Py, Pz`` is the
tool-tip position error in the workpiece frame (mm); ``Vx, Vy, Vz`` is the error of the
tool-axis direction (unit vector, so rad to first order) in the workpiece frame.  With the tool
along z, an angular error about x reaches Vz through sin A, which is how the paper's Vz key
errors (e_xx, e_xy, e_xz, e_xa, a_AM) arise.

Also here: the exact first-order Jacobian in closed form (:meth:`ACDoubleTurntable.
linear_jacobian`), the 32-element symmetry group of the normalised linear indices
(:func:`pose_orbit`, :func:`canonical_pose`), and the search for the pose behind a table of
published indices with its canonical ranking (:func:`fit_pose_to_indices`,
:func:`rank_poses`), written by hand because the pose is what the paper omits.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .. import errors as _errors
from ..kinematics import homogeneous
from ._base import Machine

AXES = ("x", "y", "z", "A", "C")
TOOL_OFFSETS = ("L",)
TRAVELS = {"x": (-400.0, 400.0), "y": (-425.0, 425.0), "z": (-275.0, 275.0),
           "A": (np.deg2rad(-130.0), np.deg2rad(130.0)), "C": (0.0, 2 * np.pi)}


def _rot_xyz(a, b, c):
    """Rx(a) Ry(b) Rz(c), batched over the shapes of a, b, c (broadcast), -> (..., 3, 3)."""
    a, b, c = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (a, b, c)))
    ca, sa, cb, sb, cc, sc = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(c), np.sin(c)
    r = np.empty(a.shape + (3, 3))
    r[..., 0, 0] = cb * cc
    r[..., 0, 1] = -cb * sc
    r[..., 0, 2] = sb
    r[..., 1, 0] = ca * sc + sa * sb * cc
    r[..., 1, 1] = ca * cc - sa * sb * sc
    r[..., 1, 2] = -sa * cb
    r[..., 2, 0] = sa * sc - ca * sb * cc
    r[..., 2, 1] = sa * cc + ca * sb * sc
    r[..., 2, 2] = ca * cb
    return r


def _compose(p, q):
    """(R1, t1) . (R2, t2) for rigid transforms held as rotation and translation."""
    r1, t1 = p
    r2, t2 = q
    return r1 @ r2, (r1 @ t2[..., None])[..., 0] + t1


def _inverse(p):
    r, t = p
    rt = np.swapaxes(r, -1, -2)
    return rt, -(rt @ t[..., None])[..., 0]


def _translation(v):
    v = np.asarray(v, dtype=float)
    return np.broadcast_to(np.eye(3), v.shape[:-1] + (3, 3)), v


class ACDoubleTurntable(Machine):
    """Zheng et al. 2024's AC double-turntable machine; pose keys x, y, z (mm), A, C (rad),
    optional tool length L (mm)."""

    name = "ac_double_turntable"
    axes = AXES
    tool_offsets = TOOL_OFFSETS
    travels = TRAVELS

    def __init__(self, convention: str = "moving"):
        if convention not in ("moving", "fixed"):
            raise ValueError(f"unknown convention {convention!r}; allowed: moving, fixed")
        self.convention = convention
        self.catalogue = _errors.five_axis_ac_catalogue()
        self._idx = {s: j for j, s in enumerate(self.error_names)}
        self._jacobian_table = _jacobian_table(self._idx)

    # -- building blocks -------------------------------------------------------------------
    def _cols(self, e, names):
        return [e[:, self._idx[s]] for s in names]

    def _motion_error(self, e, axis):
        a = axis.lower()
        dx, dy, dz, ex, ey, ez = self._cols(
            e, [f"d_x{a}", f"d_y{a}", f"d_z{a}", f"e_x{a}", f"e_y{a}", f"e_z{a}"])
        return _rot_xyz(ex, ey, ez), np.stack([dx, dy, dz], axis=-1)

    def _chains(self, e, p, with_errors=True):
        """Tool chain g_bt and workpiece chain g_bw as (R, t); errors may be zero."""
        n = e.shape[0]
        zero = np.zeros(n)
        ideal = {
            "Y": _translation(np.stack([zero, p["y"], zero], -1)),
            "X": _translation(np.stack([p["x"], zero, zero], -1)),
            "Z": _translation(np.stack([zero, zero, p["z"]], -1)),
            "A": (_rot_xyz(p["A"], zero, zero), np.zeros((n, 3))),
            "C": (_rot_xyz(zero, zero, p["C"]), np.zeros((n, 3))),
        }
        tool0 = _translation(np.stack([zero, zero, p["L"]], -1))
        if not with_errors:
            g_bt = _compose(_compose(_compose(ideal["Y"], ideal["X"]), ideal["Z"]), tool0)
            return g_bt, _compose(ideal["A"], ideal["C"])
        c = self._cols
        D = {ax: self._motion_error(e, ax) for ax in "XYZAC"}
        dx, dy, dz, a, b, g = c(e, ["d_xAM", "d_yAM", "d_zAM", "a_AM", "b_AM", "g_AM"])
        loc_a = (_rot_xyz(a, b, g), np.stack([dx, dy, dz], -1))
        dyc, bca = c(e, ["d_yCA", "b_CA"])
        loc_c = (_rot_xyz(zero, bca, zero), np.stack([zero, dyc, zero], -1))
        s_xy, s_yz, s_xz = c(e, ["S_xy", "S_yz", "S_xz"])
        if self.convention == "moving":
            sq_y = (_rot_xyz(zero, zero, s_xy), np.zeros((n, 3)))
            sq_x = (_rot_xyz(s_yz, s_xz, zero), np.zeros((n, 3)))
            t_y = _compose(_compose(ideal["Y"], D["Y"]), sq_y)
            t_x = _compose(_compose(ideal["X"], D["X"]), sq_x)
            t_z = _compose(ideal["Z"], D["Z"])
            t_a = _compose(_compose(ideal["A"], D["A"]), loc_a)
            t_c = _compose(_compose(ideal["C"], D["C"]), loc_c)
        else:  # fixed: locations before the motion, squareness as tilted axis directions
            t_y = _compose(_translation(np.stack([-s_xy * p["y"], p["y"], zero], -1)), D["Y"])
            t_x = _compose(ideal["X"], D["X"])
            t_z = _compose(_translation(np.stack([s_xz * p["z"], -s_yz * p["z"], p["z"]], -1)),
                           D["Z"])
            t_a = _compose(_compose(loc_a, ideal["A"]), D["A"])
            t_c = _compose(_compose(loc_c, ideal["C"]), D["C"])
        g_bt = _compose(_compose(_compose(t_y, t_x), t_z), tool0)
        return g_bt, _compose(t_a, t_c)

    def relative(self, errors, pose: Mapping, with_errors: bool = True):
        """Tool in the workpiece frame, g_wt = g_bw^-1 g_bt, as (R (n,3,3), t (n,3))."""
        e = self.check_errors(errors)
        p = self.check_pose(pose, e.shape[0])
        g_bt, g_bw = self._chains(e, p, with_errors)
        return _compose(_inverse(g_bw), g_bt)

    def transforms(self, errors, pose: Mapping):
        return (homogeneous(*self.relative(errors, pose)),
                homogeneous(*self.relative(errors, pose, with_errors=False)))

    def pose_error(self, errors, pose: Mapping) -> np.ndarray:
        """(n, 6): tool-tip position error Px, Py, Pz (mm) and tool-axis direction error
        Vx, Vy, Vz, both in the workpiece frame.  One pose (scalar values) and the "moving"
        convention take the fast path (:func:`fast_pose_error`); anything else the reference
        evaluation (:meth:`pose_error_reference`)."""
        if self.convention == "moving" and all(np.ndim(v) == 0 for v in pose.values()):
            return fast_pose_error(self, errors, pose)
        return self.pose_error_reference(errors, pose)

    def pose_error_reference(self, errors, pose: Mapping) -> np.ndarray:
        """The same pose error from the straightforward (R, t) product, any pose arrays."""
        ra, ta = self.relative(errors, pose)
        ri, ti = self.relative(errors, pose, with_errors=False)
        return np.concatenate([ta - ti, ra[..., :, 2] - ri[..., :, 2]], axis=-1)

    def linear_jacobian(self, pose: Mapping) -> np.ndarray:
        """The exact first-order Jacobian d(pose error)/d(errors) at zero errors, in closed
        form: (P, 6, 41) for pose arrays of length P ((1, 6, 41) for a scalar pose).

        Convention "moving" only (``convention="fixed"`` falls back to the central
        differences of :meth:`Machine.jacobian`).  Each error block is a small twist
        ``(d, w)`` in the frame after its axis' ideal motion.  A tool-chain block (ideal
        rotation identity, origin ``o``) moves the tool tip by ``d + w x (p_t - o)`` and the
        tool axis by ``w x e_z`` in the base frame, seen in the workpiece frame through
        ``R_bw^T``; a workpiece-chain block, with ``W`` the rest of that chain after it
        (``Rz(C)`` for the A blocks, identity for the C blocks), changes ``g_wt`` by
        ``-W^-1 (d, w)^ W g_wt``.  Unlike differences of the full model (which subtract
        poses of some 100 mm to get effects of some 1e-6 mm, so lose about eight digits on
        the translational entries) every entry is exact to rounding; a test checks it
        against :meth:`Machine.jacobian`.
        """
        if self.convention != "moving":
            return self.jacobian(pose)
        vals = {k: np.atleast_1d(np.asarray(v, dtype=float)) for k, v in pose.items()}
        n = max(v.shape[0] for v in vals.values())
        p = self.check_pose(vals, n)
        zero, one = np.zeros(n), np.ones(n)
        ca, sa, cc, sc = np.cos(p["A"]), np.sin(p["A"]), np.cos(p["C"]), np.sin(p["C"])
        r_a_t = np.stack([one, zero, zero, zero, ca, sa, zero, -sa, ca], -1).reshape(n, 3, 3)
        r_c_t = np.stack([cc, sc, zero, -sc, cc, zero, zero, zero, one], -1).reshape(n, 3, 3)
        r_bw_t = np.einsum("nij,njk->nik", r_c_t, r_a_t)              # base -> workpiece
        # the five frames of _JACOBIAN_TABLE (Y, X, Z carriages, A cradle, C table): rotation
        # into the workpiece frame, tool tip from the frame's origin and tool axis, both in
        # the frame, and the sign (workpiece-chain errors act inversely)
        to_w = np.empty((n, 5, 3, 3))
        to_w[:, :3] = r_bw_t[:, None]
        to_w[:, 3] = r_c_t
        to_w[:, 4] = np.eye(3)
        to_w[:, 3:] *= -1.0
        vec = np.zeros((n, 5, 2, 3))                                   # arm and axis per frame
        tip = np.stack([p["x"], p["y"], p["z"] + p["L"]], -1)          # tool tip, base frame
        vec[:, 0, 0] = tip * [1.0, 0.0, 1.0]
        vec[:, 1, 0, 2] = tip[:, 2]
        vec[:, 2, 0, 2] = p["L"]
        vec[:, :3, 1, 2] = 1.0
        vec[:, 3, 0] = np.einsum("nij,nj->ni", r_a_t, tip)
        vec[:, 3, 1] = r_a_t[:, :, 2]
        vec[:, 4, 0] = np.einsum("nij,nj->ni", r_c_t, vec[:, 3, 0])
        vec[:, 4, 1] = r_bw_t[:, :, 2]
        cols, frame, moves, shift = self._jacobian_table
        # a translation along u moves the tip by u; a rotation about u moves it by u x arm and
        # the axis by u x axis (in the frame)
        local = np.einsum("epqrk,nerk->nepq", moves, vec[:, frame]) + shift  # (n, 41, 2, 3)
        jac = np.empty((n, 6, self.n_errors))
        jac[:, :, cols] = np.einsum("neij,nepj->npie", to_w[:, frame], local).reshape(n, 6, -1)
        return jac


def _six(a, frame):
    return [(f"d_{d}{a}", frame, "t", k) for k, d in enumerate("xyz")] + \
        [(f"e_{d}{a}", frame, "r", k) for k, d in enumerate("xyz")]


def _jacobian_table(idx):
    """For :meth:`ACDoubleTurntable.linear_jacobian`: per error of :data:`_JACOBIAN_TABLE`
    its column, its frame, the linear map ``moves`` (41, 2, 3, 2, 3) from (arm, axis) in the
    frame to the first-order motion of (tip, axis) (a rotation about u: u x arm, u x axis),
    and the constant motion ``shift`` (41, 2, 3) (a translation along u: u, 0)."""
    eps = np.zeros((3, 3, 3))                                          # Levi-Civita
    eps[0, 1, 2] = eps[1, 2, 0] = eps[2, 0, 1] = 1.0
    eps[0, 2, 1] = eps[2, 1, 0] = eps[1, 0, 2] = -1.0
    m = len(_JACOBIAN_TABLE)
    moves, shift = np.zeros((m, 2, 3, 2, 3)), np.zeros((m, 2, 3))
    for e, (_, _, kind, d) in enumerate(_JACOBIAN_TABLE):
        if kind == "r":
            cross = eps[:, d, :]                                       # (u x a)_q = eps_qdk a_k
            moves[e, 0, :, 0, :] = moves[e, 1, :, 1, :] = cross
        else:
            shift[e, 0, d] = 1.0
    return (np.array([idx[t[0]] for t in _JACOBIAN_TABLE]),
            np.array([t[1] for t in _JACOBIAN_TABLE]), moves, shift)


#: Every error as (symbol, frame, translation "t" or rotation "r", direction 0-2): the frames
#: are those after each axis' ideal motion, convention "moving" (0 Y, 1 X, 2 Z carriage of the
#: tool chain, 3 A cradle with the A location errors, 4 C table with the C location errors).
_JACOBIAN_TABLE = (_six("y", 0) + [("S_xy", 0, "r", 2)]
                   + _six("x", 1) + [("S_yz", 1, "r", 0), ("S_xz", 1, "r", 1)]
                   + _six("z", 2)
                   + _six("a", 3) + [("d_xAM", 3, "t", 0), ("d_yAM", 3, "t", 1),
                                     ("d_zAM", 3, "t", 2), ("a_AM", 3, "r", 0),
                                     ("b_AM", 3, "r", 1), ("g_AM", 3, "r", 2)]
                   + _six("c", 4) + [("d_yCA", 4, "t", 1), ("b_CA", 4, "r", 1)])


def diagonal_test_points(n_per_diagonal: int = 5, rotary: str = "sweep") -> dict[str, np.ndarray]:
    """Test points equally spaced on the four body diagonals of the X-Y-Z workspace (Fig. 4).

    Each diagonal runs from one corner of the travel box to the opposite one; ``n_per_diagonal``
    points split it into equal parts, ends included, so every diagonal passes through the
    centre.  The rotary axes are not given by Fig. 4: ``rotary="sweep"`` moves A and C with the
    same fraction of their travel as the linear axes, ``rotary="zero"`` keeps A = C = 0.
    Returns pose arrays and ``diagonal`` (0-3) and ``fraction`` (0..1) per point.
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


def _least_squares_fits(residuals, starts, lo, hi, scale, ftol, xtol, max_nfev) -> list:
    """scipy's ``least_squares`` (trust-region reflective, bounds ``lo``/``hi``) from each
    start, with a central-difference Jacobian (steps ``1e-6 * scale``) evaluated in one batched
    call of ``residuals`` ((B, n) -> (B, m)); BLAS single-threaded (small matrices: threads only
    cost time, and the result is then the same for any thread count).  Returns
    ``[(x, rms misfit, status)]``, one per start."""
    from scipy.optimize import least_squares
    from threadpoolctl import threadpool_limits

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
    """
    import pandas as pd

    from ..sensitivity.sobol import linear_indices

    free = tuple(free)
    fixed = dict(fixed or {})
    if set(free) | set(fixed) != set(AXES) or set(free) & set(fixed):
        raise ValueError(f"free {free} and fixed {tuple(fixed)} must split the axes {AXES}")
    starts = np.atleast_2d(np.asarray(starts, dtype=float))
    if starts.shape[1] != len(free):
        raise ValueError(f"starts must have {len(free)} columns ({free}), got {starts.shape}")
    target = np.asarray(target, dtype=float)
    rows, cols = np.asarray(rows), np.asarray(cols)
    scale = np.array([100.0 if a in "xyz" else 1.0 for a in free])
    lo = np.array([TRAVELS[a][0] if a != "C" else -np.inf for a in free])
    hi = np.array([TRAVELS[a][1] if a != "C" else np.inf for a in free])

    def residuals(v):  # v: (P, len(free)) -> (P, len(target))
        pose = {a: v[:, i] for i, a in enumerate(free)}
        pose.update({a: np.full(v.shape[0], float(fixed[a])) for a in fixed})
        return linear_indices(machine.linear_jacobian(pose), sd)[:, rows, cols] - target

    out = []
    for x, misfit, status in _least_squares_fits(residuals, starts, lo, hi, scale, ftol, xtol,
                                                 max_nfev):
        row = {a: float(fixed[a]) for a in fixed}
        row.update({a: float(x[i]) for i, a in enumerate(free)})
        row["C"] = float(np.mod(row["C"], 2 * np.pi))
        row["misfit"], row["status"] = misfit, status
        out.append({k: row[k] for k in (*AXES, "misfit", "status")})
    return pd.DataFrame(out)


# --------------------------------------------------------------------------------------
# Fast evaluation of the "moving" convention: the same product, applied to the two vectors
# the pose error needs (the tool tip and the tool axis) instead of multiplying 4x4 matrices.
# Every rotation is three elementary rotations of vectors held as structure of arrays (one
# contiguous row per coordinate), so each step is a few elementwise numpy operations over a
# chunk of samples: no stacked small matmul (which numpy hands to BLAS one 4x4 product at a
# time: slow, and rounded differently by each BLAS kernel).  All operations write into one
# workspace allocated per call (not per chunk), so a chunk allocates nothing.  The general
# implementation above is the reference; the tests require both to agree to rounding.
# --------------------------------------------------------------------------------------


class _Workspace:
    """Scratch rows for :func:`fast_pose_error` on chunks of ``k`` samples: the gathered
    errors ``blk`` (41, k), cosines and sines ``c``, ``s`` (23, k; row 22 for the combined
    C + g_AM rotation), the three coordinate rows ``v`` (each (2, k): tip and axis) and two
    rows ``t`` for the rotations."""

    def __init__(self, k: int):
        self.k = k
        self.rows = np.empty((k, 41))
        self.blk = np.empty((41, k))
        self.c, self.s, self.x2 = np.empty((23, k)), np.empty((23, k)), np.empty((22, k))
        self.v = [np.empty((2, k)) for _ in range(3)]
        self.t = [np.empty((2, k)) for _ in range(2)]


def _rot(w, i, j, c, s, inverse=False):
    """The plane rotation of coordinates i, j of ``w.v`` by the angle with cosine c and sine
    s (rows (k,)), in place: v_i' = c v_i - s v_j, v_j' = s v_i + c v_j (``inverse``: the
    transpose).  Rx is (1, 2), Ry (2, 0), Rz (0, 1).  The same products and sums as the
    expressions written out, so the same rounding."""
    vi, vj, t0, t1 = w.v[i], w.v[j], w.t[0], w.t[1]
    np.multiply(vi, s, out=t0)
    np.multiply(vj, s, out=t1)
    vi *= c
    vj *= c
    if inverse:
        vi += t1
        vj -= t0
    else:
        vi -= t1
        vj += t0


def _rxyz(w, k):
    """Rx Ry Rz v, angles k, k+1, k+2 of the workspace's (cos, sin) rows."""
    c, s = w.c, w.s
    _rot(w, 0, 1, c[k + 2], s[k + 2])
    _rot(w, 2, 0, c[k + 1], s[k + 1])
    _rot(w, 1, 2, c[k], s[k])


def _rxyz_t(w, k, last=True):
    """(Rx Ry Rz)^T v = Rz^T Ry^T Rx^T v; ``last=False`` leaves out Rz^T."""
    c, s = w.c, w.s
    _rot(w, 1, 2, c[k], s[k], True)
    _rot(w, 2, 0, c[k + 1], s[k + 1], True)
    if last:
        _rot(w, 0, 1, c[k + 2], s[k + 2], True)


#: angles of the fast path, in the order it reads them (three per rotation block)
_ANGLES = ["e_xz", "e_yz", "e_zz", "S_yz", "S_xz", "S_xy", "e_xx", "e_yx", "e_zx",
           "e_xy", "e_yy", "e_zy", "e_xa", "e_ya", "e_za", "a_AM", "b_AM", "g_AM",
           "e_xc", "e_yc", "e_zc", "b_CA"]
_SHIFTS = {"z": ["d_xz", "d_yz", "d_zz"], "x": ["d_xx", "d_yx", "d_zx"],
           "y": ["d_xy", "d_yy", "d_zy"], "a": ["d_xa", "d_ya", "d_za"],
           "am": ["d_xAM", "d_yAM", "d_zAM"], "c": ["d_xc", "d_yc", "d_zc"]}


def fast_pose_error(machine: ACDoubleTurntable, errors: np.ndarray, pose: Mapping,
                    chunk: int = 4096, out: np.ndarray | None = None) -> np.ndarray:
    """``machine.pose_error`` for one pose (scalar pose values), convention "moving".

    The tool tip (0, 0, L) and the tool axis e_z are carried together (rows of shape (2, k))
    through the tool chain g_bt = I_Y E_Y Sq_Y I_X E_X Sq_X I_Z E_Z (innermost factor
    first), then through the inverse of the workpiece chain g_bw = I_A E_A L_A I_C E_C L_C
    (outermost first): each step a rotation of both, plus a shift of the tip; ``chunk``
    samples at a time (small chunks keep every row in cache), in a workspace allocated once.
    """
    if machine.convention != "moving":
        return machine.pose_error(errors, pose)
    e = machine.check_errors(errors)
    p = machine.check_pose(pose, 1)
    p = {k: float(v[0]) for k, v in p.items()}
    r_i, t_i = machine.relative(np.zeros((1, machine.n_errors)), p, False)
    ideal_t, ideal_v = t_i[0], r_i[0, :, 2]
    n = e.shape[0]
    idx = machine._idx
    shift = {k: [idx[s] for s in v] for k, v in _SHIFTS.items()}
    rows = [idx[s] for s in _ANGLES] + [j for v in shift.values() for j in v] + [idx["d_yCA"]]
    at = {k: 22 + 3 * i for i, k in enumerate(shift)}   # first row of each shift
    ca, sa, cc, sc = np.cos(p["A"]), np.sin(p["A"]), np.cos(p["C"]), np.sin(p["C"])
    res = np.empty((n, 6)) if out is None else out
    work = {}
    for s0 in range(0, n, chunk):
        k = min(chunk, n - s0)
        w = work.get(k) or work.setdefault(k, _Workspace(k))
        blk, c, sn, v = w.blk, w.c, w.s, w.v
        np.take(e[s0:s0 + k], rows, axis=1, out=w.rows, mode="clip")
        blk[...] = w.rows.T                                 # (41, k): angles, then shifts
        blk[11] += blk[5]  # Sq_Y = Rz(S_xy) is followed by Rz(e_zy) of E_Y: one rotation
        _cos_sin(blk[:22], c[:22], sn[:22], w.x2)
        # L_A^-1 ends with Rz(g_AM)^T, followed by I_C^-1 = Rz(C)^T: one rotation by C + g_AM
        t = w.t[0][0]
        np.multiply(c[17], cc, out=c[22])
        np.multiply(sn[17], sc, out=t)
        c[22] -= t
        np.multiply(c[17], sc, out=sn[22])
        np.multiply(sn[17], cc, out=t)
        sn[22] += t

        def shift_tip(key, sign=1, blk=blk, v=v):
            for i in range(3):
                if sign > 0:
                    v[i][0] += blk[at[key] + i]
                else:
                    v[i][0] -= blk[at[key] + i]

        # tool chain, innermost first: E_Z, I_Z, Sq_X, E_X, I_X, Sq_Y with E_Y, I_Y
        v[0].fill(0.0)
        v[1].fill(0.0)
        v[2][0], v[2][1] = p["L"], 1.0
        _rot(w, 2, 0, c[1], sn[1])  # Rz leaves (0, 0, a) alone
        _rot(w, 1, 2, c[0], sn[0])
        shift_tip("z")
        v[2][0] += p["z"]
        _rot(w, 2, 0, c[4], sn[4])
        _rot(w, 1, 2, c[3], sn[3])
        _rxyz(w, 6)
        shift_tip("x")
        v[0][0] += p["x"]
        _rxyz(w, 9)
        shift_tip("y")
        v[1][0] += p["y"]
        # inverse of the workpiece chain: I_A^-1, E_A^-1, L_A^-1, I_C^-1, E_C^-1, L_C^-1
        _rot(w, 1, 2, ca, sa, True)
        shift_tip("a", -1)
        _rxyz_t(w, 12)
        shift_tip("am", -1)
        _rxyz_t(w, 15, last=False)
        _rot(w, 0, 1, c[22], sn[22], True)
        shift_tip("c", -1)
        _rxyz_t(w, 18)
        v[1][0] -= blk[40]
        _rot(w, 2, 0, c[21], sn[21], True)
        for i in range(3):
            np.subtract(v[i][0], ideal_t[i], out=res[s0:s0 + k, i])
            np.subtract(v[i][1], ideal_v[i], out=res[s0:s0 + k, 3 + i])
    return res


def _cos_sin(x, c, s, x2):
    """cos and sin of x into c and s (x2: scratch of x's shape); for |x| < 1e-3 rad (all
    geometric errors) a Taylor polynomial whose truncation error is far below double
    precision, several times faster than numpy's cos and sin: to x^4 and x^5 below 1e-3 rad
    (errors < x^6/720 and x^7/5040), to x^2 and x^3 below 1e-4 rad (errors < x^4/24 < 5e-18
    and x^5/120 < 1e-22, under half an ulp of 1 and of x)."""
    m = max(x.max(initial=0.0), -x.min(initial=0.0))
    if m >= 1e-3:
        np.cos(x, out=c)
        np.sin(x, out=s)
        return
    np.multiply(x, x, out=x2)
    if m < 1e-4:                       # c = 1 - x^2/2, s = x (1 - x^2/6)
        np.multiply(x2, -0.5, out=c)
        c += 1.0
        np.multiply(x2, -1.0 / 6.0, out=s)
        s += 1.0
        s *= x
        return
    # c = 1 - (x^2/2)(1 - x^2/12), s = x (1 - (x^2/6)(1 - x^2/20))
    np.divide(x2, 12.0, out=c)
    np.subtract(1.0, c, out=c)
    np.divide(x2, 20.0, out=s)
    np.subtract(1.0, s, out=s)
    np.multiply(x2, 0.5, out=x2)       # x^2/2 for the cosine
    c *= x2
    np.subtract(1.0, c, out=c)
    np.multiply(x, x, out=x2)          # x^2 anew for the sine's x^2/6 (same rounding as
    np.divide(x2, 6.0, out=x2)         # x * x / 6, not (x^2/2)/3)
    s *= x2
    np.subtract(1.0, s, out=s)
    s *= x


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
    """
    import pandas as pd

    from ..sensitivity.sobol import linear_indices

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
    printed precision of two published values propagates into their ratio."""
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
    and ``status``."""
    import pandas as pd

    from ..sensitivity.sobol import linear_indices

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
    fits = _least_squares_fits(residuals, starts.reshape(len(starts), -1), lo, hi, scale, ftol,
                               xtol, max_nfev)
    for k, (x, misfit, status) in enumerate(fits):
        poses = [canonical_pose(dict(zip(AXES, p, strict=True))) for p in x.reshape(m, 5)]
        poses.sort(key=lambda p: -p["A"])
        out += [dict(start=k, pose=j, **p, misfit=misfit, status=status)
                for j, p in enumerate(poses)]
    return pd.DataFrame(out)
