"""Notebook 05's figures drawn here, each with its caption, and the chapter's captions in order.

Figs. 8-9 over many seeds (:func:`convergence_figure`, :data:`FIG08`, :data:`FIG09`), Fig. 21
(:func:`fig21_figure`, :data:`FIG21`), the noise of each separated harmonic
(:func:`noise_transfer_figure`, :data:`NOISE_TRANSFER`) and Figs. 19-20
(:func:`speed_curves_figure`, :data:`FIG19`, :data:`FIG20`); :data:`FIGURES`, every caption of
the chapter in the paper's order (the notebook draws the others itself).
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

from ... import spindle as sp
from ..figure import Caption, figures

__all__ = ["convergence_figure", "FIG08", "FIG09", "fig21_figure", "FIG21",
           "noise_transfer_figure", "NOISE_TRANSFER", "speed_curves_figure", "FIG19", "FIG20",
           "FIGURES"]


def convergence_figure(result, *, h_ref: float, harmonic_k: int, generations: int,
                       converge_tol: float, published_generation: float, title: str,
                       colours: tuple):
    """Figs. 8-9 over many seeds: every run's best-so-far H beside its convergence generations.

    The runs as percentile bands, the median and three single runs; the histogram of the
    generations at which they reach ``h_ref`` within ``converge_tol`` and plateau.  ``colours``:
    (ours, published).
    """
    convergence_generation = sp.convergence_generation
    reproduced, published = colours
    gens = np.arange(generations + 1)
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(11, 3.8), gridspec_kw=dict(width_ratios=[1.6, 1]))
    hst = result.history
    ax.fill_between(gens, np.percentile(hst, 10, axis=1), np.percentile(hst, 90, axis=1),
                    color=reproduced, alpha=0.15, label="10-90 % of runs")
    ax.fill_between(gens, np.percentile(hst, 25, axis=1), np.percentile(hst, 75, axis=1),
                    color=reproduced, alpha=0.3, label="25-75 %")
    ax.plot(gens, np.median(hst, axis=1), color=reproduced, label="median")
    for j in range(3):
        ax.plot(gens, hst[:, j], color="0.4", lw=0.6, alpha=0.7,
                label="single runs" if j == 0 else None)
    ax.axhline(h_ref, color="k", ls=":", lw=1, label=f"best known H {h_ref:.4f}")
    ax.axhline(0.25, color="k", ls="--", lw=0.8, label="lower bound 1/4")
    ax.axvline(published_generation, color=published, lw=1.2,
               label=f"published: ~{published_generation:.0f}")
    ax.set_ylim(0.248, max(0.30, float(np.percentile(hst[5], 90))))
    ax.set_xlabel("generation")
    ax.set_ylabel("best-so-far H")
    ax.set_title(f"{title} ({result.label}), k = {harmonic_k}, {hst.shape[1]} runs")
    ax.legend(fontsize=7, ncol=2)
    reach = convergence_generation(hst, h_ref, converge_tol)
    plateau = convergence_generation(hst, hst[-1], 1e-3)
    bins = np.linspace(0, generations, 21)
    ax2.hist(plateau, bins=bins, color="0.6", alpha=0.7, label="plateau generation")
    ax2.hist(reach[reach >= 0], bins=bins, color=reproduced, alpha=0.7,
             label=f"reached within {converge_tol:.0%} ({(reach >= 0).mean():.0%} of runs)")
    ax2.axvline(published_generation, color=published, lw=1.2, label="published")
    ax2.set_xlabel("convergence generation")
    ax2.set_ylabel("runs")
    ax2.legend(fontsize=7)
    fig.tight_layout()
    return fig


#: Fig. 8's caption: the improved GA over many seeds (:func:`convergence_figure`).
FIG08 = Caption(
    "fig08_improved_ga_convergence", "Fig. 8",
    "The improved GA (adaptive probabilities, Eqs. 22-23 with Eq. 23's sign corrected) at "
    "harmonic k = {harmonic_k}: {n_runs} seeded runs, {encoding} encoding, population "
    "{pop_size}, {generations} generations, in the recommended angle ranges. Left: best-so-far H, "
    "10-90 % and 25-75 % bands, median and three single runs; best known H {h_ref:.4f} dotted, "
    "bound 1/4 dashed, the paper's ~{published:g} generations vertical. Right: histograms of the "
    "plateau generation and of the generation reaching within {tol_percent:g} % of the best "
    "known H ({reached_percent:.0f} % of runs): half the runs reach their plateau between "
    "generations {plateau_q25:.0f} and {plateau_q75:.0f}, so one curve cannot fix a convergence "
    "generation.")

#: Fig. 9's caption: the traditional GA over many seeds (:func:`convergence_figure`).
FIG09 = Caption(
    "fig09_traditional_ga_convergence", "Fig. 9",
    "As Fig. 8, for the traditional GA with fixed crossover and mutation probabilities {pc:g} "
    "and {pm:g} (values the paper does not state): {n_runs} runs at k = {harmonic_k}, "
    "best-so-far H with percentile bands and three single runs, the paper's ~{published:g} "
    "generations vertical, and histograms of the plateau and the reached generation "
    "({reached_percent:.0f} % of runs within {tol_percent:g} %). Its median plateau is "
    "{median:g} generations against the improved GA's {improved_median:g}: a speed-up of "
    "{speedup:.0f} % at these settings. The speed-up depends on settings the paper does not "
    "state (the settings study), so the paper's {published_speedup} % is scored not "
    "reproducible.")


def fig21_figure(theta, layouts, *, rotation_errors, profiles, true_profile, d600,
                 true_mz_um: float, published: tuple, highlight: dict, colours: tuple):
    """Fig. 21 (simulated): each layout's separated curves and roundness beside the published.

    One run's separated rotation error and profile for every layout at 600 r/min (polar), and the
    separated roundness of each layout beside the published values.  ``rotation_errors``,
    ``profiles``: per layout, one run's curves (um, offsets added); ``true_profile`` (um, offset
    added); ``d600``: the 600 r/min rows by layout; ``published``: (optimised value, [random
    values]); ``highlight``: the layouts drawn in colour (name -> colour; two, the paper's and
    the best, so that nine curves do not share one cycle of colours), every other layout in the
    context colour; ``colours``: (context, published).  The polar panels print no radius on the
    curves: their circles' spacing is written under each (the radii carry an arbitrary offset).
    """
    context, published_colour = colours
    pub_opt, pub_rand = published
    closed = np.r_[theta, theta[:1]]
    others = [n for n in layouts if n not in highlight]
    fig = plt.figure(figsize=(12, 4.2))
    polar = []
    for k, (curves, title) in enumerate(((rotation_errors, "separated rotation error, one run"),
                                         (profiles, "separated profile, one run"))):
        ax = fig.add_subplot(1, 3, k + 1, projection="polar")
        for name in others:   # context first, beneath
            v = curves[name]
            ax.plot(closed, np.r_[v, v[:1]], lw=0.6, color=context,
                    label=f"the other {len(others)} layouts" if name == others[0] else None)
        if k == 1:
            ax.plot(closed, np.r_[true_profile, true_profile[:1]], color="k", lw=2, alpha=0.3,
                    label="true profile")
        for name, colour in highlight.items():
            v = curves[name]
            ax.plot(closed, np.r_[v, v[:1]], lw=1.3, color=colour, label=name)
        ax.set_title(f"{title} (µm)", fontsize=9, pad=18)
        ax.tick_params(labelsize=7)
        ax.set_yticklabels([])   # the radii sat on the curves; their spacing is written below
        polar.append(ax)
    ax3 = fig.add_subplot(1, 3, 3)
    ax3.bar(range(len(d600)), d600.mz_mean_um, yerr=d600.mz_std_um, capsize=3,
            color=[highlight.get(n, context) for n in d600.index])
    ax3.axhline(true_mz_um, color="k", ls="--", lw=0.8, label="true (minimum zone)")
    ax3.scatter([0] + list(range(1, 1 + len(pub_rand))), [pub_opt] + list(pub_rand), marker="D",
                color=published_colour, zorder=3, label="published (Fig. 21)")
    ax3.set_xticks(range(len(d600)), list(d600.index), rotation=30, ha="right", fontsize=7)
    for tick, name in zip(ax3.get_xticklabels(), d600.index, strict=True):
        if name in highlight:
            tick.set_color(highlight[name])
            tick.set_fontweight("bold")
    ax3.set_ylabel("separated roundness, mean ± sd (µm)")
    ax3.legend(fontsize=7)
    fig.suptitle("Fig. 21 (SIMULATION): optimised against random probe angles at 600 r/min",
                 y=1.04)
    fig.tight_layout()
    for ax, offset in zip(polar, (2, 5), strict=True):
        ticks = ax.get_yticks()
        ax.text(0.5, -0.15, f"grid circles {ticks[1] - ticks[0]:g} µm apart (offset {offset} µm)",
                transform=ax.transAxes, ha="center", va="top", fontsize=7)
    # one legend for both polar plots, below them (inside, it covered the 225° label)
    handles, labels = polar[0].get_legend_handles_labels()
    true_h, true_l = polar[1].get_legend_handles_labels()
    keep = [i for i, lab in enumerate(true_l) if lab == "true profile"]
    fig.legend(handles + [true_h[i] for i in keep], labels + [true_l[i] for i in keep],
               fontsize=7, ncol=2, loc="upper center", bbox_to_anchor=(0.36, -0.02))
    return fig


#: Fig. 21's caption (simulated): every layout at 600 r/min (:func:`fig21_figure`).
FIG21 = Caption(
    "fig21_random_vs_optimised_angles_simulated", "Fig. 21",
    "Simulation at 600 r/min: separated rotation error (offset 2 µm) and profile (offset 5 µm), "
    "one run each, for the experiment's layout, {layout}; {n_random} random layouts in the "
    "recommended ranges; {other}; the GA's best run at k = {harmonic_k}; and the layouts "
    "minimising the worst q_k² over k = 2 to {worst_k} and 2 to {lowpass_harmonic}. Right: mean "
    "± sd over {n_measurements} simulated measurements of the minimum-zone roundness of a "
    "mandrel of {roundness_um:g} µm ({calibration}; dashed: its true roundness after the "
    "filter), published values as diamonds. The random layouts read {random_low:.2f} to "
    "{random_high:.2f} µm against {experiment:.2f} µm for the experiment's layout; the largest "
    "reading, {largest:.2f} µm, is that of \"{largest_layout}\", whose closest probes are "
    "{closest} samples apart. In colour: the experiment's layout and the other layout whose "
    "reading is nearest the truth (root mean square of its error, bias and scatter: "
    "\"{best_layout}\", {best_rms:.3f} µm, against {experiment_rms:.3f} µm); the rest in grey.")


def noise_transfer_figure(harmonics, mc_var, q2, *, noise_um: float, n_samples: int, colours):
    """Section 4's figure: each separated harmonic's noise variance against Eq. 18.

    Parameters
    ----------
    harmonics : array (K,)
        The harmonic orders k.
    mc_var : array (K,)
        Monte Carlo variance of the separated A_k, B_k (um^2).
    q2 : array (K,)
        The error transfer function q_k^2 at those orders.
    noise_um : float
        Probe noise standard deviation sigma (um).
    n_samples : int
        Samples per revolution N.
    colours : tuple
        (ours, published) colours.

    Returns
    -------
    matplotlib.figure.Figure
        The Monte Carlo points, ``2 q_k^2 sigma^2 / N`` and Eq. 18 as printed,
        ``2 q_k^2 sigma^2``, on a log scale.
    """
    reproduced, published = colours
    fig, ax = plt.subplots(figsize=(8, 3.4))
    ax.semilogy(harmonics, mc_var, "o", ms=3, color=reproduced,
                label="Monte Carlo var(A_k), var(B_k)")
    ax.semilogy(harmonics, 2 * q2 * noise_um ** 2 / n_samples, "-", color="k", lw=1,
                label="2 q_k^2 sigma^2 / N")
    ax.semilogy(harmonics, 2 * q2 * noise_um ** 2, "--", color=published, lw=1,
                label="Eq. 18 as printed: 2 q_k^2 sigma^2")
    ax.set_xlabel("harmonic k")
    ax.set_ylabel("variance (µm²)")
    ax.set_title("Noise of each separated harmonic against the transfer function "
                 f"(sigma = {noise_um} µm)")
    ax.legend(fontsize=8)
    return fig


#: The caption of :func:`noise_transfer_figure`'s figure.
NOISE_TRANSFER = Caption(
    "noise_transfer_function", "Beyond the paper",
    "Variance (µm²) of each separated harmonic coefficient, k = 2 to {k_max}, from {n_trials} "
    "Monte Carlo trials with white probe noise σ = {noise_um:g} µm on the simulation's layout "
    "(points), against 2 q_k² σ²/N (line) and Eq. 18 as printed, 2 q_k² σ² (dashed), which is "
    "N = {n_samples} times too large. The Monte Carlo follows q_k² (median ratio {ratio:.3f}), "
    "which is why H = q_k² is the right objective.")


def speed_curves_figure(theta, curves, truth, *, offset: float, speeds, title: str, colours):
    """Figs. 19-20 (simulated): one separated curve per speed beside the true one, in polar form.

    Parameters
    ----------
    theta : array (N,)
        Sample angles (rad).
    curves : array (n_speeds, n_measurements, N)
        The separated curves (um); the first measurement of each speed is drawn.
    truth : array (N,)
        The true curve (um).
    offset : float
        Added to every curve (um), to keep a polar plot's radii positive.
    speeds : sequence of int
        The spindle speeds (r/min), one per row of ``curves``.
    title : str
        The figure's title.
    colours : callable
        A colormap, ``colours(i)`` the colour of speed ``i``.

    Returns
    -------
    matplotlib.figure.Figure
        The polar plot: the true curve in grey, then one curve per speed.
    """
    closed = np.r_[theta, theta[:1]]
    fig = plt.figure(figsize=(4.4, 4.4))
    ax = fig.add_subplot(projection="polar")
    ax.plot(closed, np.r_[truth, truth[:1]] + offset, color="k", lw=2.5, alpha=0.3, label="true")
    for i, speed in enumerate(speeds):
        ax.plot(closed, np.r_[curves[i, 0], curves[i, 0, :1]] + offset, lw=0.8,
                color=colours(i), label=f"{speed} r/min")
    ax.tick_params(labelsize=6)
    ax.set_title(title, fontsize=9, pad=14)
    ax.legend(fontsize=6, loc="lower left", bbox_to_anchor=(-0.2, -0.18), ncol=3)
    return fig


#: Fig. 19's caption (simulated): the separated rotation error at every speed
#: (:func:`speed_curves_figure`).
FIG19 = Caption(
    "fig19_rotation_error_by_speed_simulated", "Fig. 19",
    "Simulation, not the paper's lathe experiment (no measured data are published): the "
    "separated rotation error (µm, polar) at {speeds} r/min with {layout}, low-pass filtered at "
    "harmonic {lowpass_harmonic}, with the true synchronous motion (the paper's printed rotation "
    "error) in grey. One simulated measurement per speed is drawn. The synchronous motion is "
    "the same at every speed by assumption, so the curves coincide by design; the scorecard row "
    "is not reproducible.")

#: Fig. 20's caption (simulated): the separated shape error at every speed
#: (:func:`speed_curves_figure`).
FIG20 = Caption(
    "fig20_shape_error_by_speed_simulated", "Fig. 20",
    "Simulation, not the paper's experiment: the separated shape error (µm, mean removed, "
    "offset 3 µm, polar) of a simulated mandrel of {roundness_um:g} µm minimum-zone roundness "
    "({calibration}) at the speeds of Table 2, {speeds} r/min, with {layout}, true profile in "
    "grey. One simulated measurement per speed is drawn. They coincide by design (same mandrel, "
    "speed-independent synchronous motion), so the scorecard row is not reproducible.")


# --- the chapter's figures, in the paper's order ---------------------------------------------

FIGURES = figures(
    Caption("fig03_set_profile", "Fig. 3",
            "The set profile of the paper's simulation (Section 1.3) as printed, drawn in polar "
            "form (µm): 20 + 1.2 cos θ − 0.8 sin θ + 0.2 sin 2θ + 0.5 cos 6θ − 0.8 cos 8θ + "
            "0.3 sin 13θ + 0.4 cos 20θ, sampled at N = {n_samples} points per revolution. A "
            "constructed test input, not a measurement.",
            rows=("Section 1.3*",)),
    Caption("fig04_set_rotation_error", "Fig. 4",
            "The set rotation error of the simulation as printed, δ(θ) = 1.3 + 0.1 cos(θ + π/4) "
            "+ 0.6 sin(2θ + π/12) + 0.2 cos 7θ − 0.4 cos(12θ + π/10) µm, in polar form. The "
            "paper does not say how this scalar becomes the motion (δx, δy) the probes see; the "
            "notebook takes it as {mapping_text}, and shows the alternatives in a table.",
            rows=("Section 1.3*",)),
    Caption("fig05_sensor_signals", "Fig. 5",
            "The four probe signals (µm) against the spindle angle θ, for probes at samples "
            "{positions} of {n_samples} ({angles}) reading the set profile of Fig. 3 plus the "
            "set rotation error of Fig. 4 under the {mapping} mapping. Simulated from the "
            "paper's printed functions; no noise.",
            rows=("Section 1.1", "Section 1.3*")),
    Caption("fig06_separated_set_reconstructed_profiles", "Fig. 6",
            "Left: the set profile (grey), the separated profile without its first harmonic "
            "(dashed) and the reconstructed profile (µm, polar). Right: their differences from "
            "the set profile. Separated minus set is the first harmonic the weights cancel "
            "(amplitude {first_harmonic_um:.2f} µm); reconstructed minus set is "
            "{reconstructed}. Uses Eq. 5's weights for a3 = {a3:g} (a1 = {a1:.4f}, a2 = "
            "{a2:.4f}), not the printed a1, a2, which do not cancel the motion; {mapping} "
            "mapping, {convention} first-harmonic convention. Both profiles keep the set mean: "
            "{mean_separated:.3f} and {mean_reconstructed:.3f} µm (printed: {printed_separated} "
            "and {printed_reconstructed} µm)."),
    Caption("fig07_separated_set_rotation_error", "Fig. 7",
            "Left: the set and the separated rotation error (µm, polar). Right: separated minus "
            "set against θ, {difference}. With the {mapping} mapping, the {convention} "
            "first-harmonic convention and Eq. 5's weights; under a mapping other than the "
            "radial one, the part of the motion that looks like a first harmonic goes to the "
            "profile instead."),
    FIG08,
    Caption("fig08_09_algorithms_compared", "Figs. 8-9",
            "Every algorithm at k = {harmonic_k}, {n_runs} runs each. Left: median best-so-far H "
            "of the improved and the traditional GA in {encoding} and in real encoding, a "
            "traditional GA at fixed (Pc, Pm) = ({pc_max:g}, {pm_min:g}), the improved GA with "
            "Eq. 23 as printed, and differential evolution. Right: box plots of the plateau "
            "generation, the paper's ~{published_improved:g} and ~{published_traditional:g} "
            "dashed. Median plateau generations: improved {improved:g} against traditional "
            "{traditional:g} ({encoding}), {improved_real:g} against {traditional_real:g} (real "
            "encoding); differential evolution {de:g}."),
    FIG09,
    Caption("fig08_09_settings_dependence", "Figs. 8-9",
            "The GA comparison of Figs. 8-9 under settings the paper does not state, at k = "
            "{harmonic_k} ({encoding} encoding, population {pop_size}, {n_runs} seeded runs per "
            "setting: a reduced study). Left: median plateau generation of the improved GA and of "
            "the traditional GA (fixed Pc = {pc:g}, Pm = {pm:g}) at {generation_counts} "
            "generations (improved GA: {improved_medians}), beside the paper's single-run "
            "~{published_improved:g} and ~{published_traditional:g} (dashed). Right: the "
            "improved GA's speed-up in plateau medians ({generations} generations) over a "
            "traditional GA at each fixed Pc ∈ {{{pcs}}} and Pm ∈ {{{pms}}}: from {low:.0f} % to "
            "{high:.0f} %, against the published {published_speedup} %.",
            rows=("Fig. 8", "Fig. 9", "Abstract, Figs. 8-9")),
    Caption("fig10_objective_vs_harmonic", "Fig. 10",
            "The optimum of the objective H = q_k² against the harmonic order k = 2 to {k_max}, "
            "in the recommended ranges: median and best of {n_runs} improved-GA runs per k, the "
            "best known H (differential evolution, polished), the bound 1/4 (dashed), Table 1's "
            "printed H at k = {table1_k} (diamonds) and the paper's Fig. 10 range {low} to "
            "{high} (shaded). The best known H exceeds 1/4 by more than 4 % only at k = {above}; "
            "the printed H furthest above ours is at k = {k_gap}: {printed_gap} against "
            "{ours_gap:.3f}.", key=True),
    Caption("fig11_angles_vs_harmonic", "Fig. 11",
            "The probe angles φ1, φ2, φ3 (rad) of the best improved-GA run at each k = 2 to "
            "{k_max}, reported as the canonical member of the layouts with equal H, beside Table "
            "1's printed angles (diamonds); dotted: the edges π/4 and 3π/2 of the recommended "
            "ranges. Many layouts give the same H, so the angles jump between neighbouring k and "
            "need not match the printed ones even where H does.",
            rows=("Table 1",)),
    Caption("fig12_weights_vs_harmonic", "Fig. 12",
            "The weights a1, a2, a3 of the same best runs (a0 = 1; a1, a2 from Eq. 15) against "
            "k, beside Table 1's printed weights (diamonds). Printed rows whose weights cannot "
            "give the printed H at any probe angles (the weights alone force a larger H): "
            "{impossible}.",
            rows=("Table 1",)),
    FIG19,
    FIG20,
    FIG21,
    Caption("eq06_matrix_eigenvalues", "Beyond the paper",
            "Magnitudes of the eigenvalues Λ_k of Eq. 6's circulant matrix (log scale) against "
            "k = 0 to {k_max}, for the simulation's layout (samples {positions} of {n_samples}, "
            "a3 = {a3:g}, a1 and a2 from Eq. 5) and a symmetric layout ({symmetric}); values "
            "below {roundoff:g} are zeros up to round-off, harmonics the weights cancel. The "
            "simulation's layout cancels these harmonics: {cancelled} (and N − k each): rank "
            "{rank} = N − {deficit}, not N as printed. The symmetric layout cancels these: "
            "{symmetric_cancelled}."),
    NOISE_TRANSFER,
    Caption("worst_case_transfer_functions", "Beyond the paper",
            "The error transfer function q_k², k = 2 to {k_max}, of the simulation's layout, the "
            "best known optimum at k = {harmonic_k}, the GA's best run at k = {harmonic_k}, and "
            "the layouts minimising the worst q_k² over k = 2 to {worst_k} (shaded) on the full "
            "circle and in the recommended ranges{coincide}. Dashed: bound 1/4; dotted: floor "
            "(N − 3)/N. Within 2 to {worst_k} the worst q_k² is {ga:.0f} for the GA run, "
            "{optimum:.1f} for the optimum, {worst_case:.2f} for the worst-case layout in the "
            "recommended ranges."),
    Caption("least_squares_vs_weighted", "Beyond the paper",
            "Noise amplification per harmonic of the paper's weighted method (q_k², solid) and "
            "of least squares over the four probes (dashed), for the simulation's layout and the "
            "worst-case layouts of the previous figure{coincide}. Least squares is never worse "
            "(Gauss-Markov): over k = 2 to {worst_k} its worst case is {least_squares:.1f} "
            "against {weighted:.1f} for the simulation's layout, and with σ = {noise_um:g} µm it "
            "leaves {rms_least_squares:.2f} µm rms in the profile against {rms_weighted:.2f} µm."),
)
