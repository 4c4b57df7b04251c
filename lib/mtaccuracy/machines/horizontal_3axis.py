"""The three-axis horizontal machining centre of Rong et al. (21 errors, screw theory).

The paper models a three-axis horizontal machining centre with the product of exponentials
(screw theory), every error expressed in the machine coordinate system (MCS), and takes the
tool-tip position error in the workpiece frame as the output (its Eqs. 1-4).  Its Fig. 1 (the
topology) and its Eqs. 1-4 are lost from the text, so the layout is a constructor parameter.

Layout
------
``layout="W/T"`` names the axes that carry the workpiece (``W``) and the spindle (``T``), each
listed from the bed outwards.  The default ``"z/xy"`` is the common moving-column horizontal
machining centre (inverted-T bed, e.g. the Makino a-series): the workpiece sits on the Z table,
which moves along the spindle axis; the tool side is the X column carrying the Y headstock and the
horizontal spindle.  Other layouts: ``"x/zy"`` (T-bed: table along X, column along Z, headstock
along Y), ``"zx/y"`` (cross table: Z saddle then X table, fixed column with Y headstock), ``"/xyz"``
(all axes on the tool side), ...  Any split of x, y, z into two ordered groups is accepted.

Kinematics (product of exponentials, all twists in the MCS at the home configuration)
------------------------------------------------------------------------------------------
Each prismatic axis k has the nominal twist ``xi_k = (0, d_k)`` with the unit direction ``d_k``
and the joint value ``q_k``; its six error motions form the error twist ``(eps_k, delta_k)``
(angular ``ex(k), ey(k), ez(k)`` in rad, translational ``dx(k), dy(k), dz(k)`` in mm) expressed
in the MCS at the home configuration, i.e. at the carriage's reference point, which coincides with
the MCS origin when every axis is at 0.  A carriage moves as ``exp(xi_k q_k) exp(xi_err_k)``
(nominal motion, then its error motion), so the chains are

    g_bed_tool = prod_{k in T} exp(xi_k q_k) exp(xi_err_k) . T(tool offsets)
    g_bed_work = prod_{k in W} exp(-xi_k q_k) exp(xi_err_k)
    g_work_tool = g_bed_work^-1 g_bed_tool

and the pose error is ``g_work_tool(errors) - g_work_tool(0)`` (position part: Ex, Ey, Ez in the
workpiece frame).  Conventions, stated because the paper's are lost:

* ``x, y, z`` are the commanded *relative* tool-to-workpiece coordinates (ISO 841): an axis on the
  workpiece side moves its table by ``-q`` so that the tool moves by ``+q`` relative to the part.
  The ideal tool position in the workpiece frame is therefore ``(x, y, z) + tool offsets`` for
  every layout, and a layout change alters only how the errors reach the tool tip.
* The MCS origin is the tool tip at the home position (all axes at 0, tool offsets 0): it is the
  reference point of every carriage, so the Abbe arm of an angular error is the vector from that
  carriage's reference point to the tool tip.  ``tool_x, tool_y, tool_z`` (mm, pose entries) move
  the tool tip away from the reference point (a tool length along -z, say).
* The workpiece frame is carried by the last workpiece-side carriage (or is the MCS if no axis
  carries the workpiece).  Where its origin sits on the table does not matter: it cancels exactly
  in ``actual - ideal``.
* Squareness errors tilt the axis directions (the paper's Eq. 3, a screw on the axis):
  X is the reference, ``d_y = Rz(S_xy) e_y`` and ``d_z = R(S_yz e_x + S_xz e_y) e_z``, i.e. to
  first order ``d_y = (-S_xy, 1, 0)`` and ``d_z = (S_xz, -S_yz, 1)`` with the ISO 230-1 codes
  EC0Y, EA0Z, EB0Z (a positive angle is a positive rotation about the named axis).
* Error motions are those of the moving carriage in the MCS, so an error of a workpiece-side
  axis reaches the tool tip with the opposite sign (the table moves, not the tool).

``exact=True`` (default) uses the exact exponentials; ``exact=False`` the first-order matrices
``I + xi^`` that screw-theory papers print (they differ at second order, ~1e-8 of the error).
This module is hand-written because the error model is the paper's own contribution.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .. import errors as _errors
from ..kinematics import hat, homogeneous, matmul3, matvec3, screw_exp, translation, vee
from ._base import Machine

AXES = ("x", "y", "z")
TOOL_OFFSETS = ("tool_x", "tool_y", "tool_z")
DEFAULT_LAYOUT = "z/xy"
#: Named layouts for readers; any "W/T" split of x, y, z is accepted as well.
LAYOUTS = {
    "z/xy": "workpiece on the Z table; X column carrying the Y headstock (moving column, "
            "inverted-T bed)",
    "x/zy": "workpiece on the X table; Z column carrying the Y headstock (T-bed)",
    "zx/y": "workpiece on the X table riding on the Z saddle; fixed column with the Y headstock",
    "xz/y": "workpiece on the Z table riding on the X saddle; fixed column with the Y headstock",
}
_UNIT = np.eye(3)


def parse_layout(layout: str) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """Split ``"W/T"`` into the workpiece-side and tool-side axes, each from the bed outwards.

    Raises ValueError unless x, y and z each appear exactly once and there is exactly one '/'.
    """
    if not isinstance(layout, str):
        raise TypeError(f"layout must be a string like {DEFAULT_LAYOUT!r}, got {layout!r}")
    text = layout.strip().lower()
    if text.count("/") != 1:
        raise ValueError(f"layout {layout!r} must be 'W/T' with one '/': the axes carrying the "
                         f"workpiece, then those carrying the tool (e.g. {DEFAULT_LAYOUT!r}); "
                         f"named layouts: {', '.join(LAYOUTS)}")
    work, tool = (tuple(s) for s in text.split("/"))
    letters = work + tool
    if sorted(letters) != sorted(AXES):
        raise ValueError(f"layout {layout!r} must use each of x, y, z exactly once "
                         f"(got {''.join(letters) or 'nothing'}); e.g. {DEFAULT_LAYOUT!r}")
    return work, tool


def error_twist_exp(eps: np.ndarray, delta: np.ndarray, exact: bool = True) -> np.ndarray:
    """``exp`` of the error twist (eps, delta): (..., 3) each -> (..., 4, 4).

    ``exact=False`` gives the first-order matrix ``I + xi^`` (``[[I + [eps]x, delta], [0, 1]]``).
    The exact form is ``[[exp([eps]x), V delta], [0, 1]]`` with
    ``V = I + (1 - cos t)/t^2 [eps]x + (t - sin t)/t^3 [eps]x^2``, ``t = |eps|``.
    """
    if not exact:
        return homogeneous(np.eye(3) + hat(np.asarray(eps, dtype=float)), delta)
    return screw_exp(eps, delta)


#: Below this angle (rad) the coefficients of the exponential are evaluated by their Taylor
#: series (error < t^8 / 9! < 1e-29), above it by sin and cos.  The machine's error motions
#: (1e-4 rad) all take the series, which is plain arithmetic: no dependence on how a CPU's
#: vectorised sin and cos round.
_SERIES_BELOW = 1e-3


def _exp_coefficients(t2: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``a = sin t / t``, ``b = (1 - cos t) / t^2``, ``c = (t - sin t) / t^3`` of ``t2 = t^2``."""
    a = 1.0 - t2 / 6.0 * (1.0 - t2 / 20.0 * (1.0 - t2 / 42.0))
    b = 0.5 - t2 / 24.0 * (1.0 - t2 / 30.0 * (1.0 - t2 / 56.0))
    c = 1.0 / 6.0 - t2 / 120.0 * (1.0 - t2 / 42.0 * (1.0 - t2 / 72.0))
    large = t2 >= _SERIES_BELOW**2
    if np.any(large):
        t = np.sqrt(t2[large])
        s, co = np.sin(t), np.cos(t)
        a[large], b[large], c[large] = s / t, (1.0 - co) / t2[large], (t - s) / (t2[large] * t)
    return a, b, c


