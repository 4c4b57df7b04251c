"""The compendium's side of notebook 03 (Guo et al. 2016): the model-free eigenvalue test of the
printed Fig. 3 panels, the exchangeable pairs of every output (Et included), the units-slip
reading of the printed Eq. 12, and what the model says about the XY circle test (Table 2)."""

from __future__ import annotations

import numpy as np
import pandas as pd

__all__ = ["monte_carlo_p", "eigen_bound_table", "exchangeable_pairs", "pair_table", "UnitsSlip",
           "circle_terms"]

OUTPUTS = ("Ex", "Ey", "Ez", "Et")


def monte_carlo_p(observed: float, simulated) -> float:
    """Monte Carlo p-value ``(1 + #{simulated >= observed}) / (N + 1)``: exact under the null
    that ``observed`` is one more independent draw of the simulated law (exchangeability), so
    ``P(p <= alpha) <= alpha`` for every ``alpha`` and every ``N``.

    Parameters
    ----------
    observed : float
        The printed statistic.
    simulated : array (N,)
        Independent draws of its law under the null.

    Returns
    -------
    float
    """
    s = np.asarray(simulated, dtype=float)
    return float((1 + np.sum(s >= observed)) / (s.size + 1))


def eigen_bound_table(pub: pd.DataFrame, lam_set, lam_all, alpha: float) -> pd.DataFrame:
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
    """Pairs of errors that enter an output identically to first order at *every* pose, so
    that their expected Spearman coefficients are equal: same first-order coefficient (a
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
    import sympy as sp

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


def pair_table(pub: pd.DataFrame, pairs, rho_rep, names) -> pd.DataFrame:
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
    """The printed Eqs. 11-13 evaluated with the translational errors in micrometres and the
    positions in millimetres (angular and squareness errors in rad): a hypothesis for how
    Fig. 3 could have been computed.  The spurious second-order term ``dz(x) (dx(y) + dx(z))``
    of Eq. 12 (a product of two lengths) then reaches tens of "micrometres" and dominates Ey,
    while every term with an angle times a position (mm x rad, read as um) is a thousand
    times too small.  ``pose_error`` has the interface of a machine, so
    :func:`mtaccuracy.sensitivity.spearman_over_poses` can use it.

    Parameters
    ----------
    machine : VerticalXYFZ
        Gives the error names and kinds.
    """

    def __init__(self, machine):
        self.error_names = list(machine.error_names)
        self.scale = np.array([1e3 if e.kind in ("positioning", "straightness") else 1.0
                               for e in machine.catalogue])

    def pose_error(self, errors, pose) -> np.ndarray:
        """(Ex, Ey, Ez) of the printed equations in the slipped units, the spurious constants
        D1, D2 removed (they shift, never rank), with zero orientation columns.

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
        from ..machines.vertical_xyfz import printed_closed_form

        e = np.asarray(errors, dtype=float) * self.scale
        named = {s: e[:, j] for j, s in enumerate(self.error_names)}
        ex, ey, ez = printed_closed_form(named, **pose)
        p = np.column_stack([ex - pose["D1"], ey - pose["D2"], ez + 0.0 * ex])
        return np.concatenate([p, np.zeros_like(p)], axis=1)


def circle_terms() -> pd.DataFrame:
    """What an XY circle test can see in the paper's model: the terms of the exact Ex, Ey of
    the matrix product (Eqs. 1-10) that vary with x or y (every other term is the same at
    every point of the circle: a rigid shift, which a ballbar set at the circle's centre does
    not see), before and after compensating the angular and squareness errors (trajectory A).
    The errors are constants in the paper's model (one value per error, Section 2).

    Returns
    -------
    DataFrame
        ``component, varies_on_circle, after_A`` (sympy expressions as text), and
        ``errors_seen``: the errors in the varying part.
    """
    import sympy as sp

    from ..machines.vertical_xyfz import symbolic_position_error, symbols

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
