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
The chain itself is the generic one (:mod:`.chain`, the topology of the layout and the
placement of :func:`mtaccuracy.machines.vertical_xyfz.placements` with S_xz = +EB0Z); this
module holds the layouts, the conventions and the paper's helpers.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .. import errors as _errors
from ..kinematics import hat, homogeneous, screw_exp
from .chain import ChainMachine
from .vertical_xyfz import placements

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


def parse_layout(layout: str) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """Split ``"W/T"`` into the workpiece-side and tool-side axes, each from the bed outwards.

    Raises ValueError unless x, y and z each appear exactly once and there is exactly one '/'.

    Parameters
    ----------
    layout : str

    Returns
    -------
    work, tool : tuple of str
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


def topology(layout: str) -> str:
    """The chain topology (:mod:`.chain`) of a layout: ``"z/xy"`` -> ``"w Z b X Y t"``.

    Parameters
    ----------
    layout : str

    Returns
    -------
    str
    """
    work, tool = parse_layout(layout)
    return " ".join(["w", *(a.upper() for a in reversed(work)), "b",
                     *(a.upper() for a in tool), "t"])


def error_twist_exp(eps: np.ndarray, delta: np.ndarray, exact: bool = True) -> np.ndarray:
    """``exp`` of the error twist (eps, delta): (..., 3) each -> (..., 4, 4).

    ``exact=False`` gives the first-order matrix ``I + xi^`` (``[[I + [eps]x, delta], [0, 1]]``).
    The exact form is ``[[exp([eps]x), V delta], [0, 1]]`` with
    ``V = I + (1 - cos t)/t^2 [eps]x + (t - sin t)/t^3 [eps]x^2``, ``t = |eps|``.

    Parameters
    ----------
    eps : array (..., 3)
        Angular errors (rad).
    delta : array (..., 3)
        Translational errors (mm).
    exact : bool
        Exact exponential or first order.

    Returns
    -------
    array (..., 4, 4)
    """
    if not exact:
        return homogeneous(np.eye(3) + hat(np.asarray(eps, dtype=float)), delta)
    return screw_exp(eps, delta)


class Horizontal3Axis(ChainMachine):
    """Rong et al.'s three-axis horizontal machining centre, 21 errors, screw theory.

    ``layout``: ``"W/T"``, the workpiece-side then the tool-side axes from the bed outwards
    (default ``"z/xy"``: Z table; X column with Y headstock; see :data:`LAYOUTS`).
    ``exact``: exact exponentials (default) or the first-order matrices ``I + xi^``.
    Errors: the 21 of :func:`mtaccuracy.errors.three_axis_catalogue` (18 error motions and 3
    squareness errors, ISO 230-1 codes), columns in that order, mm and rad.
    Pose: ``x, y, z`` (relative tool-to-workpiece coordinates, mm) and optional tool offsets
    ``tool_x, tool_y, tool_z`` (mm, the tool tip relative to the carriages' reference point).

    A description for :class:`~mtaccuracy.machines.chain.ChainMachine`: the topology of the
    layout (``z/xy`` is ``w Z b X Y t``), error motions as screw exponentials in the block
    after each motion (``screw``; ``exact=False``: ``first_order``), squareness as tilted
    directions (exact or first-order), rotation-vector output.
    ``tests/test_horizontal_3axis.py`` checks it against the 4x4 product of the twist
    exponentials.

    Parameters
    ----------
    layout : str
        ``"W/T"`` axes (:data:`LAYOUTS`).
    exact : bool
        Exact exponentials or first-order matrices.
    """

    def __init__(self, layout: str = DEFAULT_LAYOUT, exact: bool = True):
        self.workpiece_axes, self.tool_axes = parse_layout(layout)
        self.layout = f"{''.join(self.workpiece_axes)}/{''.join(self.tool_axes)}"
        self.exact = bool(exact)
        super().__init__(topology(self.layout), _errors.three_axis_catalogue(),
                         placements(s_xz_sign=1.0), name="horizontal_3axis",
                         form="screw" if self.exact else "first_order",
                         tilt="exact" if self.exact else "first_order",
                         tool_offsets=TOOL_OFFSETS, orientation="rotation_vector",
                         axis_names=AXES)

    def describe(self) -> str:
        """One line: which axes carry the workpiece and which the tool.

        Returns
        -------
        str
            E.g. ``layout 'z/xy': workpiece <- Z <- bed -> X -> Y -> spindle -> tool``,
            followed by the layout's description when it is one of :data:`LAYOUTS`.
        """
        known = LAYOUTS.get(self.layout)
        work = " <- ".join(a.upper() for a in reversed(self.workpiece_axes)) or "(fixed)"
        tool = " -> ".join(a.upper() for a in self.tool_axes) or "(fixed)"
        text = f"layout {self.layout!r}: workpiece <- {work} <- bed -> {tool} -> spindle -> tool"
        return text + (f" ({known})" if known else "")

    def position_error(self, errors, pose: Mapping) -> np.ndarray:
        """The tool-tip position error in the workpiece frame.

        Parameters
        ----------
        errors : (n, 21) array
            Error values in mm and rad, columns in the order of
            :func:`mtaccuracy.errors.three_axis_catalogue`.
        pose : mapping of str to float or (n,) array
            ``x, y, z`` (mm) and optional tool offsets ``tool_x, tool_y, tool_z`` (mm).

        Returns
        -------
        (n, 3) ndarray
            ``Ex, Ey, Ez``, mm: the first three columns of :meth:`pose_error`.
        """
        return self.pose_error(errors, pose)[:, :3]

    def first_order_jacobian(self, pose: Mapping) -> np.ndarray:
        """Exact first-order coefficients of the pose error, (P, 6, 21), at P poses (pose
        values scalars or (P,) arrays), in closed form (no finite differences, so
        exchangeable errors get bitwise-equal coefficients): the generic chain's
        :meth:`~mtaccuracy.machines.chain.ChainMachine.linear_jacobian`.

        At zero errors every carriage frame is a pure translation, so the error twist
        ``(eps_k, delta_k)`` of a tool-side axis moves the tip by ``eps_k x s_k + delta_k``,
        with ``s_k`` the tip relative to that carriage, and tilts the tool by ``eps_k``; a
        workpiece-side axis contributes ``-(eps_k x r_k + delta_k)`` and ``-eps_k``.  A
        squareness error tilts an axis direction, which moves the tip by the travel times
        the tilt: ``S_xy -> (-y, 0, 0)``, ``S_yz -> (0, -z, 0)``, ``S_xz -> (z, 0, 0)`` on
        either side (x, y, z are relative coordinates).

        Parameters
        ----------
        pose : mapping of str to float or (P,) array
            ``x, y, z`` (mm) and optional tool offsets (mm) of P poses.

        Returns
        -------
        (P, 6, 21) ndarray
            d(pose error)/d(error) at zero errors: dimensionless for translational errors,
            mm per rad (position rows) for angular ones.

        Raises
        ------
        ValueError
            If a pose value is not a scalar or a 1-d array.
        """
        vals = {k: np.atleast_1d(np.asarray(v, dtype=float)) for k, v in pose.items()}
        if any(v.ndim != 1 for v in vals.values()):
            raise ValueError("pose values must be scalars or 1-d arrays")
        return self.linear_jacobian(vals)

    def first_order_coefficients(self, pose: Mapping) -> np.ndarray:
        """First-order coefficients (6, 21) of the pose error at one pose (exact, see
        :meth:`first_order_jacobian`): column j is d(pose error)/d(error j), so a
        translational error has coefficients of order 1 and an angular error its Abbe arm in
        mm.

        Parameters
        ----------
        pose : mapping of str to float
            ``x, y, z`` (mm) and optional tool offsets (mm), one pose (scalars).

        Returns
        -------
        (6, 21) ndarray
            d(pose error)/d(error j) in column j.

        Raises
        ------
        ValueError
            If a pose value is not a scalar.
        """
        single = {k: np.atleast_1d(np.asarray(v, dtype=float)) for k, v in pose.items()}
        if any(v.shape != (1,) for v in single.values()):
            raise ValueError("first_order_coefficients takes one pose (scalars)")
        return self.first_order_jacobian(single)[0]


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

    Parameters
    ----------
    machine : Horizontal3Axis
    bounds : array (2, 21)
        Uniform error ranges (mm, rad).
    pose : mapping, optional
        Fixed pose coordinates (mm).
    pose_bounds : mapping, optional
        Pose name -> (low, high) uniform.
    components : int
        Output rows kept.

    Returns
    -------
    s1, st : arrays (21, components)
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
    T x 2^k quadrature poses.

    Parameters
    ----------
    machine : Horizontal3Axis
    bounds : array (2, 21)
        Uniform error ranges (mm, rad).
    poses : mapping, optional
        Pose name -> scalar or (T,) array (mm).
    pose_bounds : mapping, optional
        Pose name -> (low, high) uniform.
    components : int
        Output rows kept.

    Returns
    -------
    s1, st : arrays (T, 21, components)
    variance : array (T, components)
    """
    from ..sensitivity import linear as _linear

    mean, var = _linear.uniform_moments(bounds, machine.n_errors)
    return _linear.pose_box_indices(machine.first_order_jacobian, mean, var, poses, pose_bounds,
                                    components, nodes=2,
                                    names=machine.axes + machine.tool_offsets,
                                    required=machine.axes)


def tool_length_offsets(tool_lengths, base=(0.0, 0.0, 0.0)) -> dict[str, np.ndarray]:
    """Tool offsets (``tool_x, tool_y, tool_z``, (T,) arrays, mm) of tools of the given
    lengths (mm, >= 0) on the horizontal spindle: the tip sits ``length`` mm from the
    carriages' reference point towards the workpiece, i.e. along -z (ISO 841: +z points from
    the workpiece to the tool), on top of the ``base`` offsets.

    Parameters
    ----------
    tool_lengths : array (T,)
        Tool lengths (mm, >= 0).
    base : sequence of 3 floats
        Offsets added (mm).

    Returns
    -------
    dict of str to array (T,)
    """
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
    A component with no variance at a pose gets zeros.

    Parameters
    ----------
    machine : Horizontal3Axis
    bounds : array (2, 21)
        Uniform error ranges (mm, rad).
    poses : mapping
        Pose name -> scalar or (P,) array (mm).
    components : int
        Output rows kept.

    Returns
    -------
    array (P, 21, components)
    """
    from ..sensitivity import linear as _linear

    _, var = _linear.uniform_moments(bounds, machine.n_errors)
    return _linear.indices_at_poses(machine.first_order_jacobian(poses)[:, :components], var)


def errors_and_pose_model(machine: Horizontal3Axis, tool: Mapping):
    """The model of Rong et al.'s Sobol' study: errors and tool-tip position as inputs.

    Parameters
    ----------
    machine : Horizontal3Axis
        The machine (D errors).
    tool : mapping
        Tool offsets ``{name: value}`` (mm), the same for every run.

    Returns
    -------
    callable
        ``model(X)``: ``X`` (m, D + 3), the D errors (mm, rad) then the pose x, y, z (mm), to
        the tool-tip position error ``Ex, Ey, Ez`` (m, 3) in mm.
    """
    d = machine.n_errors

    def model(x):
        return machine.position_error(x[:, :d], dict(x=x[:, d], y=x[:, d + 1], z=x[:, d + 2],
                                                     **tool))
    return model


def errors_at_poses_model(machine: Horizontal3Axis, poses_xyz, tool: Mapping):
    """The model of the errors alone, each row at its own pose (the poses of a design kept).

    Parameters
    ----------
    machine : Horizontal3Axis
        The machine (D errors).
    poses_xyz : array (m, 3)
        The pose x, y, z (mm) of each row.
    tool : mapping
        Tool offsets (mm).

    Returns
    -------
    callable
        ``model(E)``: errors ``E`` (m, D) to ``Ex, Ey, Ez`` (m, 3) in mm.
    """
    full = errors_and_pose_model(machine, tool)
    poses_xyz = np.asarray(poses_xyz, dtype=float)

    def model(e):
        return full(np.c_[e, poses_xyz])
    return model
