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
# Fast evaluation of the "moving" convention: the same product, regrouped so that per-sample
# work is a handful of 4x4 products into preallocated buffers (the leading sample axis is
# processed in cache-sized chunks).  The general implementation above is the reference; the
# tests require both to agree to rounding.
# --------------------------------------------------------------------------------------

_ANGLES = ["e_xy", "e_yy", "e_zy", "S_xy", "e_xx", "e_yx", "e_zx", "S_yz", "S_xz",
           "e_xz", "e_yz", "e_zz", "e_xa", "e_ya", "e_za", "a_AM", "b_AM", "g_AM",
           "e_xc", "e_yc", "e_zc", "b_CA"]


def _fill_rot_xyz(out, ca, sa, cb, sb, cc, sc):
    """Write Rx Ry Rz into out[..., :3, :3] from cosines and sines."""
    out[:, 0, 0] = cb * cc
    out[:, 0, 1] = -cb * sc
    out[:, 0, 2] = sb
    out[:, 1, 0] = ca * sc + sa * sb * cc
    out[:, 1, 1] = ca * cc - sa * sb * sc
    out[:, 1, 2] = -sa * cb
    out[:, 2, 0] = sa * sc - ca * sb * cc
    out[:, 2, 1] = sa * cc + ca * sb * sc
    out[:, 2, 2] = ca * cb


def fast_pose_error(machine: ACDoubleTurntable, errors: np.ndarray, pose: Mapping,
                    chunk: int = 2048, out: np.ndarray | None = None) -> np.ndarray:
    """``machine.pose_error`` for one pose (scalar pose values), convention "moving".

    g_bt = I_Y E_Y I_X E_X Sq I_Z E_Z and g_bw = I_A E_A L_A I_C E_C L_C are built with 4x4
    products into preallocated buffers, ``chunk`` samples at a time (small chunks keep every
    temporary in cache); the pose error needs only R_bw^T (t_bt - t_bw) and R_bw^T R_bt e_z.
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
    ang = [idx[s] for s in _ANGLES]
    lin = {a: [idx[f"d_x{a}"], idx[f"d_y{a}"], idx[f"d_z{a}"]] for a in "xyzac"}
    am = [idx["d_xAM"], idx["d_yAM"], idx["d_zAM"]]
    i_a = homogeneous(_rot_xyz(p["A"], 0.0, 0.0), np.zeros(3))
    i_c = homogeneous(_rot_xyz(0.0, 0.0, p["C"]), np.zeros(3))
    res = np.empty((n, 6)) if out is None else out
    m = min(chunk, n)
    buf = {k: np.zeros((m, 4, 4)) for k in ("ey", "ex", "sq", "ez", "ea", "la", "ec", "lc",
                                            "w1", "w2", "bt")}
    for k in buf:
        buf[k][:, 3, 3] = 1.0
    one, zero = np.ones(m), np.zeros(m)
    for s in range(0, n, chunk):
        k = min(chunk, n - s)
        blk = e[s:s + k]
        th = blk[:, ang]
        th[:, 2] += th[:, 3]  # S_xy rotates the X frame about z on Y: adds to e_zy
        c, sn = _cos_sin(th)
        b = {name: v[:k] for name, v in buf.items()}
        o, z0 = one[:k], zero[:k]
        _fill_rot_xyz(b["ey"], c[:, 0], sn[:, 0], c[:, 1], sn[:, 1], c[:, 2], sn[:, 2])
        b["ey"][:, :3, 3] = blk[:, lin["y"]]
        b["ey"][:, 1, 3] += p["y"]  # I_Y . E_Y (a translation along y)
        _fill_rot_xyz(b["ex"], c[:, 4], sn[:, 4], c[:, 5], sn[:, 5], c[:, 6], sn[:, 6])
        b["ex"][:, :3, 3] = blk[:, lin["x"]]
        _fill_rot_xyz(b["sq"], c[:, 7], sn[:, 7], c[:, 8], sn[:, 8], o, z0)
        _fill_rot_xyz(b["ez"], c[:, 9], sn[:, 9], c[:, 10], sn[:, 10], c[:, 11], sn[:, 11])
        b["ez"][:, :3, 3] = blk[:, lin["z"]]
        _fill_rot_xyz(b["ea"], c[:, 12], sn[:, 12], c[:, 13], sn[:, 13], c[:, 14], sn[:, 14])
        b["ea"][:, :3, 3] = blk[:, lin["a"]]
        _fill_rot_xyz(b["la"], c[:, 15], sn[:, 15], c[:, 16], sn[:, 16], c[:, 17], sn[:, 17])
        b["la"][:, :3, 3] = blk[:, am]
        _fill_rot_xyz(b["ec"], c[:, 18], sn[:, 18], c[:, 19], sn[:, 19], c[:, 20], sn[:, 20])
        b["ec"][:, :3, 3] = blk[:, lin["c"]]
        _fill_rot_xyz(b["lc"], o, z0, c[:, 21], sn[:, 21], o, z0)
        b["lc"][:, 1, 3] = blk[:, idx["d_yCA"]]
        w1, w2, bt = b["w1"], b["w2"], b["bt"]
        # tool side g_bt = (I_Y E_Y) (I_X E_X Sq I_Z E_Z), tool length along the tool axis
        np.matmul(b["ex"], b["sq"], out=w1)
        w1[:, :3, 3] += p["z"] * w1[:, :3, 2]  # . I_Z (a translation along z)
        np.matmul(w1, b["ez"], out=w2)
        w2[:, 0, 3] += p["x"]  # I_X . (a translation along x)
        np.matmul(b["ey"], w2, out=bt)
        # workpiece side g_bw = I_A (E_A L_A) I_C (E_C L_C)
        np.matmul(b["ea"], b["la"], out=w1)
        np.matmul(i_a, w1, out=w2)
        np.matmul(w2, i_c, out=w1)
        np.matmul(b["ec"], b["lc"], out=w2)
        np.matmul(w1, w2, out=b["ea"])
        r = b["ea"][:, :3, :3]
        d = bt[:, :3, 3] + p["L"] * bt[:, :3, 2] - b["ea"][:, :3, 3]
        v = bt[:, :3, 2]
        for i in range(3):  # R_bw^T d and R_bw^T v
            res[s:s + k, i] = (r[:, 0, i] * d[:, 0] + r[:, 1, i] * d[:, 1]
                               + r[:, 2, i] * d[:, 2] - ideal_t[i])
            res[s:s + k, 3 + i] = (r[:, 0, i] * v[:, 0] + r[:, 1, i] * v[:, 1]
                                   + r[:, 2, i] * v[:, 2] - ideal_v[i])
    return res


def _cos_sin(x):
    """cos and sin; for |x| < 1e-3 rad (all geometric errors) a Taylor polynomial whose
    truncation error (< x^6/720 and x^7/5040) is far below double precision, 5x faster than
    numpy's cos and sin."""
    if np.abs(x).max(initial=0.0) >= 1e-3:
        return np.cos(x), np.sin(x)
    x2 = x * x
    return 1.0 - 0.5 * x2 * (1.0 - x2 / 12.0), x * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0))
