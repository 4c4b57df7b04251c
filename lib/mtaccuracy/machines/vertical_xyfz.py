"""The three-axis vertical XYFZ machine of Guo et al. 2016 (Fig. 2, Eqs. 1-13).

Topology (Fig. 2): the workpiece sits on the X table, which rides on the Y carriage on the bed
(R); the spindle (S) and tool (T) are carried by the Z ram on the bed.  The paper chains the
frames in one series, workpiece <- X <- Y <- R <- Z <- S <- T (Eq. 9), with each axis' ideal
motion followed by its error matrix (Eqs. 6-8):

    W_T = T(x) E_X  T(y) E_Y  T(z) E_Z  T(D1, D2, D3)

and the tool-tip error E = (W_T^e - W_T^i) [0 0 0 1]^T (Eq. 10).  In this convention x, y, z
are the commanded *relative* tool-to-workpiece coordinates and every error enters with the
sign the paper prints; the squareness errors enter the translations of Y and Z as
``dx(y) - y S_xy``, ``dx(z) - z S_xz``, ``dy(z) - z S_yz`` (Eqs. 7-8).

The library evaluates the full product of the paper's small-angle matrices (no truncation)
with the generic chain (:mod:`.chain`, topology ``w b X Y Z t``); ``exact=True`` uses exact
rotations instead.  :func:`printed_closed_form` transcribes the
paper's second-order Eqs. 11-13 as printed, typos included, and :func:`second_order` derives
the correct second-order expansion with sympy, so the two can be compared term by term
(:func:`closed_form_typos`).  This module is hand-written because the error model is the
paper's own contribution; sympy does the algebra.
"""

from __future__ import annotations

