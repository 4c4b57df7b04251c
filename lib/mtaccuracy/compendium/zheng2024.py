"""The compendium's side of notebook 01 (Zheng et al. 2024): Table 2's fixed ratios, the
sampled and PCE references at the fitted pose, and figures.

Everything here serves the reproduction of one paper; the methods themselves are in
:mod:`mtaccuracy.sensitivity` and :mod:`mtaccuracy.machines.ac_double_turntable`.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

__all__ = ["tidy", "fmt", "normalise", "sobol_reference", "pce_indices", "group_label",
           "fixed_ratio_checks", "group_head", "converged_at", "bars_figure",
           "fig04_figure", "group_shares", "relative_scatter"]


def tidy(df: pd.DataFrame) -> pd.DataFrame:
    """Floats rounded to 6 decimals, and a rounded -0 written as 0 (its sign is rounding noise)."""
    return df.apply(lambda s: s.round(6) + 0.0 if s.dtype.kind == "f" else s)


def fmt(v: float) -> str:
    """One decimal for values above 0.1 in magnitude, four below (poses, misfits)."""
    return f"{v:.1f}" if abs(v) > 0.1 else f"{v:.4f}"


def normalise(st):
    """Total indices clipped at 0 and divided by their sum over the errors (Table 2's
    normalised total indices); ``st`` (..., d)."""
    st = np.clip(st, 0, None)
    return st / st.sum(axis=-1, keepdims=True)


def sobol_reference(machine, pose, sd, method: str, n: int, rng_seed: int, progress=False):
    """Sampled Sobol' indices of the six pose-error components at ``pose``, errors normal with
    standard deviations ``sd`` (41,): ``method`` "mc" or "lhs" designs of ``n`` base rows,
    streamed (``sensitivity.sobol_indices`` on a ``SobolDesign``); returns (s1, st), each
    (41, 6).  With ``progress`` a line per quarter of the runs."""
    from .. import sensitivity as S

    design = S.SobolDesign(n, 41, method, rng_seed, to_inputs=lambda u: S.from_unit_normal(u, sd))
    marks = set()

    def report(done, total):
        q = int(4 * done / total)
        if progress and q not in marks:
            marks.add(q)
            print(f"  {method.upper()}: {done:,} / {total:,} model runs", flush=True)

    # streaming: base rows drawn block by block, the AB runs reduced to per-error sums as they
    # come, never stored (an LHS design is held whole: see sensitivity.SobolDesign)
    return S.sobol_indices(lambda x: machine.pose_error(x, pose), design, chunk=250_000,
                           progress=report)


def pce_indices(machine, pose, sd, n: int, degree: int, rng_seed: int, q_norm: float = 1.0,
                comps=tuple(range(6))) -> dict:
    """Sparse PCE fits (``sensitivity.fit_pce_outputs``) of the pose-error components ``comps``
    on a Latin hypercube of ``n`` standard normals (errors = xi * sd); {component: fit}."""
    from .. import sensitivity as S

    u = S.base_samples(n, 41, "lhs", rng_seed)[0]
    xi = S.from_unit_normal(u, np.ones(41))
    y = machine.pose_error(xi * sd, pose)
    fits = S.fit_pce_outputs(xi, y[:, list(comps)], degree=degree, q_norm=q_norm)
    return dict(zip(comps, fits, strict=True))


def group_label(groups, t2, g) -> str:
    """A group of Table 2 entries fixed equal by the model: its component and symbols."""
    m = groups[groups.group == g].entry
    return f"{t2.comp.iloc[m.iloc[0]]} " + "/".join(t2.symbol.iloc[m])


def group_head(groups, ci, ei, g):
    """(component, error) index of a group's first entry."""
    j = groups.entry[groups.group == g].iloc[0]
    return ci[j], ei[j]


def fixed_ratio_checks(t2, half, groups, cross, any_sd, methods=("pce", "mcs", "lhs")):
    """Table 2 against the equalities and quotients the model fixes at every pose.

    ``t2``: Table 2 (one row per entry, a column per method), ``half``: half a unit of each
    printed value's last digit; ``groups``, ``cross``: ``index_invariants`` (entries equal at
    every pose, up to fixed factors; quotients of four groups fixed at every pose); ``any_sd``:
    the quotients that hold for any error variances.  Returns (equalities, quotients, floor,
    scatter):
    per group the spread of the printed values and whether their printed intervals meet; per
    quotient the printed value's interval (printed precision propagated, widened by twice the
    paper's own scatter) and whether it holds the model's value; and the noise floor, the RMS
    of the published PCE values around the group means of the equalities, and the relative
    scatter of one published value around its group mean per method."""
    from ..machines.ac_double_turntable import ratio_interval

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
            k_lo, k_hi = ratio_interval(*iv[0], *iv[1])
            l_lo, l_hi = ratio_interval(*iv[2], *iv[3])
            lo, hi = ratio_interval(k_lo, k_hi, l_lo, l_hi)
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


