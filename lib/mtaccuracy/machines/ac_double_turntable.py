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
"""

from __future__ import annotations

import numpy as np

from .. import errors as _errors
from .chain import ChainMachine, Placement

AXES = ("x", "y", "z", "A", "C")
TOOL_OFFSETS = ("L",)
TRAVELS = {"x": (-400.0, 400.0), "y": (-425.0, 425.0), "z": (-275.0, 275.0),
           "A": (np.deg2rad(-130.0), np.deg2rad(130.0)), "C": (0.0, 2 * np.pi)}


class ACDoubleTurntable(ChainMachine):
    """Zheng et al. 2024's AC double-turntable machine, a chain of :data:`TOPOLOGY`.

    Pose keys x, y, z (mm), A, C (rad), optional tool length L (mm).  A description for
    :class:`~mtaccuracy.machines.chain.ChainMachine` (:data:`TOPOLOGY`, :func:`placements`):
    the generic chain evaluates it (2 M samples/s and more) and gives its closed-form Jacobian
    (:meth:`jacobian`).

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
