"""The three-axis horizontal machining centre of Rong et al. (21 errors, screw theory).

The paper models a three-axis horizontal machining centre with the product of exponentials
(screw theory), every error expressed in the machine coordinate system (MCS), and takes the
tool-tip position error in the workpiece frame as the output (its Eqs. 1-4).  Its Fig. 1 (the
topology) and its Eqs. 1-4 are lost from the text, so the layout is a constructor parameter.

Layout
------
The layout is a topology of :mod:`.topology` (:func:`~.topology.parse_topology`: ``w``, the
workpiece-side axes with the one carrying the workpiece first, ``b``, the tool-side axes from the
bed out, ``t``), or the name of one of the common ones in :data:`LAYOUTS`, written ``W/T``: the
axes that carry the workpiece (``W``) and the spindle (``T``), each from the bed outwards.  The
default ``"z/xy"`` (``w Z b X Y t``) is the common moving-column horizontal machining centre
(inverted-T bed, e.g. the Makino a-series): the workpiece sits on the Z table, which moves along
the spindle axis; the tool side is the X column carrying the Y headstock and the horizontal
spindle.  The other named layouts: ``"x/zy"`` (T-bed: table along X, column along Z, headstock
along Y), ``"zx/y"`` and ``"xz/y"`` (cross tables under a fixed column with the Y headstock).
Any other arrangement of X, Y and Z is given as a topology (all axes on the tool side:
``"w b X Y Z t"``).

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
placement of :func:`mtaccuracy.machines.vertical_xyfz.placements` with S_xz = +EB0Z): the
exponential of an error twist is :func:`mtaccuracy.kinematics.screw_exp`.  This module holds
the layouts and the conventions; the paper's study (the model with the pose as inputs, the
closed-form indices of the linearised model, the tool lengths) is
:mod:`mtaccuracy.papers.rong`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import NamedTuple

import numpy as np

from .. import errors as _errors
from .chain import ChainMachine
from .topology import parse_topology
from .vertical_xyfz import placements

AXES = ("x", "y", "z")
TOOL_OFFSETS = ("tool_x", "tool_y", "tool_z")
DEFAULT_LAYOUT = "z/xy"


class Layout(NamedTuple):
    """A named layout: its chain topology and what it is, in words.

    Attributes
    ----------
    topology : str
        The chain from the workpiece to the tool (:func:`~.topology.parse_topology`).
    description : str
        The machine it describes, for readers (tables, :meth:`Horizontal3Axis.describe`).
    """

    topology: str
    description: str


#: The common layouts by name (``W/T``: the workpiece-side, then the tool-side axes, each from
#: the bed outwards); any other arrangement of X, Y, Z is given as its topology.
LAYOUTS = {
    "z/xy": Layout("w Z b X Y t", "workpiece on the Z table; X column carrying the Y headstock "
                                  "(moving column, inverted-T bed)"),
    "x/zy": Layout("w X b Z Y t", "workpiece on the X table; Z column carrying the Y headstock "
                                  "(T-bed)"),
    "zx/y": Layout("w X Z b Y t", "workpiece on the X table riding on the Z saddle; fixed "
                                  "column with the Y headstock"),
    "xz/y": Layout("w Z X b Y t", "workpiece on the Z table riding on the X saddle; fixed "
                                  "column with the Y headstock"),
}
#: (workpiece axes, tool axes) -> the name of that layout in :data:`LAYOUTS`
_NAMES = {(t.work, t.tool): k for k, t in
          ((k, parse_topology(v.topology)) for k, v in LAYOUTS.items())}


class Horizontal3Axis(ChainMachine):
    """Rong et al.'s three-axis horizontal machining centre, 21 errors, screw theory.

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
        A name of :data:`LAYOUTS` (default ``"z/xy"``: Z table; X column with Y headstock) or a
        topology placing the linear axes X, Y and Z (``"w b X Y Z t"``), each once.
    exact : bool
        Exact exponentials (default) or the first-order matrices ``I + xi^``.

    Raises
    ------
    TypeError
        If ``layout`` is not a string.
    ValueError
        If ``layout`` is neither a named layout nor a topology of exactly X, Y and Z.
    """

    def __init__(self, layout: str = DEFAULT_LAYOUT, exact: bool = True):
        text = LAYOUTS[layout].topology if layout in LAYOUTS else layout
        try:
            topo = parse_topology(text)
        except ValueError as exc:
            raise ValueError(f"layout {layout!r} is neither a named layout "
                             f"({', '.join(LAYOUTS)}) nor a topology: {exc}") from None
        if sorted(topo.axes) != ["X", "Y", "Z"]:
            raise ValueError(f"layout {layout!r} must place X, Y and Z, each once, and no "
                             f"other axis (got {', '.join(topo.axes)}); named layouts: "
                             f"{', '.join(LAYOUTS)}")
        self.layout = _NAMES.get((topo.work, topo.tool), text)
        self.exact = bool(exact)
        super().__init__(text, _errors.three_axis_catalogue(),
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
        work = " <- ".join(reversed(self.topology.work)) or "(fixed)"
        tool = " -> ".join(self.topology.tool) or "(fixed)"
        text = f"layout {self.layout!r}: workpiece <- {work} <- bed -> {tool} -> spindle -> tool"
        return text + (f" ({known.description})" if known else "")

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

