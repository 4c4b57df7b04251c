"""Table 2's checks: the ratios the model fixes at every pose, and Sections 3.2-3.3's checks.

The necessary conditions every single pose meets: ratios of indices the model fixes at every
pose (:func:`index_invariants`), with the printed precision carried into a ratio
(:func:`ratio_interval`), and Table 2 against them (:func:`fixed_ratio_checks`); Section 3.2's
group shares (:func:`group_shares`); Section 3.3's relative differences, of our estimates
(:func:`relative_scatter`, :func:`key_relative_difference`) and of the paper's own Table 2
(:func:`published_relative_difference`).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pandas as pd

from ... import sensitivity as S
from ...machines.ac_double_turntable import ACDoubleTurntable

__all__ = ["index_invariants", "ratio_interval", "group_label", "group_head",
           "fixed_ratio_checks", "group_shares", "relative_scatter", "key_relative_difference",
           "published_relative_difference"]


# --------------------------------------------------------------------------------------
# Necessary conditions on a table of indices: ratios the model fixes at every pose
# --------------------------------------------------------------------------------------

def index_invariants(machine: ACDoubleTurntable, sd, *, rows, cols, poses: Mapping,
                     rtol: float = 1e-9):
    """Ratios of normalised linear indices that the model fixes at every pose.

    The normalised linear index is ``S_ki = J_ki^2 sd_i^2 / V_k``, so

    - within a component, two errors whose Jacobian entries stay proportional at every pose
      (the same structure: e.g. translations along one direction of one moving frame) have
      ``S_ki / S_kj`` fixed by their variance ratio, whatever the pose: they form a *group*;
    - across components, a ratio of two groups in component k and one in component l can be
      the same function of the pose (e.g. ``sin^2 A`` in Vx and in Vy), so their quotient is
      fixed too (``V_k``, ``V_l`` cancel).

    A ratio counts as fixed when its largest relative spread over ``poses`` is below
    ``rtol``; entries whose index is zero at some pose are left alone (no ratio).

    Parameters
    ----------
    machine : ACDoubleTurntable
        The machine whose Jacobian gives the indices.
    sd : array (41,)
        Error standard deviations (mm, rad).
    rows, cols : arrays of int (m,)
        The table's (component, error) entries (e.g. Table 2).
    poses : mapping
        Pose arrays (P,), P >= 3: many random poses, x, y, z (mm), A, C (rad).
    rtol : float
        Largest relative spread over the poses of a ratio that counts as fixed.

    Returns
    -------
    groups : DataFrame
        One row per entry: ``entry``, ``component``, ``error``, ``group`` (an integer, -1 for
        an entry left alone; entries of one group share a component) and ``factor``, the fixed
        ratio ``S_entry / S_head`` (head: the group's first entry).
    cross : DataFrame
        The groups ``num_k, den_k, num_l, den_l`` and ``value``, the fixed quotient
        ``(S_num_k / S_den_k) / (S_num_l / S_den_l)`` of their heads.
    """
    rows, cols = np.asarray(rows), np.asarray(cols)
    s = S.linear_indices(machine.jacobian(poses), sd=sd)[:, cols, rows]   # (P, entries)
    if s.shape[0] < 3:
        raise ValueError("index_invariants needs at least 3 poses to tell a fixed ratio")
    ok = (s > 0).all(axis=0)
    logs = np.log(np.where(s > 0, s, 1.0))

    def fixed(r):
        return float(np.abs(np.expm1(r - r.mean())).max()) < rtol

    group = -np.ones(len(rows), dtype=int)
    factor = np.full(len(rows), np.nan)
    heads = []
    for a in range(len(rows)):
        if group[a] >= 0 or not ok[a]:
            continue
        group[a], factor[a] = len(heads), 1.0
        for b in range(a + 1, len(rows)):
            if group[b] < 0 and ok[b] and rows[b] == rows[a] and fixed(logs[:, b] - logs[:, a]):
                group[b], factor[b] = len(heads), float(np.exp((logs[:, b] - logs[:, a]).mean()))
        heads.append(a)
    pairs = [(g, h) for g in range(len(heads)) for h in range(g + 1, len(heads))
             if rows[heads[g]] == rows[heads[h]]]
    cross = []
    for i, (g, h) in enumerate(pairs):
        rk = logs[:, heads[g]] - logs[:, heads[h]]
        for g2, h2 in pairs[i + 1:]:
            if rows[heads[g2]] == rows[heads[g]]:
                continue
            for num, den in ((g2, h2), (h2, g2)):
                q = rk - (logs[:, heads[num]] - logs[:, heads[den]])
                if fixed(q):
                    cross.append(dict(num_k=g, den_k=h, num_l=num, den_l=den,
                                      value=float(np.exp(q.mean()))))
    groups = pd.DataFrame({"entry": np.arange(len(rows)), "component": rows, "error": cols,
                           "group": group, "factor": factor})
    return groups, pd.DataFrame(cross, columns=["num_k", "den_k", "num_l", "den_l", "value"])


def ratio_interval(num, den):
    """The interval of ``num / den`` for two positive intervals (interval arithmetic).

    How the printed precision of two published values propagates into their ratio.

    Parameters
    ----------
    num, den : pair of float
        ``(lo, hi)`` of the numerator and of the denominator; ``den`` strictly positive,
        ``num`` not negative.

    Returns
    -------
    lo, hi : float
        ``num_lo / den_hi`` and ``num_hi / den_lo``.
    """
    (num_lo, num_hi), (den_lo, den_hi) = num, den
    if np.any(np.asarray(den_lo) <= 0) or np.any(np.asarray(num_lo) < 0):
        raise ValueError("ratio_interval needs positive intervals")
    return np.asarray(num_lo) / np.asarray(den_hi), np.asarray(num_hi) / np.asarray(den_lo)


def group_label(groups, t2, g) -> str:
    """A group of Table 2 entries fixed equal by the model: its component and symbols.

    Parameters
    ----------
    groups : pandas.DataFrame
        The groups of :func:`index_invariants` (``entry``, ``group``).
    t2 : pandas.DataFrame
        Table 2, one row per entry (``comp``, ``symbol``).
    g : int
        The group.

    Returns
    -------
    str
        ``"Py d_xx/d_xz/d_xa/d_xAM"``.
    """
    m = groups[groups.group == g].entry
    return f"{t2.comp.iloc[m.iloc[0]]} " + "/".join(t2.symbol.iloc[m])


def group_head(groups, ci, ei, g):
    """(component, error) index of a group's first entry.

    Parameters
    ----------
    groups : pandas.DataFrame
        The groups of :func:`index_invariants` (``entry``, ``group``).
    ci, ei : array of int
        Component and error index of each Table 2 entry.
    g : int
        The group.

    Returns
    -------
    (int, int)
        Component and error index of the group's first entry.
    """
    j = groups.entry[groups.group == g].iloc[0]
    return ci[j], ei[j]


def fixed_ratio_checks(t2, *, half, groups, cross, any_sd, methods=("pce", "mcs", "lhs")):
    """Table 2 against the equalities and quotients the model fixes at every pose.

    Parameters
    ----------
    t2 : pandas.DataFrame
        Table 2, one row per entry, a float column per method (and ``comp``, ``symbol``).
    half : pandas.DataFrame
        Half a unit of each printed value's last digit, the same columns.
    groups, cross : pandas.DataFrame
        :func:`index_invariants`: entries equal at every pose up to fixed factors, and
        quotients of four groups fixed at every pose.
    any_sd : set of tuple
        The quotients ``(num_k, den_k, num_l, den_l)`` that hold for any error variances.
    methods : sequence of str
        The columns of ``t2`` checked.

    Returns
    -------
    equalities : pandas.DataFrame
        Per group of two or more entries, the spread of the printed values (percent) and
        whether their printed intervals meet, per method.
    quotients : pandas.DataFrame
        Per fixed quotient, the model's value, the printed value's interval (printed precision
        propagated, widened by twice the paper's own scatter) and whether it holds the model's
        value, per method.
    floor : float
        The noise floor: RMS of the published PCE values around the group means.
    scatter : dict of str to float
        Per method, the relative scatter of one published value around its group mean.
    """
    def group_interval(g, m):
        """(lo, hi) of a group's mean published value (divided by the fixed factors)."""
        e = groups[groups.group == g]
        v, h = t2[m].to_numpy()[e.entry] / e.factor, half[m].to_numpy()[e.entry] / e.factor
        return float((v - h).mean()), float((v + h).mean())

    def label(g):
        return group_label(groups, t2, g)

    # the paper's own scatter: relative deviations of its values from the group means
    fixed = groups[groups.group >= 0]

    def rel_dev(m):
        v = t2[m].to_numpy()[fixed.entry] / fixed.factor.to_numpy()
        return v / pd.Series(v).groupby(fixed.group.to_numpy()).transform("mean").to_numpy() - 1

    multi = fixed.group.map(fixed.group.value_counts()).to_numpy() > 1
    scatter = {m: float(np.sqrt(np.mean(rel_dev(m)[multi] ** 2) * multi.sum()
                                / (multi.sum() - fixed[multi].group.nunique())))
               for m in methods}  # RMS relative deviation, corrected for the fitted group means
    size = fixed.group.value_counts()
    eq_rows = []
    for g, e in fixed.groupby("group"):
        if len(e) < 2:
            continue
        row = dict(group=label(g))
        for m in methods:
            v, h = t2[m].to_numpy()[e.entry] / e.factor, half[m].to_numpy()[e.entry] / e.factor
            row[f"{m}_spread_percent"] = 100 * (v.max() / v.min() - 1)
            row[f"{m}_holds"] = bool((v - h).max() <= (v + h).min())   # printed intervals meet
        eq_rows.append(row)
    cr_rows = []
    for r in cross.itertuples():
        row = dict(quotient=f"({label(r.num_k)}) / ({label(r.den_k)})  over  "
                            f"({label(r.num_l)}) / ({label(r.den_l)})",
                   model=r.value, any_variances=(r.num_k, r.den_k, r.num_l, r.den_l) in any_sd)
        for m in methods:
            iv = [group_interval(g, m) for g in (r.num_k, r.den_k, r.num_l, r.den_l)]
            lo, hi = ratio_interval(ratio_interval(iv[0], iv[1]), ratio_interval(iv[2], iv[3]))
            row[m] = 0.5 * (lo + hi)
            # widened by twice the paper's own scatter of a quotient of four group means
            s = scatter[m] * np.sqrt(sum(1 / size[g] for g in (r.num_k, r.den_k, r.num_l, r.den_l)))
            lo, hi = lo * (1 - 2 * s), hi * (1 + 2 * s)
            row[f"{m}_interval"] = f"[{lo:.3f}, {hi:.3f}]"
            row[f"{m}_holds"] = bool(lo <= r.value <= hi)
        cr_rows.append(row)
    # the noise floor: RMS of the published PCE values around the equalities the model fixes
    scaled = t2.pce.to_numpy()[fixed.entry] / fixed.factor.to_numpy()
    means = pd.Series(scaled).groupby(fixed.group.to_numpy()).transform("mean").to_numpy()
    floor = float(np.sqrt(np.mean((scaled - means) ** 2)))
    return pd.DataFrame(eq_rows), pd.DataFrame(cr_rows), floor, scatter


def group_shares(s, catalogue, comps) -> pd.DataFrame:
    """Section 3.2's comparisons of groups of errors, from normalised total indices.

    Parameters
    ----------
    s : array (6, 41)
        Indices of the components ``comps``, summing to 1 over the errors.
    catalogue : sequence of errors
        The machine's 41 errors (``translational``, ``axis``, ``kind``).
    comps : sequence of str
        Names of the components, the rows of ``s``.

    Returns
    -------
    pandas.DataFrame
        One row per component: the summed index of the translational and of the angular
        errors, of the errors of the rotary axes (A, C: their error motions and location
        errors) and of the linear axes (X, Y, Z and the squareness errors), and the mean index
        per error of the location errors (PIGEs) and of the error motions (PDGEs, squareness
        counted as PIGE as in Table 1).
    """
    s = np.asarray(s, dtype=float)
    trans = np.array([e.translational for e in catalogue])
    rotary = np.array([e.axis in ("A", "C") for e in catalogue])
    pige = np.array([e.kind != "error motion" for e in catalogue])
    return pd.DataFrame({"component": list(comps),
                         "translational": s[:, trans].sum(axis=1),
                         "angular": s[:, ~trans].sum(axis=1),
                         "rotary_axes": s[:, rotary].sum(axis=1),
                         "linear_axes": s[:, ~rotary].sum(axis=1),
                         "pige_mean": s[:, pige].mean(axis=1),
                         "pdge_mean": s[:, ~pige].mean(axis=1)})


def relative_scatter(estimate, exact, threshold: float = 0.05) -> float:
    """RMS relative deviation of sampled indices ``estimate`` from the ``exact`` ones (key errors).

    Over the entries (same shape) whose exact index exceeds ``threshold`` (the key errors):
    the sampling scatter of one printed value, comparable with the paper's own scatter around
    the equalities its model fixes.

    Parameters
    ----------
    estimate, exact : array
        Sampled and exact indices, the same shape.
    threshold : float
        Entries whose exact index exceeds this are compared.

    Returns
    -------
    float
        The RMS relative deviation (a fraction).
    """
    estimate, exact = np.asarray(estimate, dtype=float), np.asarray(exact, dtype=float)
    key = exact > threshold
    if not key.any():
        raise ValueError(f"no exact index above {threshold}")
    return float(np.sqrt(np.mean((estimate[key] / exact[key] - 1) ** 2)))


def key_relative_difference(st, *, keys, comps, names, of: str = "PCE",
                            against=("MCS", "LHS")) -> float:
    """Section 3.3's check on our estimates: the largest relative difference over the key errors.

    ``|st[of] / st[m] - 1|`` over the entries ``keys`` and the methods ``m`` of ``against``:
    relative to the sampled value, as the paper states its "< 5 %".

    Parameters
    ----------
    st : mapping of str to array (len(comps), len(names))
        Normalised total indices by method, components by errors (as Table 2).
    keys : iterable of (str, str)
        The (component, error symbol) entries compared: the key errors.
    comps : sequence of str
        Component names, the rows of each array.
    names : sequence of str
        Error symbols, the columns of each array.
    of : str
        The method compared (the paper's PCE).
    against : sequence of str
        The methods it is compared with, each value the reference of its ratio.

    Returns
    -------
    float
        The largest relative difference (a fraction, not percent).
    """
    rows, cols = np.array([[comps.index(c), names.index(s)] for c, s in sorted(keys)],
                          dtype=int).reshape(-1, 2).T
    if rows.size == 0:
        raise ValueError("key_relative_difference needs at least one key error")
    return max(np.abs(np.asarray(st[of])[rows, cols] / np.asarray(st[m])[rows, cols] - 1).max()
               for m in against)


def published_relative_difference(t2: pd.DataFrame) -> tuple[pd.Series, int]:
    """The same check on the paper's own Table 2: each row's PCE value against MCS and LHS.

    Parameters
    ----------
    t2 : pandas.DataFrame
        Table 2 with float columns ``pce``, ``mcs`` and ``lhs`` (normalised total indices).

    Returns
    -------
    rel : pandas.Series
        Per row, the larger of ``|pce / mcs - 1|`` and ``|pce / lhs - 1|`` (a fraction).
    worst : int
        Position of the row where it is largest (the first of equal ones).
    """
    rel = np.maximum(np.abs(t2.pce / t2.mcs - 1), np.abs(t2.pce / t2.lhs - 1))
    return rel, int(np.argmax(rel.to_numpy()))