def converged_at(g, r_max: float = 3.0, assign: str = "larger"):
    """The first sample size from which the fluctuation R (``g.R_percent``, Eq. 24, the
    change from the previous size, so NaN at the first) stays at or below ``r_max`` percent
    (``g.n`` ascending); NaN if never.

    Eq. 24, R = |S_(l+1) - S_l| / S_l, does not say to which of the two sizes R belongs:
    ``assign="larger"`` gives it to size l+1 (the reading under which the largest size of a
    series can be the one that converges, as the paper says of MCS and LHS at 1e5),
    ``assign="smaller"`` to size l (Eq. 24 literally; the largest size then has no R)."""
    if assign not in ("larger", "smaller"):
        raise ValueError(f"assign must be 'larger' or 'smaller', got {assign!r}")
    r = g.R_percent.to_numpy(dtype=float)[1:]
    n = g.n.to_numpy()
    n = n[:-1] if assign == "smaller" else n[1:]   # "smaller": R of step l -> l+1 is size l's
    fails = np.flatnonzero(~(r <= r_max))
    first = fails[-1] + 1 if fails.size else 0     # from here on R stays small
    return int(n[first]) if first < len(n) else np.nan


def group_shares(s, catalogue, comps) -> pd.DataFrame:
    """Section 3.2's comparisons of groups of errors, from normalised total indices.

    ``s`` (6, 41): indices of the components ``comps`` (summing to 1 over the errors);
    ``catalogue``: the machine's 41 errors (``translational``, ``axis``, ``kind``).  Returns
    one row per component with the summed index of the translational and of the angular
    errors, of the errors of the rotary axes (A, C: their error motions and location errors)
    and of the linear axes (X, Y, Z and the squareness errors), and the mean index per error
    of the location errors (PIGEs) and of the error motions (PDGEs, squareness counted as
    PIGE as in Table 1)."""
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
    """RMS relative deviation of sampled indices ``estimate`` from the ``exact`` ones (same
    shape) over the entries whose exact index exceeds ``threshold`` (the key errors): the
    sampling scatter of one printed value, comparable with the paper's own scatter around
    the equalities its model fixes."""
    estimate, exact = np.asarray(estimate, dtype=float), np.asarray(exact, dtype=float)
    key = exact > threshold
    if not key.any():
        raise ValueError(f"no exact index above {threshold}")
    return float(np.sqrt(np.mean((estimate[key] / exact[key] - 1) ** 2)))


def bars_figure(st, comps, all_comps, names, t2, key_threshold: float, title: str,
                published_colour):
    """Figs. 5-6: normalised total indices of every error by method (bars) for the
    components ``comps``, beside Table 2's PCE values (diamonds) unless ``t2`` is None (the
    bars drawn at a pose other than Table 2's)."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(comps), 1, figsize=(13, 3.2 * len(comps)), sharex=True)
    w = 0.27
    xpos = np.arange(41)
    for ax, c in zip(axes, comps, strict=True):
        k = all_comps.index(c)
        for j, (m, col) in enumerate(zip(st, ("#1b9e77", "#7570b3", "#66a61e"), strict=True)):
            ax.bar(xpos + (j - 1) * w, st[m][k], w, label=m, color=col)
        if t2 is not None:
            p = t2[t2.comp == c]
            ax.scatter([names.index(s) for s in p.symbol], p.pce, marker="D",
                       color=published_colour, zorder=3, label="published (Table 2, PCE)")
        ax.axhline(key_threshold, color="k", lw=0.7, ls="--")
        ax.set_ylabel(f"{c}: normalised ST")
    axes[0].legend(ncol=4, fontsize=8)
    axes[-1].set_xticks(xpos, names, rotation=90)
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def fig04_figure(s_tp, comps, names, diagonal, vmax: float = 0.3):
    """Fig. 4's test points: the linear total index of every error (rows, named) at every
    test point (columns, numbered 1..N along the diagonals, which white lines separate), one
    heat map per component, two rows of three; the first point of each diagonal and the last
    point are numbered, and every point has a tick (up to 60 points).

    ``s_tp`` (N, len(comps), 41): indices per point; ``names`` (41,): the error names;
    ``diagonal`` (N,): the diagonal (0-3) of each point, points of one diagonal consecutive."""
    import matplotlib.pyplot as plt

    n_pts = s_tp.shape[0]
    firsts = np.r_[0, np.flatnonzero(np.diff(diagonal)) + 1]   # first point of each diagonal
    numbered = np.unique(np.r_[firsts + 1, n_pts])
    fig, axes = plt.subplots(2, 3, figsize=(13, 14), sharex=True, sharey=True,
                             layout="constrained")
    fig.get_layout_engine().set(wspace=0.05)
    for k, ax in enumerate(axes.flat):
        im = ax.imshow(s_tp[:, k, :].T, aspect="auto", cmap="viridis", vmin=0, vmax=vmax,
                       extent=(0.5, n_pts + 0.5, len(names) - 0.5, -0.5), interpolation="nearest")
        for f in firsts[1:]:
            ax.axvline(f + 0.5, color="w", lw=1.5)
        ax.set_title(comps[k], fontsize=11)
        ax.set_xticks(numbered, [str(t) for t in numbered])
        if n_pts <= 60:   # a tick at every point while they stay apart
            ax.set_xticks(np.arange(1, n_pts + 1), minor=True)
        ax.set_yticks(range(len(names)), names, fontsize=8)
        left, right = k % 3 == 0, k % 3 == 2   # error names beside the outer panels
        ax.tick_params(axis="y", left=left, labelleft=left, right=right, labelright=right)
        ax.tick_params(axis="x", labelbottom=True)
        ax.grid(False)
        ax.set_xlabel("test point (white lines: next diagonal)")
    fig.colorbar(im, ax=axes, orientation="horizontal", shrink=0.5, aspect=40,
                 label="normalised linear total index")
    fig.suptitle("Linear total index of each error at each test point on the four workspace "
                 "diagonals")
    return fig
