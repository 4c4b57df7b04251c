"""Notebook 01's figures drawn here, each with its caption, and the chapter's captions in order.

Figs. 5-6 (:func:`bars_figure`, :data:`FIG05`, :data:`FIG06`) and Fig. 4
(:func:`fig04_figure`, :data:`FIG04`); :data:`FIGURES`, every caption of the chapter in the
book's order (the notebook draws the others itself).
"""

from __future__ import annotations

import numpy as np

from ..figure import Caption, figures
from .measurement import MEASURE

__all__ = ["FIG04", "FIG05", "FIG06", "bars_figure", "fig04_figure", "FIGURES"]


#: Fig. 5's caption (:func:`bars_figure` of Px, Py, Pz); fields: ``n_pce``, ``n_reference``,
#: ``key_threshold``, ``where`` (the test point) and ``gap_pce``, ``gap_mcs``, ``gap_lhs`` (the
#: largest difference of a drawn index from the exact one, per method).
FIG05 = Caption(
    "fig05_position_total_sobol", "Fig. 5",
    "Normalised total Sobol indices of the position error Px, Py, Pz for the 41 errors: sparse "
    "PCE ({n_pce} samples), MCS and LHS ({n_reference:,} base samples each); dashed: key "
    "threshold {key_threshold:g}. Drawn at Fig. 4 {where}, a point chosen by a fixed rule, not "
    "fitted. The published Table 2 belongs to another pose or mean of poses and is not drawn; "
    "it is scored against a two-pose mean. Largest difference of a drawn index from the exact "
    "(closed-form) one: {gap_pce:.0e} (PCE), {gap_mcs:.0e} (MCS), {gap_lhs:.0e} (LHS).",
    rows=("Section 3.3",))

#: Fig. 6's caption (:func:`bars_figure` of Vx, Vy, Vz); the fields of :data:`FIG05`.
FIG06 = Caption(
    "fig06_attitude_total_sobol", "Fig. 6",
    "As Fig. 5, for the error of the tool-axis direction Vx, Vy, Vz (radians to first order), "
    "at the same test point. Only angular and squareness errors enter. Largest difference of a "
    "drawn index from the exact one: {gap_pce:.0e} (PCE), {gap_mcs:.0e} (MCS), {gap_lhs:.0e} "
    "(LHS).",
    rows=("Section 3.3",))


def bars_figure(st, *, comps, all_comps, names, t2, key_threshold: float, title: str,
                published_colour):
    """Figs. 5-6: normalised total indices of every error by method (bars).

    For the components ``comps``, beside Table 2's PCE values (diamonds) unless ``t2`` is
    None (the bars drawn at a pose other than Table 2's).  Captions: :data:`FIG05`,
    :data:`FIG06`.

    Parameters
    ----------
    st : mapping of str to array (6, 41)
        Normalised total indices by method (three methods), components by errors.
    comps : sequence of str
        The components drawn, one panel each.
    all_comps : sequence of str
        Names of the rows of each array of ``st``.
    names : sequence of str
        The 41 error symbols.
    t2 : pandas.DataFrame or None
        Table 2 (``comp``, ``symbol``, ``pce``), drawn as diamonds; None draws none.
    key_threshold : float
        The key-error threshold (a dashed line).
    title : str
        The figure's title.
    published_colour : colour
        The colour of the published values.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt  # local: heavy, needed only by the figures

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


#: Fig. 4's caption (:func:`fig04_figure` at its default colour scale); fields: ``n_points``,
#: ``n_per_diagonal``, ``rms_mean`` (RMS difference of the points' mean indices to Table 2) and
#: ``rms_single`` (the same at the best single pose).
FIG04 = Caption(
    "fig04_indices_per_test_point", "Fig. 4",
    "Closed-form (linear) normalised total Sobol indices of the 41 errors (rows) for the "
    "position error Px, Py, Pz and the tool-axis direction error Vx, Vy, Vz, at the {n_points} "
    "test points on the four workspace diagonals (columns, {n_per_diagonal} per diagonal, white "
    "lines between diagonals); colour scale 0 to 0.3. The paper's Fig. 4 only shows where the "
    "points lie; the rotary angles are not given, so A and C sweep the same fraction of their "
    "travel as x, y, z (an assumption). The key errors change from point to point; their mean "
    "does not fit Table 2 (RMS difference {rms_mean:.4f}, against {rms_single:.4f} at the best "
    "single pose).",
    rows=("Section 3.2",))


def fig04_figure(s_tp, *, comps, names, diagonal, vmax: float = 0.3):
    """Fig. 4's test points: the linear total index of every error at every test point.

    Errors are rows (named), test points columns (numbered 1..N along the diagonals, which
    white lines separate), one heat map per component, two rows of three; the first point of
    each diagonal and the last point are numbered, and every point has a tick (up to 60
    points).  Caption: :data:`FIG04`.

    Parameters
    ----------
    s_tp : array (N, len(comps), 41)
        Indices per test point.
    comps : sequence of str
        The components, one panel each (six).
    names : sequence of str
        The 41 error names.
    diagonal : array of int (N,)
        The diagonal (0-3) of each point, points of one diagonal consecutive.
    vmax : float
        The top of the colour scale.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt  # local: heavy, needed only by the figures

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


# --- the chapter's figures, in the book's order ----------------------------------------------

FIGURES = figures(
    FIG04,
    FIG05,
    FIG06,
    Caption("fig07_convergence", "Fig. 7",
            "Convergence of d_xc in Px (a), d_yc in Py (b) and d_za in Pz (c) at Fig. 4 "
            "{where}, with a new seeded design at each size (PCE up to {pce_largest}). MCS and "
            "LHS are shown with the size read as base samples N (solid) and as model runs 43 N "
            "(dashed, from 10 base samples); dotted: the exact index. Bottom: fluctuation R "
            "(Eq. 24) given to the larger size, with the paper's 3 % criterion dashed. R at 1e3 "
            "(the step that ends there) is {r_base} read as base samples and {r_runs} read as "
            "model runs; the paper reports above 10 %.", key=True),
    Caption("pce_benchmarks", "Beyond the paper",
            "Sparse PCE on benchmark functions with exact Sobol indices, not the machine model. "
            "(a) Ishigami, n = {n_ishigami}: exact total indices, recovered by a Legendre PCE "
            "(the uniform inputs' basis; largest error {err_legendre:.0e}) but not by a Hermite "
            "PCE after a normal transform (largest error {err_hermite:.2f}). (b) Sobol's G "
            "function in 41 inputs, n = {n_g}, degree at most 3: the first 10 of the 41 total "
            "indices, {n_below} of them below the exact ones (largest error {err_g:.2f}); the "
            "validation error {validation_g:.2f} {warned}. (c) G function in 16 inputs, n = 200: "
            "along the OMP path the corrected leave-one-out error keeps falling (to "
            "{loo_last:.3f} at {terms_last} terms) while the 5-fold validation error is smallest "
            "at {terms_best} terms and then turns up."),
    MEASURE,
)
