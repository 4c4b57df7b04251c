"""The compendium's side of notebook 03 (Guo et al. 2016): what serves that paper's audit.

The paper's printed equations against the matrix product, the model-free eigenvalue test of the
printed Fig. 3 panels, the exchangeable pairs of every output (Et included), the units-slip
reading of the printed Eq. 12, and what the model says about the XY circle test (Table 2);
what an XY circle can confirm once the errors vary along the axes is
:mod:`mtaccuracy.papers.guo2016_measurement`'s (Section 7b).

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
import param
import sympy as sp

from ..errors import three_axis_catalogue
from ..machines.vertical_xyfz import AXES, TOOL_OFFSETS
from .figure import Caption, figures
from .guo2016_measurement import CIRCLE_SEES
from .parameters import NotebookParameters, OutputFolder, ParameterError

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


class Parameters(NotebookParameters):
    """Notebook 03: Guo et al. 2016, Latin hypercube and Spearman ranking of 21 errors."""

    stem = "03_guo2016_spearman_21_errors"
    seed = param.Integer(20160, bounds=(0, None), doc="seed of every random draw")
    n_samples = param.Integer(500, bounds=(10, 10000),
                              doc="Latin hypercube sample size (paper: 500)")
    n_repeats = param.Integer(200, bounds=(2, 1000),
                              doc="independent designs measuring the spread at n_samples")
    positioning_um = param.Number(3.0, bounds=(0.0, 1000.0), inclusive_bounds=(False, True),
                                  doc="positioning errors uniform on [0, this] µm (paper: 3)")
    straightness_um = param.Number(4.0, bounds=(0.0, 1000.0), inclusive_bounds=(False, True),
                                   doc="straightness errors uniform on [0, this] µm (paper: 4)")
    angular_rad = param.Number(3.2e-05, bounds=(0.0, 0.01), inclusive_bounds=(False, True),
                               doc="angular errors uniform on [0, this] rad (paper: 3.2e-5)")
    squareness_um_per_m = param.Number(1.9, bounds=(0.0, 10000.0),
                                       inclusive_bounds=(False, True),
                                       doc="squareness errors uniform on [0, this] µm/m")
    x_mm = param.Number(100.0, bounds=(-5000.0, 5000.0),
                        doc="nominal pose x (mm), not stated in the paper")
    y_mm = param.Number(100.0, bounds=(-5000.0, 5000.0),
                        doc="nominal pose y (mm), not stated in the paper")
    z_mm = param.Number(100.0, bounds=(-5000.0, 5000.0),
                        doc="nominal pose z (mm), not stated in the paper")
    D1_mm = param.Number(0.0, bounds=(-1000.0, 1000.0),
                         doc="tool offset D1 in the spindle frame (mm), not stated")
    D2_mm = param.Number(0.0, bounds=(-1000.0, 1000.0), doc="tool offset D2 (mm), not stated")
    D3_mm = param.Number(0.0, bounds=(-1000.0, 1000.0), doc="tool offset D3 (mm), not stated")
    workspace_mm = param.Number(500.0, bounds=(0.0, 5000.0), inclusive_bounds=(False, True),
                                doc="the pose grid covers y, z in [0, workspace_mm]")
    grid_step_mm = param.Number(25.0, bounds=(0.0, 5000.0), inclusive_bounds=(False, True),
                                doc="step of the pose grid (mm); at most 101 points per axis")
    n_search_poses = param.Integer(512, bounds=(16, 4096),
                                   doc="random poses of the any-pose search")
    n_search_samples = param.Integer(1000, bounds=(100, 10000),
                                     doc="error samples per pose in the any-pose search")
    n_bound_designs = param.Integer(10000, bounds=(100, 100000),
                                    doc="random designs: eigenvalue bound, 8 inputs fixed first")
    n_bound_designs_all = param.Integer(2000, bounds=(100, 20000),
                                        doc="random designs: eigenvalue bound, any 8 of 21")
    alpha_bound = param.Number(0.001, bounds=(0.0, 0.5), inclusive_bounds=(False, False),
                               doc="chance that the eigenvalue test rejects a genuine design")
    # Section 7b: the XY circle on the chain with error motions that vary along the travels
    circle_radius_mm = param.Number(100.0, bounds=(1.0, 1000.0),
                                    doc="XY circle (ballbar) radius in mm; not given in the paper")
    circle_travel_mm = param.Number(250.0, bounds=(1.0, 5000.0),
                                    doc="half travel of each axis about the pose (mm), not given")
    ballbar_noise_um = param.Number(0.2, bounds=(0.0, 100.0), inclusive_bounds=(False, True),
                                    doc="noise of one ballbar reading (µm)")
    motion_degree = param.Integer(1, bounds=(1, 2),
                                  doc="Legendre degree of the error motions (1: scale errors)")
    output_dir = OutputFolder("figures/03_guo2016_spearman_21_errors",
                              doc="where figures and tables are written")

    def memory_bytes(self) -> float:
        # measured 0.41 GB at the defaults; 730 B per repeated sample (designs, outputs, ranks),
        # 64 poses of samples evaluated at a time
        grid = (self.workspace_mm / self.grid_step_mm + 1) ** 2
        return (4.5e8 + 1000 * self.n_repeats * self.n_samples
                + 6e4 * max(self.n_samples, self.n_search_samples)
                + 1000 * (self.n_search_poses + grid))

    def check(self) -> None:
        n_grid = int(self.workspace_mm / self.grid_step_mm + 0.5) + 1
        if n_grid > 101:
            raise ParameterError(f"{self.stem}: the pose grid would have {n_grid} points per "
                                 f"axis; at most 101 (raise grid_step_mm)")
        if self.circle_radius_mm > self.circle_travel_mm:
            raise ParameterError(f"{self.stem}: the XY circle (circle_radius_mm "
                                 f"{self.circle_radius_mm:g}) must lie within the travels "
                                 f"(circle_travel_mm {self.circle_travel_mm:g}): raise "
                                 "circle_travel_mm or lower the radius")
        if (min(self.n_bound_designs, self.n_bound_designs_all) + 1) * self.alpha_bound < 1:
            raise ParameterError(f"{self.stem}: the eigenvalue test cannot reach p <= "
                                 f"alpha_bound with so few designs: need n_bound_designs, "
                                 f"n_bound_designs_all >= 1 / alpha_bound - 1")


def beyond_bounds(eig: pd.DataFrame) -> dict[str, str]:
    """The panels of Fig. 3 beyond both eigenvalue bounds, and beyond the fixed-set one only.

    Parameters
    ----------
    eig : pandas.DataFrame
        :func:`eigen_bound_table`, one row per panel (a-d, in order).

    Returns
    -------
    dict
        ``{"beyond_both": "Fig. 3b", "beyond_fixed": "Fig. 3c, Fig. 3d"}`` (``"none"`` when
        empty), for the caption of the test figure.
    """
    both, fixed = [], []
    for letter, r in zip("abcd", eig.itertuples(), strict=False):
        if r.any_set == "impossible":
            both.append(f"Fig. 3{letter}")
        elif r.fixed_set == "impossible":
            fixed.append(f"Fig. 3{letter}")
    return {"beyond_both": ", ".join(both) or "none", "beyond_fixed": ", ".join(fixed) or "none"}


# --- the chapter's figures, in the paper's order ---------------------------------------------
# matplotlib is imported in each drawing function: the compendium extra, an optional heavy
# dependency of the paper code

FIG3 = Caption(
    "fig03_spearman_ex_ey_ez_et", "Fig. 3",
    "Spearman rank correlation of each of the 21 errors with Ex (a), Ey (b), Ez (c) and the "
    "total error Et (d), sorted by |ρ|: bars from one Latin hypercube of n = {n_samples} on the "
    "paper's ranges, whiskers 2 sd over {n_repeats} designs, diamonds the paper's top 8. Drawn "
    "at {pose}: a pose the paper does not state, the best fit of the pose search of this "
    "chapter. Rows naming errors with no first-order effect are scored against 0 (any pose), "
    "and unreachable values against the closest value over the searched poses, not at this "
    "pose.", key=True)


def spearman_bars_figure(fig3: pd.DataFrame, pub: pd.DataFrame, *, outputs, n_samples: int,
                         pose: str, colours: tuple[str, str]):
    """Fig. 3 regenerated: each output's coefficients, sorted, with the paper's top 8.

    Parameters
    ----------
    fig3 : pandas.DataFrame
        Ours: ``output, rank, symbol, spearman, sd_at_n`` per output, ranked.
    pub : pandas.DataFrame
        The paper's: ``output, symbol, spearman`` (floats).
    outputs : sequence of str
        The four outputs, in panel order.
    n_samples : int
        The design's size (the legend).
    pose : str
        The pose drawn (the title).
    colours : (str, str)
        Ours and the paper's.

    Returns
    -------
    matplotlib.figure.Figure
        Four panels, (a) to (d).
    """
    import matplotlib.pyplot as plt  # the compendium extra (see above)

    fig, axes = plt.subplots(2, 2, figsize=(11, 7.5), sharey=True)
    for ax, o, letter in zip(axes.flat, outputs, "abcd", strict=True):
        d = fig3[fig3.output == o]
        xpos = np.arange(len(d))
        ax.bar(xpos, d.spearman, yerr=2 * d.sd_at_n, color=colours[0], alpha=0.85,
               capsize=2, label=f"reproduced (n={n_samples}, bars: 2 sd)")
        p = pub[pub.output == o]
        where = [list(d.symbol).index(s) for s in p.symbol]
        ax.scatter(where, p.spearman, marker="D", color=colours[1], zorder=3,
                   label="published (top 8)")
        ax.axhline(0, color="k", lw=0.6)
        ax.set_xticks(xpos, d.symbol, rotation=90)
        ax.set_title(f"({letter}) {o}")
        ax.set_ylabel("Spearman rho")
    axes.flat[0].legend(loc="upper right", fontsize=7)
    fig.suptitle(f"Fig. 3: Spearman coefficient of each error, sorted by |rho| ({pose})")
    fig.tight_layout()
    return fig


EIGENVALUE_BOUND = Caption(
    "fig03_eigenvalue_bound", "Fig. 3 (test)",
    "Model-free test of Fig. 3: distribution of the largest eigenvalue of the inputs' "
    "rank-correlation matrix over random {n_samples}-run Latin hypercube designs, for 8 inputs "
    "fixed in advance ({n_fixed:,} designs) and for all 21 inputs, which bounds any 8 however "
    "picked ({n_any:,} designs); dashed and dotted lines are their 1 − {alpha:g} quantiles. "
    "Vertical lines are each panel's printed top-8 sum of squared ρ: for any model and any "
    "pose the sum cannot exceed its design's eigenvalue. Beyond both bounds: {beyond_both}; "
    "beyond the fixed-set bound only: {beyond_fixed}. No pose is involved.")


def eigenvalue_bound_figure(lam_set: np.ndarray, lam_all: np.ndarray, eig: pd.DataFrame, *,
                            n_samples: int, alpha: float, colours: tuple[str, str]):
    """The law of the model-free bound beside each printed panel's sum of squares.

    Parameters
    ----------
    lam_set, lam_all : numpy.ndarray
        ``(designs,)``: largest eigenvalues for the 8 inputs fixed in advance, and for all 21.
    eig : pandas.DataFrame
        :func:`eigen_bound_table`.
    n_samples : int
        Runs per design.
    alpha : float
        The test's failure probability (its quantiles are drawn).
    colours : (str, str)
        Ours and the paper's.

    Returns
    -------
    matplotlib.figure.Figure
        The two histograms, the quantiles and the printed sums.
    """
    import matplotlib.pyplot as plt  # the compendium extra (see above)

    k_printed, n_all = 8, 21
    fig, ax = plt.subplots(figsize=(10, 4.2))
    bins = np.linspace(1.0, max(lam_all.max(), eig.printed_top8_sum_sq.max()) + 0.05, 110)
    ax.hist(lam_set, bins=bins, density=True, color=colours[0], alpha=0.55,
            label=f"{k_printed} inputs fixed in advance ({lam_set.size} designs)")
    ax.hist(lam_all, bins=bins, density=True, color="0.45", alpha=0.45,
            label=f"all {n_all} inputs: bounds any {k_printed} ({lam_all.size} designs)")
    for q, ls in ((eig.bound_fixed_set.iloc[0], "--"), (eig.bound_any_set.iloc[0], ":")):
        ax.axvline(q, color="k", ls=ls, lw=1)
    ax.axvline(1.0, color="k", lw=0.6)
    top = ax.get_ylim()[1]
    for r, c in zip(eig.itertuples(), "abcd", strict=True):
        ax.axvline(r.printed_top8_sum_sq, color=colours[1], lw=1.6)
        ax.text(r.printed_top8_sum_sq, 0.97 * top, f" Fig. 3{c} ({r.output})", rotation=90,
                va="top", ha="right", fontsize=8, color=colours[1])
    ax.plot([], [], color=colours[1], label="published: top-8 sum of squared rho")
    ax.plot([], [], "k--", lw=1, label=f"1 - {alpha:g} quantiles (fixed set: dashed; any set: "
                                       "dotted)")
    ax.set_xlabel(f"largest eigenvalue of the inputs' rank-correlation matrix (n = {n_samples} "
                  f"runs)")
    ax.set_ylabel("density")
    ax.legend(loc="center right", fontsize=8)
    ax.set_title("Model-free bound on the sum of squared Spearman coefficients (any model, any "
                 "pose)")
    fig.tight_layout()
    return fig


POSE_GRID = Caption(
    "fig03_pose_grid_ranking", "Beyond the paper",
    "How the ranking of Fig. 3 changes across the workspace: the same {n_samples}-sample design "
    "on a {n_grid} × {n_grid} grid, y and z from 0 to {workspace:g} mm in {step:g} mm steps (x "
    "does not enter the model; tool offsets as in Fig. 3). Top: the error ranked first (largest "
    "|ρ|) for Ex, Ey, Ez and Et. Bottom: the six largest coefficients along the diagonal y = z. "
    "The first-ranked error depends on a pose the paper does not give.")


def pose_grid_figure(g: np.ndarray, rho_grid: np.ndarray, top_idx: np.ndarray, *, names,
                     outputs, colours):
    """The error ranked first over a square grid of poses, and the leaders along its diagonal.

    Parameters
    ----------
    g : numpy.ndarray
        ``(m,)``: the grid's coordinates (mm), the same for y and z.
    rho_grid : numpy.ndarray
        ``(m * m, 21, 4)``: the coefficients at each pose (y major).
    top_idx : numpy.ndarray
        ``(m * m, 4)``: the index of the error ranked first, per output.
    names : list of str
        The errors, in catalogue order.
    outputs : sequence of str
        The four outputs.
    colours : sequence of str
        A categorical palette, one colour per leading error in catalogue order (repeated past
        its length): the compendium's colour-blind-safe ``plotting.CATEGORICAL``.

    Returns
    -------
    matplotlib.figure.Figure
        Maps on top, the diagonal below.
    """
    import matplotlib.pyplot as plt  # the compendium extra (see above)

    gy, gz = np.meshgrid(g, g, indexing="ij")
    leaders = sorted({names[j] for j in np.unique(top_idx)}, key=names.index)
    from matplotlib.colors import ListedColormap  # the compendium extra, as pyplot above

    palette = [colours[k % len(colours)] for k in range(max(len(leaders), 2))]
    cmap = ListedColormap(palette)
    lead = {names.index(n): palette[k] for k, n in enumerate(leaders)}
    fig, axes = plt.subplots(2, 4, figsize=(14, 6.5))
    for k, o in enumerate(outputs):
        ax = axes[0, k]
        codes = np.array([leaders.index(names[j]) for j in top_idx[:, k]]).reshape(gy.shape)
        ax.pcolormesh(g, g, codes.T, cmap=cmap, vmin=-0.5, vmax=cmap.N - 0.5, shading="nearest")
        ax.set_title(f"{o}: error ranked first")
        ax.set_xlabel("y (mm)")
        ax.set_ylabel("z (mm)")
        ax.grid(False)
        diag = np.isclose(gy.ravel(), gz.ravel())
        ax2 = axes[1, k]
        for j in np.argsort(-np.abs(rho_grid[diag, :, k]).max(axis=0), kind="stable")[:6]:
            ax2.plot(g, rho_grid[diag, j, k], label=names[j], color=lead.get(j, "0.6"),
                     ls="-" if j in lead else "--")
        ax2.set_xlabel("y = z (mm)")
        ax2.set_ylabel("Spearman rho")
        ax2.legend(fontsize=7, ncol=2)
    handles = [plt.Rectangle((0, 0), 1, 1, color=cmap(i)) for i in range(len(leaders))]
    fig.legend(handles, leaders, loc="upper center", ncol=len(leaders), fontsize=8,
               bbox_to_anchor=(0.5, 1.03))
    fig.tight_layout()
    return fig


FIGURES = figures(FIG3, EIGENVALUE_BOUND, POSE_GRID, CIRCLE_SEES)
