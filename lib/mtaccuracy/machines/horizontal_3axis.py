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
from ..kinematics import chain, hat, homogeneous, rotation_exp, screw_exp, translation
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


def _inverse(g: np.ndarray) -> np.ndarray:
    """Inverse of (..., 4, 4) transforms (general: the first-order matrices are not rigid)."""
    return np.linalg.inv(g)


class Horizontal3Axis(Machine):
    """Rong et al.'s three-axis horizontal machining centre, 21 errors, screw theory.

    ``layout``: ``"W/T"``, the workpiece-side then the tool-side axes from the bed outwards
    (default ``"z/xy"``: Z table; X column with Y headstock; see :data:`LAYOUTS`).
    ``exact``: exact exponentials (default) or the first-order matrices ``I + xi^``.
    Errors: the 21 of :func:`mtaccuracy.errors.three_axis_catalogue` (18 error motions and 3
    squareness errors, ISO 230-1 codes), columns in that order, mm and rad.
    Pose: ``x, y, z`` (relative tool-to-workpiece coordinates, mm) and optional tool offsets
    ``tool_x, tool_y, tool_z`` (mm, the tool tip relative to the carriages' reference point).
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
        """Actual unit directions (n, 3) of the three axes, tilted by the squareness errors."""
        n = e.shape[0]
        zero = np.zeros(n)
        s_xy, s_yz, s_xz = (e[:, self._sq[s]] for s in ("S_xy", "S_yz", "S_xz"))
        rot_y = np.stack([zero, zero, s_xy], axis=-1)
        rot_z = np.stack([s_yz, s_xz, zero], axis=-1)
        if self.exact:
            d_y = rotation_exp(rot_y) @ _UNIT[1]
            d_z = rotation_exp(rot_z) @ _UNIT[2]
        else:
            d_y = _UNIT[1] + np.cross(rot_y, _UNIT[1])
            d_z = _UNIT[2] + np.cross(rot_z, _UNIT[2])
        return {"x": np.broadcast_to(_UNIT[0], (n, 3)), "y": d_y, "z": d_z}

    def _work_tool(self, e: np.ndarray, p: Mapping[str, np.ndarray]) -> np.ndarray:
        d = self._directions(e)

        def carriage(axis: str, sign: float) -> tuple[np.ndarray, np.ndarray]:
            # exp of the prismatic twist (0, d) times q: a translation by q d (twist_exp with a
            # zero axis gives the same matrix; building it directly halves the run time)
            motion = translation(d[axis] * (sign * p[axis])[:, None])
            err = error_twist_exp(e[:, self._eps[axis]], e[:, self._delta[axis]], self.exact)
            return motion, err

        tool = [g for a in self.tool_axes for g in carriage(a, +1.0)]
        tool.append(translation(np.stack([p[k] for k in TOOL_OFFSETS], axis=-1)))
        g_tool = chain(*tool)
        if not self.workpiece_axes:
            return g_tool
        g_work = chain(*[g for a in self.workpiece_axes for g in carriage(a, -1.0)])
        return _inverse(g_work) @ g_tool

    def transforms(self, errors, pose: Mapping) -> tuple[np.ndarray, np.ndarray]:
        e = self.check_errors(errors)
        n = e.shape[0]
        p = self.check_pose(pose, n)
        stacked = np.stack([p[k] for k in self.axes + self.tool_offsets])
        if n > 1 and np.all(stacked == stacked[:, :1]):  # one pose for every sample
            one = {k: v[:1] for k, v in p.items()}
            ideal = np.broadcast_to(self._work_tool(np.zeros((1, self.n_errors)), one),
                                    (n, 4, 4))
        else:
            ideal = self._work_tool(np.zeros_like(e), p)
        return self._work_tool(e, p), ideal

    def position_error(self, errors, pose: Mapping) -> np.ndarray:
        """(n, 3) tool-tip position error ``Ex, Ey, Ez`` (mm) in the workpiece frame."""
        return self.pose_error(errors, pose)[:, :3]

    def first_order_coefficients(self, pose: Mapping, h: float = 1e-6) -> np.ndarray:
        """First-order coefficients (6, 21) of the pose error at one pose (central
        differences of the full model with steps ``h`` mm or rad): column j is d(pose
        error)/d(error j), so a translational error has coefficients of order 1 and an angular
        error its Abbe arm in mm."""
        single = {k: np.atleast_1d(np.asarray(v, dtype=float)) for k, v in pose.items()}
        if any(v.shape != (1,) for v in single.values()):
            raise ValueError("first_order_coefficients takes one pose (scalars)")
        return self.jacobian(pose, step=h)[0]


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
    the full model (about 1e-4 of the error here).
    """
    b = np.asarray(bounds, dtype=float)
    if b.shape != (2, machine.n_errors) or np.any(b[1] <= b[0]):
        raise ValueError(f"bounds must be (2, {machine.n_errors}) with high > low")
    mean, var = b.mean(0), (b[1] - b[0]) ** 2 / 12.0
    base = dict(pose or {})
    box = dict(pose_bounds or {})
    unknown = [k for k in box if k not in machine.axes + machine.tool_offsets]
    if unknown:
        raise ValueError(f"unknown pose name(s) {unknown}")
    missing = [a for a in machine.axes if a not in base and a not in box]
    if missing:
        raise ValueError(f"pose lacks axis value(s) {missing}")
    nodes = 0.5 + np.array([-1.0, 1.0]) / (2.0 * np.sqrt(3.0))  # Gauss-Legendre on [0, 1]
    keys = list(box)
    coeffs = []
    for corner in np.array(np.meshgrid(*[nodes] * len(keys), indexing="ij")).reshape(
            len(keys), -1).T if keys else [()]:
        p = dict(base)
        for k, u in zip(keys, corner, strict=True):
            lo, hi = box[k]
            p[k] = lo + u * (hi - lo)
        coeffs.append(machine.first_order_coefficients(p)[:components])      # (q, 21)
    c = np.array(coeffs)                                      # (P, q, 21), equal weights
    ec, ec2 = c.mean(0), (c**2).mean(0)
    mean_part = c @ mean                                      # (P, q)
    v = (ec2 * var).sum(-1) + mean_part.var(0)                # (q,)
    return (ec**2 * var / v[:, None]).T, (ec2 * var / v[:, None]).T
