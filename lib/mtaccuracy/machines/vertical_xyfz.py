"""The three-axis vertical XYFZ machine of Guo et al. 2016 (Fig. 2, Eqs. 1-10).

Topology (Fig. 2): the workpiece sits on the X table, which rides on the Y carriage on the bed
(R); the spindle (S) and tool (T) are carried by the Z ram on the bed.  The frames are chained
in one series, workpiece <- X <- Y <- R <- Z <- S <- T (Eq. 9), with each axis' ideal motion
followed by its error matrix (Eqs. 6-8):

    W_T = T(x) E_X  T(y) E_Y  T(z) E_Z  T(D1, D2, D3)

and the tool-tip error E = (W_T^e - W_T^i) [0 0 0 1]^T (Eq. 10).  In this convention x, y, z
are the commanded *relative* tool-to-workpiece coordinates and every error enters with the
sign the paper prints; the squareness errors enter the translations of Y and Z as
``dx(y) - y S_xy``, ``dx(z) - z S_xz``, ``dy(z) - z S_yz`` (Eqs. 7-8).  x never multiplies
an error (the X errors sit first in the chain).

The machine is the generic chain (:mod:`.chain`, topology ``w b X Y Z t``) with the placements
of :func:`placements`, evaluated as the full product of first-order error matrices (no
truncation); ``exact=True`` uses exact rotations instead.  The 21 errors are the three-axis
ISO 230-1 catalogue (:func:`mtaccuracy.errors.three_axis_catalogue`).
"""

from __future__ import annotations

from .. import errors as _errors
from .chain import ChainMachine, Placement

AXES = ("x", "y", "z")
TOOL_OFFSETS = ("D1", "D2", "D3")


class VerticalXYFZ(ChainMachine):
    """Guo et al. 2016's XYFZ vertical machine; ``exact=True`` for exact rotation matrices.

    A description for :class:`~mtaccuracy.machines.chain.ChainMachine`: the paper's serial
    reading ``w b X Y Z t`` (Eq. 9 composes X, Y, Z from the workpiece, each motion followed
    by its error matrix), first-order error matrices (``exact=True``: exact rotations, form
    ``rodrigues``), squareness entering the translations linearly (first-order tilts of the
    Y and Z directions; the paper's S_xz is -EB0Z: ``dx(z) - z S_xz``), tool offsets
    ``D1, D2, D3``, rotation-vector output.

    Parameters
    ----------
    exact : bool
        Exact rotation matrices instead of the paper's first-order ones.
    """

    def __init__(self, exact: bool = False):
        self.exact = bool(exact)
        super().__init__(TOPOLOGY, _errors.three_axis_catalogue(), placements(),
                         name="vertical_xyfz", form="rodrigues" if self.exact else "first_order",
                         tilt="first_order", tool_offsets=TOOL_OFFSETS,
                         orientation="rotation_vector", axis_names=AXES)


#: the paper's chain read from the workpiece to the tool (see :mod:`.chain`)
TOPOLOGY = "w b X Y Z t"


def placements(s_xz_sign: float = -1.0) -> dict[str, Placement]:
    """Where the 21 errors of a three-axis chain enter it, by paper symbol.

    Each axis' six error motions enter in the block after its motion; S_xy tilts Y about z
    (EC0Y), S_yz tilts Z about x (EA0Z) and S_xz tilts Z about y with the sign ``s_xz_sign``.

    Parameters
    ----------
    s_xz_sign : float
        Sign of S_xz against EB0Z: -1 for Guo et al. 2016 (their S_xz is -EB0Z), +1 for Rong
        et al. (:mod:`.horizontal_3axis`).

    Returns
    -------
    dict of str to Placement
        Paper symbol (``dx(x)``, ..., ``S_xz``) -> axis, slot, component and sign.
    """
    pl = {}
    for a in AXES:
        for c, d in enumerate(AXES):
            pl[f"d{d}({a})"] = Placement(a.upper(), "motion", c)
            pl[f"e{d}({a})"] = Placement(a.upper(), "motion", 3 + c)
    pl["S_xy"] = Placement("Y", "tilt", 5)
    pl["S_yz"] = Placement("Z", "tilt", 3)
    pl["S_xz"] = Placement("Z", "tilt", 4, s_xz_sign)
    return pl