def _error_motion(eps: np.ndarray, delta: np.ndarray, exact: bool
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Rotation (n, 3, 3) and translation (n, 3) of :func:`error_twist_exp`, built without
    4x4 matrices: ``R = (1 - b t^2) I + a [eps]x + b eps eps^T`` (Rodrigues, with
    ``[eps]x^2 = eps eps^T - t^2 I``) and ``u = delta + b eps x delta + c eps x (eps x delta)``."""
    if not exact:
        return np.eye(3) + hat(eps), delta
    t2 = eps[:, 0] ** 2 + eps[:, 1] ** 2 + eps[:, 2] ** 2
    a, b, c = _exp_coefficients(t2)
    rot = a[:, None, None] * hat(eps) + b[:, None, None] * (eps[:, :, None] * eps[:, None, :])
    rot += (1.0 - b * t2)[:, None, None] * np.eye(3)
    exd = np.cross(eps, delta)
    return rot, delta + b[:, None] * exd + c[:, None] * np.cross(eps, exd)


def _transpose(r: np.ndarray) -> np.ndarray:
    return np.swapaxes(r, -1, -2)


class Horizontal3Axis(Machine):
    """Rong et al.'s three-axis horizontal machining centre, 21 errors, screw theory.

    ``layout``: ``"W/T"``, the workpiece-side then the tool-side axes from the bed outwards
    (default ``"z/xy"``: Z table; X column with Y headstock; see :data:`LAYOUTS`).
    ``exact``: exact exponentials (default) or the first-order matrices ``I + xi^``.
    Errors: the 21 of :func:`mtaccuracy.errors.three_axis_catalogue` (18 error motions and 3
    squareness errors, ISO 230-1 codes), columns in that order, mm and rad.
    Pose: ``x, y, z`` (relative tool-to-workpiece coordinates, mm) and optional tool offsets
    ``tool_x, tool_y, tool_z`` (mm, the tool tip relative to the carriages' reference point).

    The chains are composed as rotation-translation pairs ``(R, t)`` (a 4x4 product with a pure
    translation is a vector sum), with every 3x3 product written out in a fixed order: no BLAS
    call, so the result does not depend on the BLAS kernel of the machine, and about three
    times faster than the 4x4 products.  ``tests/test_horizontal_3axis.py`` checks it against
    the 4x4 product of the twist exponentials.
    """

    name = "horizontal_3axis"
    axes = AXES
    tool_offsets = TOOL_OFFSETS

    def __init__(self, layout: str = DEFAULT_LAYOUT, exact: bool = True):
        self.workpiece_axes, self.tool_axes = parse_layout(layout)
        self.layout = f"{''.join(self.workpiece_axes)}/{''.join(self.tool_axes)}"
        self.exact = bool(exact)
        self.catalogue = _errors.three_axis_catalogue()
        idx = {s: j for j, s in enumerate(self.error_names)}
        self._delta = {a: [idx[f"d{d}({a})"] for d in AXES] for a in AXES}
        self._eps = {a: [idx[f"e{d}({a})"] for d in AXES] for a in AXES}
        self._sq = {s: idx[s] for s in ("S_xy", "S_yz", "S_xz")}

    def describe(self) -> str:
        """One line: which axes carry the workpiece and which the tool."""
        known = LAYOUTS.get(self.layout)
        work = " <- ".join(a.upper() for a in reversed(self.workpiece_axes)) or "(fixed)"
        tool = " -> ".join(a.upper() for a in self.tool_axes) or "(fixed)"
        text = f"layout {self.layout!r}: workpiece <- {work} <- bed -> {tool} -> spindle -> tool"
        return text + (f" ({known})" if known else "")

    def _directions(self, e: np.ndarray) -> dict[str, np.ndarray]:
        """Actual directions (n, 3) of the three axes, tilted by the squareness errors:
        ``d_y = Rz(S_xy) e_y``, ``d_z = exp([S_yz, S_xz, 0]x) e_z`` (exact), or their
        first-order forms ``e + rot x e``."""
        n = e.shape[0]
        zero = np.zeros(n)
        s_xy, s_yz, s_xz = (e[:, self._sq[s]] for s in ("S_xy", "S_yz", "S_xz"))
        if self.exact:
            t2 = s_yz**2 + s_xz**2
            a, b, _ = _exp_coefficients(t2)
            a_y, b_y, _ = _exp_coefficients(s_xy**2)
            d_y = np.stack([-a_y * s_xy, 1.0 - b_y * s_xy**2, zero], axis=-1)
            d_z = np.stack([a * s_xz, -a * s_yz, 1.0 - b * t2], axis=-1)
        else:
            d_y = np.stack([-s_xy, np.ones(n), zero], axis=-1)
            d_z = np.stack([s_xz, -s_yz, np.ones(n)], axis=-1)
        return {"x": np.broadcast_to(_UNIT[0], (n, 3)), "y": d_y, "z": d_z}

    def _side(self, axes, sign: float, e, d, p, tip=None) -> tuple[np.ndarray, np.ndarray]:
        """``(R, t)`` of prod_k exp(sign xi_k q_k) exp(xi_err_k) [T(tip)] over ``axes``."""
        rot, t = None, None
        for a in axes:
            step = d[a] * (sign * p[a])[:, None]
            t = step if t is None else t + matvec3(rot, step)
            r_e, u_e = _error_motion(e[:, self._eps[a]], e[:, self._delta[a]], self.exact)
            if rot is None:
                rot, t = r_e, t + u_e
            else:
                rot, t = matmul3(rot, r_e), t + matvec3(rot, u_e)
        n = e.shape[0]
        if rot is None:
            rot, t = np.broadcast_to(np.eye(3), (n, 3, 3)), np.zeros((n, 3))
        if tip is not None:
            t = t + matvec3(rot, tip)
        return rot, t

    def _work_tool_rt(self, e: np.ndarray, p: Mapping[str, np.ndarray]
                      ) -> tuple[np.ndarray, np.ndarray]:
        """``(R, t)`` of ``g_work_tool = g_bed_work^-1 g_bed_tool``, (n, 3, 3) and (n, 3)."""
        d = self._directions(e)
        tip = np.stack([p[k] for k in TOOL_OFFSETS], axis=-1)
        r_t, t_t = self._side(self.tool_axes, +1.0, e, d, p, tip)
        if not self.workpiece_axes:
            return r_t, t_t
        r_w, t_w = self._side(self.workpiece_axes, -1.0, e, d, p)
        # inverse of (R_w, t_w): R_w^T for the exact (rigid) motions; the first-order matrices
        # I + [eps]x are not rotations, so they take a general inverse
        inv = _transpose(r_w) if self.exact else np.linalg.inv(r_w)
        return matmul3(inv, r_t), matvec3(inv, t_t - t_w)

    def _ideal_position(self, p: Mapping[str, np.ndarray]) -> np.ndarray:
        """The error-free tool tip in the workpiece frame: ``(x, y, z) + tool offsets`` for
        every layout (the rotation is the identity)."""
        return np.stack([p[a] + p[k] for a, k in zip(AXES, TOOL_OFFSETS, strict=True)], axis=-1)

    def transforms(self, errors, pose: Mapping) -> tuple[np.ndarray, np.ndarray]:
        e = self.check_errors(errors)
        p = self.check_pose(pose, e.shape[0])
        rot, t = self._work_tool_rt(e, p)
        ideal = translation(self._ideal_position(p))
        return homogeneous(rot, t), ideal

    def pose_error(self, errors, pose: Mapping) -> np.ndarray:
        """(n, 6) pose error ``Px, Py, Pz`` (mm), ``Vx, Vy, Vz`` (rad) of the tool in the
        workpiece frame, actual minus ideal (the ideal frame is a pure translation, so the
        rotation part is ``vee(R)``)."""
        e = self.check_errors(errors)
        p = self.check_pose(pose, e.shape[0])
        rot, t = self._work_tool_rt(e, p)
        return np.concatenate([t - self._ideal_position(p), vee(rot)], axis=-1)

    def position_error(self, errors, pose: Mapping) -> np.ndarray:
        """(n, 3) tool-tip position error ``Ex, Ey, Ez`` (mm) in the workpiece frame."""
        e = self.check_errors(errors)
        p = self.check_pose(pose, e.shape[0])
        return self._work_tool_rt(e, p)[1] - self._ideal_position(p)

    def first_order_jacobian(self, pose: Mapping) -> np.ndarray:
        """Exact first-order coefficients of the pose error, (P, 6, 21), at P poses (pose
        values scalars or (P,) arrays), derived in closed form (no finite differences, so
        exchangeable errors get bitwise-equal coefficients).

        At zero errors every carriage frame is a pure translation, so the error twist
        ``(eps_k, delta_k)`` of a tool-side axis moves the tip by ``eps_k x s_k + delta_k``,
        with ``s_k`` the tip relative to that carriage (the later tool-side travels plus the
        tool offset), and tilts the tool by ``eps_k``; a workpiece-side axis contributes
        ``-(eps_k x r_k + delta_k)`` and ``-eps_k``, with ``r_k`` the tip relative to that
        table (the tool-side travels, the tool offset and the travels of this and the inner
        workpiece-side axes).  A squareness error tilts an axis direction, which moves the tip
        by the travel times the tilt: ``S_xy -> (-y, 0, 0)``, ``S_yz -> (0, -z, 0)``,
        ``S_xz -> (z, 0, 0)`` on either side (x, y, z are relative coordinates).
        """
        vals = {k: np.atleast_1d(np.asarray(v, dtype=float)) for k, v in pose.items()}
        if any(v.ndim != 1 for v in vals.values()):
            raise ValueError("pose values must be scalars or 1-d arrays")
        n_poses = max((v.shape[0] for v in vals.values()), default=1)
        p = self.check_pose(vals, n_poses)
        unit = np.eye(3)
        travel = {a: unit[AXES.index(a)] * p[a][:, None] for a in AXES}      # (P, 3)
        tip = np.stack([p[k] for k in TOOL_OFFSETS], axis=-1)
        jac = np.zeros((n_poses, 6, self.n_errors))

        def put(axis, arm, sign):
            for c in range(3):
                jac[:, c, self._delta[axis][c]] = sign
                jac[:, :3, self._eps[axis][c]] = sign * np.cross(unit[c], arm)
                jac[:, 3 + c, self._eps[axis][c]] = sign

        tool = list(self.tool_axes)
        for k, a in enumerate(tool):
            put(a, tip + sum((travel[b] for b in tool[k + 1:]), np.zeros((n_poses, 3))), 1.0)
        tip_bed = tip + sum((travel[b] for b in tool), np.zeros((n_poses, 3)))
        work = list(self.workpiece_axes)
        for k, a in enumerate(work):
            put(a, tip_bed + sum((travel[b] for b in work[:k + 1]), np.zeros((n_poses, 3))),
                -1.0)
        jac[:, 0, self._sq["S_xy"]] = -p["y"]
        jac[:, 1, self._sq["S_yz"]] = -p["z"]
        jac[:, 0, self._sq["S_xz"]] = p["z"]
        return jac + 0.0  # no negative zeros (a table side's -(eps x r) gives -0.0)

    def first_order_coefficients(self, pose: Mapping) -> np.ndarray:
        """First-order coefficients (6, 21) of the pose error at one pose (exact, see
        :meth:`first_order_jacobian`): column j is d(pose error)/d(error j), so a
        translational error has coefficients of order 1 and an angular error its Abbe arm in
        mm."""
        single = {k: np.atleast_1d(np.asarray(v, dtype=float)) for k, v in pose.items()}
        if any(v.shape != (1,) for v in single.values()):
            raise ValueError("first_order_coefficients takes one pose (scalars)")
        return self.first_order_jacobian(single)[0]


def _linear_parts(machine: Horizontal3Axis, bounds, components: int):
    b = np.asarray(bounds, dtype=float)
    if b.shape != (2, machine.n_errors) or np.any(b[1] <= b[0]):
        raise ValueError(f"bounds must be (2, {machine.n_errors}) with high > low")
    return b.mean(0), (b[1] - b[0]) ** 2 / 12.0


def linear_sobol_indices(machine: Horizontal3Axis, bounds, pose: Mapping | None = None,
                         pose_bounds: Mapping | None = None, components: int = 3
                         ) -> tuple[np.ndarray, np.ndarray]:
    """Exact Sobol indices (S1, ST), each (21, components), of the *first-order* model.

    Errors are independent uniforms on ``bounds`` (2, 21).  Either one ``pose`` (a mapping of
    scalars; then S1 = ST), or ``pose_bounds`` mapping some pose names to ``(low, high)``: those
    coordinates are uniform in the box (the others fixed by ``pose``) and independent of the
    errors.  The first-order coefficients are affine in the pose, so the pose expectations of
    their squares are exact with 2-point Gauss-Legendre quadrature per coordinate.  This is the
    reference the Monte Carlo (Saltelli) estimates converge to, up to the second-order terms of
    the full model (about 1e-4 of the error here).  Errors that enter identically (same
    coefficients, same range) get bitwise-equal indices.  One case of
    :func:`linear_sobol_indices_batch`.
    """
    base = {k: np.atleast_1d(np.asarray(v, dtype=float)) for k, v in (pose or {}).items()}
    if any(v.shape != (1,) for v in base.values()):
        raise ValueError("linear_sobol_indices takes one pose (scalars); "
                         "use linear_sobol_indices_batch for many")
    s1, st, _ = linear_sobol_indices_batch(machine, bounds, base, pose_bounds, components)
    return s1[0], st[0]


def linear_sobol_indices_batch(machine: Horizontal3Axis, bounds, poses: Mapping | None = None,
                               pose_bounds: Mapping | None = None, components: int = 3
                               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`linear_sobol_indices` for T cases at once: ``poses`` maps pose names to scalars
    or (T,) arrays (e.g. T tool lengths), ``pose_bounds`` as there (the same box for every
    case).  Returns ``S1`` and ``ST`` (T, 21, components) and the output variance ``V``
    (T, components) in mm^2 (pooled over the box), all from one batched Jacobian over the
    T x 2^k quadrature poses."""
    mean, var = _linear_parts(machine, bounds, components)
    base = {k: np.atleast_1d(np.asarray(v, dtype=float)) for k, v in (poses or {}).items()}
    if any(v.ndim != 1 for v in base.values()):
        raise ValueError("pose values must be scalars or 1-d arrays")
    sizes = {v.shape[0] for v in base.values()} - {1}
    if len(sizes) > 1:
        raise ValueError(f"pose arrays of different lengths {sorted(sizes)}")
    n_cases = sizes.pop() if sizes else 1
    box = dict(pose_bounds or {})
    unknown = [k for k in [*box, *base] if k not in machine.axes + machine.tool_offsets]
    if unknown:
        raise ValueError(f"unknown pose name(s) {unknown}")
    missing = [a for a in machine.axes if a not in base and a not in box]
    if missing:
        raise ValueError(f"pose lacks axis value(s) {missing}")
    nodes = 0.5 + np.array([-1.0, 1.0]) / (2.0 * np.sqrt(3.0))  # Gauss-Legendre on [0, 1]
    keys = list(box)
    grid = (np.array(np.meshgrid(*[nodes] * len(keys), indexing="ij")).reshape(len(keys), -1)
            if keys else np.zeros((0, 1)))
    n_nodes = grid.shape[1]
    flat = {k: np.repeat(np.broadcast_to(v, (n_cases,)), n_nodes) for k, v in base.items()}
    for k, u in zip(keys, grid, strict=True):
        lo, hi = box[k]
        flat[k] = np.tile(lo + u * (hi - lo), n_cases)
    c = machine.first_order_jacobian(flat)[:, :components]     # (T * G, q, 21)
    c = c.reshape(n_cases, n_nodes, *c.shape[1:])              # (T, G, q, 21), equal weights
    ec, ec2 = c.mean(1), (c**2).mean(1)                        # (T, q, 21)
    mean_part = (c * mean).sum(-1)                             # (T, G, q)
    v = (ec2 * var).sum(-1) + mean_part.var(1)                 # (T, q)
    s1 = np.swapaxes(ec**2 * var / v[..., None], 1, 2)
    st = np.swapaxes(ec2 * var / v[..., None], 1, 2)
    return s1, st, v


def tool_length_offsets(tool_lengths, base=(0.0, 0.0, 0.0)) -> dict[str, np.ndarray]:
    """Tool offsets (``tool_x, tool_y, tool_z``, (T,) arrays, mm) of tools of the given
    lengths (mm, >= 0) on the horizontal spindle: the tip sits ``length`` mm from the
    carriages' reference point towards the workpiece, i.e. along -z (ISO 841: +z points from
    the workpiece to the tool), on top of the ``base`` offsets."""
    lengths = np.atleast_1d(np.asarray(tool_lengths, dtype=float))
    if lengths.ndim != 1 or np.any(lengths < 0) or not np.all(np.isfinite(lengths)):
        raise ValueError(f"tool lengths must be finite and >= 0, got {tool_lengths!r}")
    bx, by, bz = (float(v) for v in base)
    return {"tool_x": np.full(lengths.shape, bx), "tool_y": np.full(lengths.shape, by),
            "tool_z": bz - lengths}


def linear_indices_at_poses(machine: Horizontal3Axis, bounds, poses: Mapping,
                            components: int = 3) -> np.ndarray:
    """Exact Sobol indices (S1 = ST) of the first-order model at each of P fixed poses:
    (P, 21, components).  ``poses`` maps pose names to scalars or (P,) arrays.  The same
    numbers as :func:`linear_sobol_indices` with ``pose=`` one at a time, in one batched call.
    A component with no variance at a pose gets zeros."""
    _, var = _linear_parts(machine, bounds, components)
    c = machine.first_order_jacobian(poses)[:, :components]   # (P, q, 21)
    v = c**2 * var
    tot = v.sum(-1, keepdims=True)
    s = np.divide(v, tot, out=np.zeros_like(v), where=tot > 0)
    return np.swapaxes(s, 1, 2)