from collections.abc import Mapping

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
    """Where the 21 errors enter a three-axis chain: each axis' six error motions in the block
    after its motion; S_xy tilts Y about z (EC0Y), S_yz tilts Z about x (EA0Z) and S_xz tilts
    Z about y with ``s_xz_sign`` (Guo et al.: -1, their S_xz is -EB0Z; Rong et al.: +1).

    Parameters
    ----------
    s_xz_sign : float
        -1 (Guo et al.) or +1 (Rong et al.).

    Returns
    -------
    dict of str to Placement
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


# --------------------------------------------------------------------------------------
# The paper's printed closed form (Eqs. 11-13), transcribed as printed.
# --------------------------------------------------------------------------------------

def printed_closed_form(e: Mapping, x, y, z, D1, D2, D3):
    """Eqs. 11-13 exactly as printed in Guo et al. 2016, typos included.

    ``e`` maps paper symbols to values; works with numpy arrays and with sympy symbols.
    Ambiguous brackets are read as follows (:data:`PRINTED_UNBALANCED`): in Eq. 13,
    ``y(ey(x) S_xy + ex(x)`` is closed after ``ex(x)``.  Returns ``(Ex, Ey, Ez)``.

    Parameters
    ----------
    e : mapping
        Paper symbol -> value (mm, rad) or sympy symbol.
    x, y, z, D1, D2, D3 : float, array or sympy symbol
        The pose (mm).

    Returns
    -------
    Ex, Ey, Ez
    """
    d = lambda s: e[s]  # noqa: E731  (short alias keeps the transcription readable)
    ex = (d("dx(z)") + d("dx(x)") + d("dx(y)") - y * (d("ez(x)") + d("S_xy"))
          + D1 + d("ey(x)") * (d("dz(y)") + d("dz(z)")) + d("ey(y)") * d("dz(z)")
          + D2 * (-d("ez(x)") - d("ez(y)") - d("ez(z)"))
          - d("ez(x)") * (d("dy(y)") + d("dy(y)"))
          + z * (d("ey(x)") + d("ey(y)") - d("S_xz") + d("ez(x)") * d("ex(y)")
                 + d("ez(x)") * d("S_yz") + d("ez(y)") * d("S_yz"))
          + D3 * (d("ey(x)") + d("ey(y)") + d("ey(z)") + d("ex(y)") * d("ez(x)")
                  + d("ex(z)") * d("ez(x)") + d("ex(z)") * d("ez(y)"))
          - d("ez(y)") * d("dy(z)"))
    ey = (d("dy(z)") + d("dy(x)") + d("dy(y)") + D1 * (d("ez(y)") + d("ez(x)") + d("ez(z)"))
          + D2 + d("dz(x)") * (d("dx(y)") + d("dx(z)")) - y * d("ez(x)") * d("S_xy")
          - d("ex(y)") * d("dz(z)")
          - z * (d("ex(x)") + d("ex(y)") + d("S_yz") - d("ey(y)") * d("ez(x)")
                 + d("ez(x)") * d("S_xz") + d("ez(y)") * d("S_xz"))
          - D3 * (d("ex(x)") + d("ex(y)") + d("ex(z)") - d("ey(y)") * d("ez(x)")
                  - d("ey(z)") * d("ez(x)") - d("ey(z)") * d("ez(y)"))
          + d("dx(z)") * d("ez(y)") - d("ex(x)") * (d("dz(y)") + d("dz(z)")))
    ez = (d("dz(x)") + d("dz(y)") + d("dz(z)") + y * (d("ey(x)") * d("S_xy") + d("ex(x)"))
          + d("ex(x)") * (d("dy(y)") + d("dy(z)")) - d("dx(z)") * d("ey(y)")
          - z * (d("ex(x)") * d("S_yz") + d("ex(y)") * d("ex(x)") - d("ey(x)") * d("ey(y)")
                 - d("ey(y)") * d("S_xz") + d("ex(y)") * d("S_yz"))
          - d("ey(x)") * (d("dx(y)") + d("dx(z)"))
          - D3 * (d("ex(y)") * d("ex(x)") + d("ex(z)") * d("ex(x)") + d("ey(y)") * d("ey(x)")
                  + d("ey(z)") * d("ey(x)") + d("ex(y)") * d("ex(z)") + d("ey(y)") * d("ey(z)"))
          + d("ex(y)") * d("dy(z)") + D1 * (-d("ey(x)") - d("ey(y)") - d("ey(z)"))
          + D2 * (d("ex(x)") + d("ex(y)") + d("ex(z)")))
    return ex, ey, ez


# Eq. 8 as printed: the (3,1) entry reads -ey(y) where the pattern of Eqs. 6-7 needs -ey(z).
PRINTED_EQ8_ROW3 = ("-ey(y)", "ex(z)", "1", "dz(z)")

# Brackets of Eqs. 11-13 that are opened and never closed as printed, with the reading
# :func:`printed_closed_form` takes and the lowest degree in the errors of the terms the
# reading decides: (equation, component, as printed, reading taken, degree).  Eq. 13: read to
# the end, y would multiply every later term (the first-order ex(x) term among them).
PRINTED_UNBALANCED = (
    ("Eq. 13", "Ez", "y(ey(x)S_xy + ex(x) + ex(x)(dy(y) + dy(z)) - ... (the bracket after y is "
     "never closed)", "y*(S_xy*ey(x) + ex(x))", 1),
)


# --------------------------------------------------------------------------------------
# Symbolic derivation (sympy).
# --------------------------------------------------------------------------------------

def symbols():
    """sympy symbols: a dict of the 21 errors by paper symbol, and the pose symbols.

    Returns
    -------
    errors : dict of str to sympy.Symbol
    pose : dict of str to sympy.Symbol
    """
    import sympy as sp

    cat = _errors.three_axis_catalogue()
    err = {e.symbol: sp.Symbol(e.symbol, real=True) for e in cat}
    pose = {k: sp.Symbol(k, real=True) for k in AXES + TOOL_OFFSETS}
    return err, pose


def symbolic_position_error():
    """Exact symbolic (Ex, Ey, Ez) of the full product of the paper's matrices (Eqs. 1-10,
    Eq. 8 corrected), as sympy expressions in the error and pose symbols.

    Returns
    -------
    Ex, Ey, Ez : sympy expressions
    """
    import sympy as sp

    e, p = symbols()

    def t(vx, vy, vz):
        return sp.Matrix([[1, 0, 0, vx], [0, 1, 0, vy], [0, 0, 1, vz], [0, 0, 0, 1]])

    def err(a, dx, dy, dz):
        ex, ey, ez = e[f"ex({a})"], e[f"ey({a})"], e[f"ez({a})"]
        return sp.Matrix([[1, -ez, ey, dx], [ez, 1, -ex, dy], [-ey, ex, 1, dz], [0, 0, 0, 1]])

    x, y, z = p["x"], p["y"], p["z"]
    ex_ = err("x", e["dx(x)"], e["dy(x)"], e["dz(x)"])
    ey_ = err("y", e["dx(y)"] - y * e["S_xy"], e["dy(y)"], e["dz(y)"])
    ez_ = err("z", e["dx(z)"] - z * e["S_xz"], e["dy(z)"] - z * e["S_yz"], e["dz(z)"])
    tool = t(p["D1"], p["D2"], p["D3"])
    actual = t(x, 0, 0) * ex_ * t(0, y, 0) * ey_ * t(0, 0, z) * ez_ * tool
    ideal = t(x, 0, 0) * t(0, y, 0) * t(0, 0, z) * tool
    diff = (actual - ideal)[:3, 3]
    return tuple(sp.expand(diff[i]) for i in range(3))


def truncate(expr, order: int = 2):
    """Drop every term of ``expr`` whose total degree in the 21 error symbols exceeds
    ``order`` (pose symbols do not count).

    Parameters
    ----------
    expr : sympy expression
    order : int
        Highest total degree kept.

    Returns
    -------
    sympy expression
    """
    import sympy as sp

    e, _ = symbols()
    gens = list(e.values())
    poly = sp.Poly(sp.expand(expr), *gens)
    return sp.Add(*[c * sp.Mul(*[g**k for g, k in zip(gens, m, strict=True)])
                    for m, c in poly.terms() if sum(m) <= order])


def second_order():
    """The correct second-order closed form (Ex, Ey, Ez) derived from the matrix product.

    Returns
    -------
    Ex, Ey, Ez : sympy expressions
    """
    return tuple(truncate(c, 2) for c in symbolic_position_error())


def closed_form_typos():
    """Compare the printed Eqs. 11-13 with the derived second-order expansion, term by term.

    Returns a list of dicts ``equation, component, term, degree, printed, derived, kind``
    where a term is a monomial in the error symbols (with its pose factor folded into the
    coefficients) and kind is ``spurious`` (printed, not derived), ``missing`` (derived, not
    printed) or ``coefficient`` (both, different coefficient).  Eq. 8's (3,1) entry is
    checked against the skew-symmetric pattern of Eqs. 6-7 and reported too, and every
    bracket opened and never closed as printed (:data:`PRINTED_UNBALANCED`) is a row of kind
    ``bracket`` (printed: the text as printed; derived: the reading whose terms are compared;
    degree: the lowest degree in the errors it affects).

    Returns
    -------
    list of dict
    """
    import sympy as sp

    e, p = symbols()
    gens = list(e.values())
    printed = printed_closed_form(e, p["x"], p["y"], p["z"], p["D1"], p["D2"], p["D3"])
    derived = second_order()
    rows = []
    if PRINTED_EQ8_ROW3[0] != "-ey(z)":
        rows.append(dict(equation="Eq. 8", component="Z error matrix, row 3, column 1",
                         term="-ey(z)", degree=1, printed=PRINTED_EQ8_ROW3[0],
                         derived="-ey(z)", kind="coefficient"))
    for eq, comp, pr, de in zip(("Eq. 11", "Eq. 12", "Eq. 13"), ("Ex", "Ey", "Ez"),
                                printed, derived, strict=True):
        for eq_, comp_, text, reading, low in PRINTED_UNBALANCED:
            if eq_ == eq:
                rows.append(dict(equation=eq, component=comp_, term=reading, degree=low,
                                 printed=text, derived=reading, kind="bracket"))
        tp = dict(sp.Poly(sp.expand(pr), *gens).terms())
        td = dict(sp.Poly(sp.expand(de), *gens).terms())
        for mono in sorted(set(tp) | set(td), key=lambda m: (sum(m), str(m))):
            cp, cd = sp.expand(tp.get(mono, 0)), sp.expand(td.get(mono, 0))
            if sp.simplify(cp - cd) == 0:
                continue
            term = sp.Mul(*[g**k for g, k in zip(gens, mono, strict=True)])
            kind = "spurious" if cd == 0 else ("missing" if cp == 0 else "coefficient")
            rows.append(dict(equation=eq, component=comp, term=str(term), degree=sum(mono),
                             printed=str(cp), derived=str(cd), kind=kind))
    return rows


def describe_typos(typos, equation: str) -> str:
    """Every difference of one printed equation (Guo et al. 2016, Eqs. 11-13), in words.

    Parameters
    ----------
    typos : DataFrame
        The rows of :func:`closed_form_typos`.
    equation : str
        Which equation.

    Returns
    -------
    str
        ``kind term (printed ..., derived ...)`` per difference, joined by "; " (a bracket
        left open is named without its coefficients).
    """
    d = typos[typos.equation == equation]
    return "; ".join(f"{r.kind} {r.term}" + ("" if r.kind == "bracket"
                                               else f" (printed {r.printed}, derived {r.derived})")
                     for r in d.itertuples())
