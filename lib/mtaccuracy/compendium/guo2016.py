"""The compendium's side of notebook 03 (Guo et al. 2016): what serves that paper's audit.

The paper's printed equations against the matrix product, the model-free eigenvalue test of the
printed Fig. 3 panels, the exchangeable pairs of every output (Et included), the units-slip
reading of the printed Eq. 12, and what the model says about the XY circle test (Table 2).

The machine itself (Fig. 2, Eqs. 1-10) is :class:`mtaccuracy.machines.vertical_xyfz.VerticalXYFZ`.
The paper then expands its Eq. 10 to second order and prints the result as Eqs. 11-13.
:func:`printed_closed_form` transcribes those equations as printed, typos included, and
:func:`second_order` derives the correct second-order expansion from the matrix product with
sympy (:func:`symbolic_position_error`, Eq. 8 corrected), so the two can be compared term by
term (:func:`closed_form_typos`, :func:`describe_typos`).  This is written by hand because the
printed expansion is the paper's own contribution; sympy does the algebra.

sympy (a dependency of the ``compendium`` extra) is imported at module level: only notebook 03
and its tests import this module, and both use sympy themselves.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pandas as pd
import sympy as sp

from ..errors import three_axis_catalogue
from ..machines.vertical_xyfz import AXES, TOOL_OFFSETS

__all__ = ["printed_closed_form", "PRINTED_EQ8_ROW3", "PRINTED_UNBALANCED", "symbols",
           "symbolic_position_error", "truncate", "second_order", "closed_form_typos",
           "describe_typos", "monte_carlo_p", "eigen_bound_table", "exchangeable_pairs",
           "pair_table", "UnitsSlip", "circle_terms"]


# --------------------------------------------------------------------------------------
# The paper's printed closed form (Eqs. 11-13), transcribed as printed.
# --------------------------------------------------------------------------------------

def printed_closed_form(e: Mapping, *, x, y, z, D1, D2, D3):
    """The tool-tip error of Eqs. 11-13 exactly as printed in Guo et al. 2016, typos included.

    Works with numpy arrays and with sympy symbols alike.  Brackets opened and never closed
    are read as :data:`PRINTED_UNBALANCED` says: in Eq. 13, ``y(ey(x) S_xy + ex(x)`` is closed
    after ``ex(x)``.

    Parameters
    ----------
    e : mapping
        Paper symbol (``dx(x)``, ..., ``S_xz``) -> value (mm, rad; scalars or (n,) arrays) or
        sympy symbol.
    x, y, z, D1, D2, D3 : float, array (n,) or sympy symbol
        The commanded relative position and the tool offsets (mm).

    Returns
    -------
    Ex, Ey, Ez : array (n,) or sympy expression
        Eqs. 11, 12, 13 (mm), the printed constants D1 (in Ex) and D2 (in Ey) included.
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
    """Real sympy symbols of the 21 errors and of the pose, by name.

    Returns
    -------
    errors : dict of str to sympy.Symbol
        Paper symbol -> symbol, in catalogue order (``dx(x)``, ..., ``S_xz``).
    pose : dict of str to sympy.Symbol
        ``x, y, z, D1, D2, D3`` -> symbol.
    """
    cat = three_axis_catalogue()
    err = {e.symbol: sp.Symbol(e.symbol, real=True) for e in cat}
    pose = {k: sp.Symbol(k, real=True) for k in AXES + TOOL_OFFSETS}
    return err, pose


def symbolic_position_error():
    """The exact tool-tip error of the paper's matrix product (Eqs. 1-10, Eq. 8 corrected).

    The product of the paper's first-order error matrices in full, with no truncation: an
    independent formulation of :class:`~mtaccuracy.machines.vertical_xyfz.VerticalXYFZ`.

    Returns
    -------
    Ex, Ey, Ez : sympy expressions
        Expanded polynomials in the symbols of :func:`symbols` (mm when evaluated in mm, rad).
    """
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
    """``expr`` without its terms of total degree above ``order`` in the 21 error symbols.

    Parameters
    ----------
    expr : sympy expression
        A polynomial in the symbols of :func:`symbols`.
    order : int
        Highest total degree in the error symbols kept (pose symbols do not count).

    Returns
    -------
    sympy expression
    """
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
        :func:`symbolic_position_error` truncated to degree 2 in the errors: what Eqs. 11-13
        should read.
    """
    return tuple(truncate(c, 2) for c in symbolic_position_error())


def closed_form_typos():
    """Compare the printed Eqs. 11-13 with the derived second-order expansion, term by term.

    A term is a monomial in the error symbols (its pose factor folded into the coefficients).
    Eq. 8's (3,1) entry is checked against the skew-symmetric pattern of Eqs. 6-7 and
    reported too, and every bracket opened and never closed as printed
    (:data:`PRINTED_UNBALANCED`) is a row of kind ``bracket``.

    Returns
    -------
    list of dict
        One per difference: ``equation, component, term, degree, printed, derived, kind``.
        kind is ``spurious`` (printed, not derived), ``missing`` (derived, not printed),
        ``coefficient`` (both, different coefficient) or ``bracket`` (printed: the text as
        printed; derived: the reading whose terms are compared; degree: the lowest degree in
        the errors it affects).
    """
    e, p = symbols()
    gens = list(e.values())
    printed = printed_closed_form(e, **p)
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
        The ``equation`` value of the rows to describe (``"Eq. 11"``, ``"Eq. 8"``, ...).

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


# --------------------------------------------------------------------------------------
# The printed Fig. 3 panels, the circle test.
# --------------------------------------------------------------------------------------

OUTPUTS = ("Ex", "Ey", "Ez", "Et")


def monte_carlo_p(observed: float, simulated) -> float:
    """Monte Carlo p-value ``(1 + #{simulated >= observed}) / (N + 1)`` of a printed statistic.

    Exact under the null that ``observed`` is one more independent draw of the simulated law
    (exchangeability), so ``P(p <= alpha) <= alpha`` for every ``alpha`` and every ``N``.

    Parameters
    ----------
    observed : float
        The printed statistic.
    simulated : array (N,)
        Independent draws of its law under the null.

    Returns
    -------
    float
        In ``[1 / (N + 1), 1]``.
    """
    s = np.asarray(simulated, dtype=float)
    return float((1 + np.sum(s >= observed)) / (s.size + 1))


def eigen_bound_table(pub: pd.DataFrame, *, lam_set, lam_all, alpha: float) -> pd.DataFrame:
    """Each printed panel's top-8 sum of squares against the model-free eigenvalue bound.

    ``sum r_i^2 <= lambda_max(R_S)`` for any output and any set S of inputs
    (:func:`mtaccuracy.sensitivity.lhs_rank_eigenvalues`).  The paper's 500-run design is not
    printed, so the bound is random: ``lam_set`` holds ``lambda_max`` for a set of 8 inputs
    fixed in advance, ``lam_all`` for all 21 inputs, which bounds every 8-subset however it
    was picked (Cauchy interlacing), so also a top 8 chosen on the same design.  A panel is
    ``impossible`` when its Monte Carlo p-value is at most ``alpha``.

    Parameters
    ----------
    pub : DataFrame
        The printed top 8: columns ``output``, ``spearman`` (float).
    lam_set, lam_all : array (N1,), (N2,)
        Simulated ``lambda_max`` for 8 fixed inputs and for all 21 inputs.
    alpha : float
        Failure probability of the test (a genuine design is called impossible with at most
        this probability).

    Returns
    -------
    DataFrame
        One row per output: the printed sum, each bound (the 1 - alpha quantile of the
        simulated ``lambda_max``), its p-value and verdict.
    """
    rows = []
    for o in OUTPUTS:
        ss = float((pub[pub.output == o].spearman ** 2).sum())
        p_set, p_all = monte_carlo_p(ss, lam_set), monte_carlo_p(ss, lam_all)
        rows.append(dict(output=o, printed_top8_sum_sq=ss,
                         bound_fixed_set=float(np.quantile(lam_set, 1 - alpha)), p_fixed_set=p_set,
                         bound_any_set=float(np.quantile(lam_all, 1 - alpha)), p_any_set=p_all,
                         fixed_set="impossible" if p_set <= alpha else "not excluded",
                         any_set="impossible" if p_all <= alpha else "not excluded"))
    return pd.DataFrame(rows)


def exchangeable_pairs(first: dict, names, kinds) -> list[tuple[str, str, str]]:
    """Pairs of errors that enter an output identically to first order at *every* pose.

    Their expected Spearman coefficients are then equal: same first-order coefficient (a
    polynomial in the pose, compared identically after expansion), not zero, and the same kind
    (hence the same range).  For Et = |(Ex, Ey, Ez)| the coefficients must agree in all three
    components.

    Parameters
    ----------
    first : dict
        ``first[output][symbol]``: first-order coefficient (sympy) for Ex, Ey, Ez.
    names : list of str
        Error symbols in catalogue order.
    kinds : list of str
        Their kinds (positioning, straightness, angular, squareness).

    Returns
    -------
    list of (output, a, b)
        ``a`` before ``b`` in catalogue order; outputs in the order Ex, Ey, Ez, Et.
    """
    comps = [o for o in OUTPUTS if o in first]
    out = []
    for o in (*comps, "Et"):
        use = comps if o == "Et" else [o]
        for i, a in enumerate(names):
            for b, kb in zip(names[i + 1:], kinds[i + 1:], strict=True):
                if kinds[i] != kb or all(first[c][a] == 0 for c in use):
                    continue
                if all(sp.expand(first[c][a] - first[c][b]) == 0 for c in use):
                    out.append((o, a, b))
    return out


def pair_table(pub: pd.DataFrame, *, pairs, rho_rep, names) -> pd.DataFrame:
    """The printed gap of each exchangeable pair against its sampling spread.

    Both listed: the gap is printed.  One listed: the other's |rho| is at most the smallest
    printed |rho| of that output (its 8th), so ``|gap| >= |rho_listed| - |rho_8th|`` (a lower
    bound, ``gap_is_bound``).  Neither listed: nothing printed to test (left out).  The sign of
    the gap is not predicted (either error can come out larger), so the share of designs is
    two-sided: ``|gap_design| >= |printed|``.

    Parameters
    ----------
    pub : DataFrame
        Printed top 8: ``output``, ``symbol``, ``spearman`` (float).
    pairs : list of (output, a, b)
        From :func:`exchangeable_pairs`.
    rho_rep : array (R, 21, 4)
        Coefficients of R independent designs (Ex, Ey, Ez, Et).
    names : list of str
        Error symbols in catalogue order.

    Returns
    -------
    DataFrame
        ``output, pair, listed, printed_gap, gap_is_bound, sd_of_gap, share_of_designs``.
    """
    rows = []
    for o, a, b in pairs:
        d = pub[pub.output == o].set_index("symbol").spearman
        if a not in d.index and b not in d.index:
            continue
        k = OUTPUTS.index(o)
        diff = rho_rep[:, names.index(a), k] - rho_rep[:, names.index(b), k]
        if a in d.index and b in d.index:
            gap, bound = abs(float(d[a] - d[b])), False
        else:
            gap, bound = max(abs(float(d.get(a, d.get(b)))) - float(d.abs().min()), 0.0), True
        rows.append(dict(output=o, pair=f"{a} vs {b}", listed="both" if not bound else
                         (a if a in d.index else b), printed_gap=gap, gap_is_bound=bound,
                         sd_of_gap=float(diff.std(ddof=1)),
                         share_of_designs=float(np.mean(np.abs(diff) >= gap))))
    return pd.DataFrame(rows)


class UnitsSlip:
    """The printed Eqs. 11-13 with translational errors in micrometres, positions in mm.

    Angular and squareness errors stay in rad: a hypothesis for how Fig. 3 could have been
    computed.  The spurious second-order term ``dz(x) (dx(y) + dx(z))`` of Eq. 12 (a product
    of two lengths) then reaches tens of "micrometres" and dominates Ey, while every term with
    an angle times a position (mm x rad, read as um) is a thousand times too small.
    ``pose_error`` has the interface of a machine, so
    :func:`mtaccuracy.sensitivity.spearman_over_poses` can use it.

    Parameters
    ----------
    machine : VerticalXYFZ
        Gives the error names and kinds (which errors are scaled by 1e3).
    """

    def __init__(self, machine):
        self.error_names = list(machine.error_names)
        self.scale = np.array([1e3 if e.kind in ("positioning", "straightness") else 1.0
                               for e in machine.catalogue])

    def pose_error(self, errors, pose) -> np.ndarray:
        """(Ex, Ey, Ez) of the printed equations in the slipped units, zero orientation columns.

        The spurious constants D1, D2 are removed (they shift, never rank).

        Parameters
        ----------
        errors : array (N, 21)
            Errors in mm and rad (library units).
        pose : dict
            x, y, z, D1, D2, D3: floats or (N,) arrays (mm).

        Returns
        -------
        array (N, 6)
            "Ex, Ey, Ez" in the slipped unit (um for the first-order translational terms),
            then three zeros.
        """
        e = np.asarray(errors, dtype=float) * self.scale
        named = {s: e[:, j] for j, s in enumerate(self.error_names)}
        ex, ey, ez = printed_closed_form(named, **pose)
        p = np.column_stack([ex - pose["D1"], ey - pose["D2"], ez + 0.0 * ex])
        return np.concatenate([p, np.zeros_like(p)], axis=1)


def circle_terms() -> pd.DataFrame:
    """What an XY circle test can see in the paper's model: the terms of Ex, Ey that vary on it.

    The terms of the exact Ex, Ey of the matrix product (Eqs. 1-10) that vary with x or y
    (every other term is the same at every point of the circle: a rigid shift, which a ballbar
    set at the circle's centre does not see), before and after compensating the angular and
    squareness errors (trajectory A).  The errors are constants in the paper's model (one
    value per error, Section 2).

    Returns
    -------
    DataFrame
        ``component, varies_on_circle, after_A`` (sympy expressions as text), and
        ``errors_seen``: the errors in the varying part.
    """
    e, p = symbols()
    comp = dict(zip(("Ex", "Ey"), symbolic_position_error()[:2], strict=True))
    zero_a = {v: 0 for k, v in e.items() if k.startswith(("e", "S"))}
    rows = []
    for c, expr in comp.items():
        terms = sp.expand(expr).as_ordered_terms()
        dep = sp.Add(*[t for t in terms if t.has(p["x"]) or t.has(p["y"])])
        seen = sorted((s for s, v in e.items() if dep.has(v)), key=list(e).index)
        rows.append(dict(component=c, varies_on_circle=str(sp.factor_terms(dep)),
                         after_A=str(sp.simplify(dep.subs(zero_a))), errors_seen=", ".join(seen)))
    return pd.DataFrame(rows)
