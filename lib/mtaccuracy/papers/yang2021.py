"""Notebook 05 (Yang et al. 2021): the checks of its parameters, its analyses and its figures.

The method itself (four-point separation, the error transfer function, the GAs, the simulated
lathe experiment) is :mod:`mtaccuracy.spindle`; this module holds what serves the paper's audit:
Table 1's consistency check, the GA settings study, the printed Eq. 17 against its inverse, the
scorecard's texts and inputs, the figures drawn here with their captions (:data:`FIGURES`, in
the paper's order) and the notebook's declaration of its parameters (:class:`Parameters`).
"""

from __future__ import annotations

import itertools

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import param

from .. import spindle as sp
from .figure import Caption, figures
from .parameters import NotebookParameters, NumberList, OutputFolder, ParameterError
from .printed import half_unit

__all__ = ["difference_text", "eq17_sign_check", "experiment_genes", "experiment_inputs",
           "ga_settings_study", "layout_text", "least_squares_vs_weighted",
           "mappings_and_conventions", "noise_transfer_figure", "ranges_statement",
           "single_run_speedups", "speed_curves_figure", "table1_consistency_texts"]


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


def table1_consistency(t1, sweep):
    """Table 1 against Eqs. 15, 20 and our optimum, row by printed row.

    For every printed row, H and the weights of every parameter set that rounds to the printed
    one (a 21^4 grid over half a unit of the last printed digit), the weights-only bound of H,
    and our GA and best known optima at that k.  ``t1``: the published table (strings);
    ``sweep``: the optimum per harmonic order.
    """
    rows = []
    g = np.linspace(-1, 1, 21)
    grid = np.stack(np.meshgrid(g, g, g, g, indexing="ij"), -1).reshape(-1, 4)
    for _, r in t1.iterrows():
        k = int(r.k)
        cols = ["phi1_rad", "phi2_rad", "phi3_rad", "a3"]
        centre = np.array([float(r[c]) for c in cols])
        half = np.array([half_unit(r[c]) for c in cols])
        x = centre + grid * half                            # every value that rounds to the printed
        h = sp.objective_H(x, k)
        a1_, a2_ = sp.weights(x[:, :3], x[:, 3])
        w_pr = np.array([float(r[c]) for c in ("a1", "a2", "a3")])
        w_bound = float(sp.weights_bound_H(w_pr, [half_unit(r[c]) for c in ("a1", "a2", "a3")]))
        ours = sweep.set_index("k").loc[k]
        rows.append(dict(k=k, published_H=float(r.H),
                         H_of_printed_parameters=float(sp.objective_H(centre, k)),
                         H_min_within_rounding=h.min(), H_max_within_rounding=h.max(),
                         H_weights_only_bound=w_bound,
                         published_a1=float(r.a1), eq15_a1_min=a1_.min(), eq15_a1_max=a1_.max(),
                         published_a2=float(r.a2), eq15_a2_min=a2_.min(), eq15_a2_max=a2_.max(),
                         ours_H_ga=ours.H_ga_best, ours_H_best_known=ours.H_best_known,
                         ours_phi1=ours.phi1, ours_phi2=ours.phi2, ours_phi3=ours.phi3,
                         ours_a1=ours.a1, ours_a2=ours.a2, ours_a3=ours.a3))
    table1 = pd.DataFrame(rows)
    table1["H_consistent"] = (table1.published_H >= table1.H_min_within_rounding - 5e-4) & \
                             (table1.published_H <= table1.H_max_within_rounding + 5e-4)
    table1["a1_consistent"] = (table1.published_a1 >= table1.eq15_a1_min - 5e-4) & \
                              (table1.published_a1 <= table1.eq15_a1_max + 5e-4)
    table1["abs_a1_consistent"] = (table1.published_a1 >= -table1.eq15_a1_max - 5e-4) & \
                                  (table1.published_a1 <= -table1.eq15_a1_min + 5e-4)
    table1["a2_consistent"] = (table1.published_a2 >= table1.eq15_a2_min - 5e-3) & \
                              (table1.published_a2 <= table1.eq15_a2_max + 5e-3)
    # possible for the printed weights with some angles: the printed H (+ half its last digit)
    # reaches the bound
    table1["H_possible_for_the_weights"] = (table1.published_H + t1.H.map(half_unit).to_numpy()
                                            >= table1.H_weights_only_bound)
    return table1


def fig21_figure(theta, layouts, *, rotation_errors, profiles, true_profile, d600,
                 true_mz_um: float, published: tuple, colours):
    """Fig. 21 (simulated): each layout's separated curves and roundness beside the published.

    One run's separated rotation error and profile for every layout at 600 r/min (polar), and the
    separated roundness of each layout beside the published values.  ``rotation_errors``,
    ``profiles``: per layout, one run's curves (um, offsets added); ``true_profile`` (um, offset
    added); ``d600``: the 600 r/min rows by layout; ``published``: (optimised value, [random
    values]); ``colours``: (colormap, published).
    """
    cmap, published_colour = colours
    pub_opt, pub_rand = published
    closed = np.r_[theta, theta[:1]]
    fig = plt.figure(figsize=(12, 4.2))
    ax = fig.add_subplot(1, 3, 1, projection="polar")
    for i, name in enumerate(layouts):
        v = rotation_errors[name]
        ax.plot(closed, np.r_[v, v[:1]], lw=1.2 if i == 0 else 0.7, color=cmap(i), label=name)
    ax.set_title("separated rotation error, one run (µm, offset 2)", fontsize=9, pad=18)
    ax.tick_params(labelsize=6)
    ax2 = fig.add_subplot(1, 3, 2, projection="polar")
    for i, name in enumerate(layouts):
        v = profiles[name]
        ax2.plot(closed, np.r_[v, v[:1]], lw=1.2 if i == 0 else 0.7, color=cmap(i))
    ax2.plot(closed, np.r_[true_profile, true_profile[:1]], color="k", lw=2, alpha=0.3,
             label="true")
    ax2.set_title("separated profile, one run (µm, offset 5)", fontsize=9, pad=18)
    ax2.tick_params(labelsize=6)
    ax3 = fig.add_subplot(1, 3, 3)
    ax3.bar(range(len(d600)), d600.mz_mean_um, yerr=d600.mz_std_um,
            color=[cmap(i) for i in range(len(d600))], capsize=3)
    ax3.axhline(true_mz_um, color="k", ls="--", lw=0.8, label="true (minimum zone)")
    ax3.scatter([0] + list(range(1, 1 + len(pub_rand))), [pub_opt] + list(pub_rand), marker="D",
                color=published_colour, zorder=3, label="published (Fig. 21)")
    ax3.set_xticks(range(len(d600)), list(d600.index), rotation=30, ha="right", fontsize=7)
    ax3.set_ylabel("separated roundness, mean ± sd (µm)")
    ax3.legend(fontsize=7)
    fig.suptitle("Fig. 21 (SIMULATION): optimised against random probe angles at 600 r/min",
                 y=1.04)
    fig.tight_layout()
    # one legend for both polar plots, below them (inside, it covered the 225° label)
    handles, labels = ax.get_legend_handles_labels()
    true_h, true_l = ax2.get_legend_handles_labels()
    fig.legend(handles + true_h, labels + [f"{t} profile" for t in true_l], fontsize=7,
               ncol=4, loc="upper center", bbox_to_anchor=(0.36, 0.02))
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
    "{closest} samples apart.")


def experiment_genes(facts):
    """The layout of the paper's lathe experiment, as printed: genes ``(phi_1, phi_2, phi_3, a_3)``.

    From ``data/papers/yang2021_facts.csv`` (Table 1's k = 20 row, which Section 3 says the
    experiment used); ``a_1, a_2`` are left to Eq. 15.

    Parameters
    ----------
    facts : pandas.Series
        The published facts indexed by quantity (strings): ``experiment_angles`` (three angles,
        rad, separated by spaces) and ``experiment_a3``.

    Returns
    -------
    numpy.ndarray
        ``(4,)``: the three angles (rad) and ``a_3``.

    Raises
    ------
    ValueError
        ``experiment_angles`` does not hold three angles.
    """
    phi = [float(v) for v in str(facts["experiment_angles"]).split()]
    if len(phi) != 3:
        raise ValueError(f"yang2021_facts.csv: experiment_angles needs 3 angles, got {phi}")
    return np.array([*phi, float(facts["experiment_a3"])])


def layout_text(name: str, genes, positions, *, n_samples: int) -> str:
    """A probe layout as a caption states it: what it is, its genes and its sample positions.

    Parameters
    ----------
    name : str
        What the layout is (``"our best known optimum at k = 20"``).
    genes : array (4,)
        ``(phi_1, phi_2, phi_3, a_3)`` (rad, rad, rad, 1); ``a_1, a_2`` follow from Eq. 15.
    positions : sequence of int
        The sample positions the angles are rounded to, the first probe's (0) included.
    n_samples : int
        Samples per revolution.

    Returns
    -------
    str
        ``"<name> (φ = 0.522, 3.45, 5.47 rad, a3 = 1.39, a1 and a2 from Eq. 15, rounded to
        samples 0, 11, 70, 111 of 128)"``: three significant digits.
    """
    genes = np.asarray(genes, dtype=float)
    phi = ", ".join(f"{v:.3g}" for v in genes[:3])
    return (f"{name} (φ = {phi} rad, a3 = {genes[3]:.3g}, a1 and a2 from Eq. 15, rounded to "
            f"samples {', '.join(str(int(p)) for p in positions)} of {n_samples})")


def experiment_inputs(card, mandrel_roundness_um: float, calibration_um: float):
    """Declare the simulated lathe experiment's inputs on ``card``; ``(mandrel, simulation, sync)``.

    The mandrel is ``constructed`` when its roundness is the paper's calibration value (the
    value Table 2's shape errors, Fig. 21 and the abstract's deviation are compared with: the
    simulation then returns it by design), else ``simulated``; the noise, the asynchronous
    motion and the layouts are ``simulated``; the synchronous motion, the printed Section 1.3
    rotation error at every speed, is ``assumed``: it makes the separated curves coincide
    across speeds (Figs. 19-20) by design.

    Parameters
    ----------
    card : Card
        The scorecard (``mtaccuracy.compendium.reproduction.Card``, or anything with its
        ``constructed``, ``simulated`` and ``assumed`` methods).
    mandrel_roundness_um : float
        The simulated mandrel's minimum-zone roundness (um).
    calibration_um : float
        The paper's calibration value (um).

    Returns
    -------
    mandrel, simulation, sync : Input
        The inputs the card declared, for the rows' ``uses``.
    """
    at_calibration = abs(float(mandrel_roundness_um) - float(calibration_um)) <= 1e-12
    what = f"a mandrel of minimum-zone roundness {mandrel_roundness_um:g} um"
    if at_calibration:
        mandrel = card.constructed(
            "simulated mandrel at the calibration roundness",
            targets=["Table 2 (simulated)*", "Abstract (simulated)*", "Fig. 21 (simulated)*"],
            how=f"{what}, set to the paper's calibration value {calibration_um:g} um, the value "
                "Table 2, Fig. 21 and the abstract's deviation are compared with")
    else:
        mandrel = card.simulated("simulated mandrel", how=f"{what} (not the paper's calibration "
                                                          f"value {calibration_um:g} um)")
    simulation = card.simulated(
        "simulated lathe experiment",
        how="asynchronous motion, probe noise, acquisition, filter and layouts as assumed in "
            "Section 9; the paper publishes no measured data")
    same_sync = card.assumed(
        "synchronous motion the same at every speed",
        settles=["Fig. 19 (simulated)*", "Fig. 20 (simulated)*"],
        how="the printed Section 1.3 rotation error is the synchronous motion at every speed and "
            "the mandrel is one object, so the separated mean curves of the four speeds agree by "
            "design, up to the noise")
    return mandrel, simulation, same_sync


def ga_settings_study(k: int, *, bounds, generation_counts, pc_values, pm_values,
                      traditional_pc: float, traditional_pm: float, generations: int,
                      n_runs: int, pop_size: int, encoding: str, seed: int):
    """How the GA comparison of Figs. 8-9 depends on settings the paper omits.

    The plateau generation (:func:`~mtaccuracy.spindle.convergence_generation`, 0.1 % of the final
    best) of the improved and the traditional GA at every count of ``generation_counts``, and the
    speed-up of the improved GA (``generations``) over a traditional GA at every fixed ``(pc, pm)``
    of ``pc_values`` x ``pm_values``.  ``n_runs`` seeded runs per setting, each setting its own seed
    (``seed + 100 + i`` in table order).

    Parameters
    ----------
    k : int
        The harmonic order optimised.
    bounds : sequence of 4 (low, high)
        The search box of the genes ``(phi_1, phi_2, phi_3, a_3)``.
    generation_counts : sequence of int
        The generation counts compared (both GAs).
    pc_values, pm_values : sequence of float
        The traditional GA's fixed crossover and mutation probabilities compared.
    traditional_pc, traditional_pm : float
        The traditional GA's probabilities in the generation-count study.
    generations : int
        The generation count of the fixed-rates study.
    n_runs : int
        Seeded runs per setting.
    pop_size : int
        Population size (even).
    encoding : str
        ``"binary"`` or ``"real"``.
    seed : int
        The first setting's seed is ``seed + 100``.

    Returns
    -------
    pandas.DataFrame
        One row per setting: ``study`` ("generation count" or "fixed rates"), ``generations``,
        ``pc``, ``pm`` (the traditional GA's), ``runs``, the plateau medians of both GAs
        (``improved_median``, ``traditional_median``) and ``speedup_percent``
        (:func:`~mtaccuracy.spindle.speedup`).
    """
    common = dict(bounds=bounds, n_runs=n_runs, pop_size=pop_size, encoding=encoding)
    seeds = itertools.count(seed + 100)

    def plateau(res):
        return sp.convergence_generation(res.history, res.history[-1], 1e-3)

    rows, base = [], None
    for g in generation_counts:
        imp = plateau(sp.run_ga(k, adaptive=True, generations=int(g), seed=next(seeds), **common))
        trad = plateau(sp.run_ga(k, adaptive=False, pc=traditional_pc, pm=traditional_pm,
                                 generations=int(g), seed=next(seeds), **common))
        if int(g) == int(generations):
            base = imp
        rows.append(dict(study="generation count", generations=int(g), pc=traditional_pc,
                         pm=traditional_pm, runs=n_runs, improved_median=np.median(imp),
                         traditional_median=np.median(trad), speedup_percent=sp.speedup(imp, trad)))
    if base is None:
        base = plateau(sp.run_ga(k, adaptive=True, generations=int(generations), seed=next(seeds),
                                 **common))
    for pc in pc_values:
        for pm in pm_values:
            trad = plateau(sp.run_ga(k, adaptive=False, pc=float(pc), pm=float(pm),
                                     generations=int(generations), seed=next(seeds), **common))
            rows.append(dict(study="fixed rates", generations=int(generations), pc=float(pc),
                             pm=float(pm), runs=n_runs, improved_median=np.median(base),
                             traditional_median=np.median(trad),
                             speedup_percent=sp.speedup(base, trad)))
    return pd.DataFrame(rows)


def single_run_speedups(improved, traditional):
    """The speed-up (percent) one run of each algorithm would show, as Figs. 8-9 do, every pair.

    Parameters
    ----------
    improved : array (runs,)
        The improved GA's convergence generations ``g_i``.
    traditional : array (runs,)
        The traditional GA's convergence generations ``g_t``; those at 0 are left out.

    Returns
    -------
    numpy.ndarray
        ``100 (1 - g_i / g_t)`` for every pair with ``g_t > 0``, improved-major; shape
        ``(n_improved * n_traditional_positive,)``.
    """
    gi = np.asarray(improved, float)[:, None]
    gt = np.asarray(traditional, float)
    gt = gt[gt > 0][None, :]
    return (100 * (1 - gi / gt)).ravel()


#: How a caption states each mapping of :data:`~mtaccuracy.spindle.MAPPINGS` (the scalar
#: rotation error to the motion the probes see).
MAPPING_TEXT = {"radial": "purely radial, δx = δ cos θ, δy = δ sin θ (the inverse of Eq. 9)",
                "radial_reversed": "radial along the direction turning with the workpiece, "
                                   "δx = δ cos θ, δy = −δ sin θ",
                "x_only": "along a fixed direction, the first probe's: δx = δ, δy = 0"}


def difference_text(difference: float, scale: float, *, roundoff: float) -> str:
    """How a caption states the largest difference between two curves: round-off, or its size.

    Parameters
    ----------
    difference : float
        The largest absolute difference (um).
    scale : float
        The largest absolute value of the curves compared (um).
    roundoff : float
        The fraction of ``scale`` below which a difference is round-off.

    Returns
    -------
    str
        ``"zero"``; ``"of order 1e-14 µm: round-off"`` (the power of ten at or below the
        difference) when it is below ``roundoff * scale``; else ``"up to 0.0123 µm"``.
    """
    d = abs(float(difference))
    if d == 0:
        return "zero"
    if d < roundoff * abs(float(scale)):
        return f"of order {10.0 ** np.floor(np.log10(d)):.0e} µm: round-off"
    return f"up to {d:.3g} µm"


def mappings_and_conventions(profile, delta, *, phi, weights, positions):
    """Section 1.3's simulation under every mapping and first-harmonic convention: means, errors.

    The printed set profile and scalar rotation error are turned into probe signals under each
    mapping of :data:`~mtaccuracy.spindle.MAPPINGS` (the paper does not say which) and separated
    under both first-harmonic conventions; the means the paper prints beside Figs. 6-7 and the
    largest differences from the set curves, for every pair.

    Parameters
    ----------
    profile : array (N,)
        The set profile (um), sampled uniformly over one revolution.
    delta : array (N,)
        The set scalar rotation error (um).
    phi : array (4,)
        Probe angles (rad), the first 0.
    weights : array (4,)
        The weights a_0..a_3 (Eq. 5).
    positions : sequence of 4 int
        Probe sample positions p_0..p_3.

    Returns
    -------
    pandas.DataFrame
        One row per mapping and convention (``mapping``, ``convention``): ``mean_set_profile``,
        ``mean_separated`` (no first harmonic), ``mean_reconstructed``, ``mean_set_error``,
        ``mean_separated_error``, ``max_profile_error`` and ``max_error_motion_error`` (um).
    """
    rows = []
    for mp in sp.MAPPINGS:
        dxm, dym, inv = sp.motion_from_scalar(delta, mp)
        y_m = sp.probe_signals(profile, dxm, dym, positions)
        for conv in ("radial", "eccentricity"):
            s_m = sp.separate_details(y_m, phi, weights, first_harmonic=conv)
            d_m = inv(s_m.dx, s_m.dy)
            rows.append(dict(mapping=mp, convention=conv, mean_set_profile=profile.mean(),
                             mean_separated=s_m.profile_no_first.mean(),
                             mean_reconstructed=s_m.profile.mean(), mean_set_error=delta.mean(),
                             mean_separated_error=d_m.mean(),
                             max_profile_error=np.abs(s_m.profile - profile).max(),
                             max_error_motion_error=np.abs(d_m - delta).max()))
    return pd.DataFrame(rows)


def eq17_sign_check(theta, phi, weights, *, k: int, a: float, b: float):
    """Eq. 17 as printed, with its sign fixed, and the exact inverse, on one known harmonic.

    The weighted signal of a profile ``a cos k theta + b sin k theta`` is built under Eq. 11's
    convention ``r(theta + phi)`` and under the one Eq. 13's coefficients belong to,
    ``r(theta - phi)``; its Fourier coefficients ``F_k, G_k`` (normalised as in Eq. 17,
    ``2/N sum``) are inverted three ways: Eq. 17 as printed, ``-(lambda F + mu G)/|Lambda|^2``
    and ``(mu F - lambda G)/|Lambda|^2``; with its sign fixed; and the exact inverse of each
    convention (under Eq. 11's, ``mu`` changes sign).

    Parameters
    ----------
    theta : array (N,)
        Sample angles (rad), uniform over one revolution.
    phi : array (4,)
        Probe angles (rad).
    weights : array (4,)
        The weights a_0..a_3.
    k : int
        The harmonic order checked.
    a, b : float
        The profile's true cosine and sine coefficients A_k, B_k.

    Returns
    -------
    pandas.DataFrame
        One row per convention (``model``): ``A_true``, ``B_true`` and the ``A_``/``B_``
        estimates ``eq17_printed``, ``eq17_sign_fixed`` and ``inverse_of_this_model``.
    """
    n = len(theta)
    lam_k = sp.eigenvalues(phi, weights, [k])[0]
    l_, m_ = lam_k.real, lam_k.imag
    den = l_ ** 2 + m_ ** 2
    rows = []
    for model, sgn in (("Eq. 11: r(theta + phi)", 1), ("Eq. 13: r(theta - phi)", -1)):
        yk = sum(weights[j] * (a * np.cos(k * (theta + sgn * phi[j]))
                               + b * np.sin(k * (theta + sgn * phi[j]))) for j in range(4))
        f_k = 2 / n * (yk * np.cos(k * theta)).sum()
        g_k = 2 / n * (yk * np.sin(k * theta)).sum()
        fixed = ((l_ * f_k + m_ * g_k) / den, (l_ * g_k - m_ * f_k) / den)
        exact = ((l_ * f_k - m_ * g_k) / den, (l_ * g_k + m_ * f_k) / den) if sgn == 1 else fixed
        rows.append(dict(model=model, A_true=a, B_true=b,
                         A_eq17_printed=-(l_ * f_k + m_ * g_k) / den,
                         B_eq17_printed=(m_ * f_k - l_ * g_k) / den,
                         A_eq17_sign_fixed=fixed[0], B_eq17_sign_fixed=fixed[1],
                         A_inverse_of_this_model=exact[0], B_inverse_of_this_model=exact[1]))
    return pd.DataFrame(rows)


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


def table1_consistency_texts(row, printed_row):
    """The scorecard texts of one Table 1 row's check: do the printed parameters give its H?

    Parameters
    ----------
    row : pandas.Series
        One row of :func:`table1_consistency`.
    printed_row : pandas.Series
        The same row of the published Table 1 (strings): ``H``, ``phi1_rad``..``phi3_rad``,
        ``a1``..``a3``.

    Returns
    -------
    printed : str
        The printed H and parameters.
    ours : str
        What the printed parameters give: the weights-only bound where the printed H is below
        it, else the range of H within the rounding of the printed angles and a3.
    holds : bool
        The printed H is possible for the printed weights, and the printed H and weights lie in
        the ranges of Eqs. 15 and 20 within the printed rounding (a1 perhaps up to its sign).
    note : str
        Why, with the weights-only bound.
    """
    r, pr = row, printed_row
    printed = (f"H = {pr.H} at phi = ({pr.phi1_rad}, {pr.phi2_rad}, {pr.phi3_rad}), "
               f"a = (1, {pr.a1}, {pr.a2}, {pr.a3})")
    bound_note = ("weights-only bound (1 + sum a^2) / (1 + sum |a|)^2 over every weight that "
                  f"rounds to the printed ones: H >= {r.H_weights_only_bound:.4f} for every "
                  "probe-angle choice")
    if not r.H_possible_for_the_weights:
        return (printed, "impossible: the printed weights force H >= "
                         f"{r.H_weights_only_bound:.3f} at any angles", False, bound_note)
    ok = bool(r.H_consistent) and (bool(r.a1_consistent) or bool(r.abs_a1_consistent)) \
        and bool(r.a2_consistent)
    ours = (f"H {r.H_min_within_rounding:.3f}..{r.H_max_within_rounding:.3f} within the "
            "rounding of the printed angles and a3")
    note = (("consistent" if ok else "not consistent")
            + " with Eqs. 15 and 20 within the printed rounding")
    if ok and not r.a1_consistent:
        note += " once the sign of a1 is restored"
    note += f"; the weights alone allow it ({bound_note})"
    return printed, ours, ok, note


def least_squares_vs_weighted(layouts, harmonics):
    """The noise amplification of the paper's weighted sum against least squares over the probes.

    Parameters
    ----------
    layouts : dict
        Layout name -> genes ``(phi_1, phi_2, phi_3, a_3)`` (rad, rad, rad, 1); the weights
        a_1, a_2 follow from Eq. 15.
    harmonics : array (K,)
        The harmonic orders compared (the protected band).

    Returns
    -------
    pandas.DataFrame
        One row per layout, in the given order: ``layout``, the worst and the mean over
        ``harmonics`` of q_k^2 (``worst_q2_weighted``, ``mean_q2_weighted``) and of the
        least-squares amplification (``worst_q2_least_squares``, ``mean_q2_least_squares``).
    """
    rows = []
    for name, x in layouts.items():
        q2w = sp.transfer(x[:3], sp.full_weights(x[:3], x[3]), harmonics)
        q2l = sp.least_squares_transfer(x[:3], harmonics)
        rows.append(dict(layout=name, worst_q2_weighted=q2w.max(),
                         worst_q2_least_squares=q2l.max(), mean_q2_weighted=q2w.mean(),
                         mean_q2_least_squares=q2l.mean()))
    return pd.DataFrame(rows)


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


def ranges_statement(sweep, k_lost, h_lost, *, k_tab: int, band_text: str):
    """Section 3's recommended ranges against Fig. 10's band, at every order Table 1 covers.

    The best known H in the ranges at the orders of the sweep from Table 1's smallest on and at
    the orders of its lost second part, against the printed upper edge of Fig. 10's band (plus
    half a unit of its last digit); the lower orders, which the paper does not tabulate, are
    named in the note.

    Parameters
    ----------
    sweep : pandas.DataFrame
        The optimum per harmonic order: ``k``, ``H_best_known``.
    k_lost : array of int
        The orders of Table 1's second part, whose values are lost in the text.
    h_lost : array, same length as ``k_lost``
        The best known H at those orders.
    k_tab : int
        The smallest order Table 1 tabulates.
    band_text : str
        The upper edge of Fig. 10's band, as printed.

    Returns
    -------
    ours : str
        At how many orders the best known H lies within the band, and where it does not.
    holds : bool
        Within the band at every such order.
    note : str
        How close to 1/4, and the lower orders.
    """
    top = float(band_text) + half_unit(band_text)
    ranges_k = np.r_[sweep.k[sweep.k >= k_tab], k_lost]
    ranges_h = np.r_[sweep.H_best_known[sweep.k >= k_tab], h_lost]
    above = ranges_k[ranges_h > top]
    low = sweep[sweep.k < k_tab].set_index("k").H_best_known
    ours = (f"best known H in the ranges within Fig. 10's band (<= {band_text}) at "
            f"{len(ranges_k) - len(above)} of {len(ranges_k)} orders k = "
            f"{k_tab}..{int(sweep.k.max())} and {' '.join(map(str, k_lost))}"
            + (f"; above it at k = {' '.join(map(str, above))}" if len(above) else ""))
    note = (f"within {100 * (ranges_h / 0.25 - 1).max():.1f} % of 1/4 there; below Table 1's "
            f"smallest order the ranges give up to {low.max():.3f} (k = {int(low.idxmax())}; "
            f"above the band at k = {' '.join(map(str, low.index[low > top])) or 'none'}); "
            f"Table 1's second part (k = {min(k_lost)}..{max(k_lost)}) is lost in the text, so "
            "its H are ours only; the ranges exclude the pair layouts that reach 1/4 at even k "
            "on the full circle; every Table 1 layout lies inside them")
    return ours, bool(above.size == 0), note


class Parameters(NotebookParameters):
    """Notebook 05: Yang et al. 2021, four-point spindle error separation and the GA."""

    stem = "05_yang2021_spindle_four_point_ga"
    seed = param.Integer(2021, bounds=(0, 4294967295), doc="seed of every random draw")
    n_samples = param.Integer(128, bounds=(32, 1024),
                              doc="samples per revolution, Section 1.3 (paper: 128)")
    probe_positions = NumberList([0, 14, 65, 116], item_type=int, bounds=(4, 4),
                                 item_bounds=(0, 1023),
                                 doc="probe sample positions p_0..p_3 (paper: 0 14 65 116)")
    a3 = param.Number(1.953, bounds=(-10.0, 10.0),
                      doc="a3 of Section 1.3 (paper: 1.953); a1, a2 follow from Eq. 5")
    mapping = param.Selector(default="radial", objects=["radial", "radial_reversed", "x_only"],
                             doc="scalar rotation error to (dx, dy), not stated in the paper")
    first_harmonic = param.Selector(default="radial", objects=["radial", "eccentricity"],
                                    doc="how the first harmonic is split from the motion")
    noise_um = param.Number(0.1, bounds=(0.0, 10.0), doc="sensor noise sd of the noise study (µm)")
    n_noise_trials = param.Integer(2000, bounds=(50, 20000),
                                   doc="Monte Carlo trials of the noise study")
    harmonic_k = param.Integer(20, bounds=(2, 200),
                               doc="harmonic order of Figs. 8-9 (paper: 20)")
    n_ga_runs = param.Integer(64, bounds=(30, 1024), doc="runs per algorithm for Figs. 8-9")
    pop_size = param.Integer(50, bounds=(4, 500), doc="GA population size, even (not stated)")
    generations = param.Integer(200, bounds=(20, 2000),
                                doc="generations alpha_max (not stated in the paper)")
    encoding = param.Selector(default="binary", objects=["binary", "real"],
                              doc="GA encoding (not stated in the paper)")
    traditional_pc = param.Number(0.8, bounds=(0.0, 1.0),
                                  doc="crossover probability of the traditional GA (not stated)")
    traditional_pm = param.Number(0.05, bounds=(0.0, 1.0),
                                  doc="mutation probability of the traditional GA (not stated)")
    n_study_runs = param.Integer(32, bounds=(8, 1024),
                                 doc="runs per setting of the GA settings study (Section 6)")
    study_generations = NumberList([120, 200, 300], item_type=int, item_bounds=(20, 2000),
                                   doc="generation counts of the settings study")
    study_pc = NumberList([0.6, 0.8, 0.99], item_type=float, item_bounds=(0.0, 1.0),
                          doc="crossover probabilities of the settings study")
    study_pm = NumberList([0.005, 0.01, 0.05, 0.09], item_type=float, item_bounds=(0.0, 1.0),
                          doc="mutation probabilities of the settings study")
    converge_tol = param.Number(0.01, bounds=(0.0, 1.0), inclusive_bounds=(False, True),
                                doc="converged: best H within this fraction of the best known")
    a3_max = param.Number(3.0, bounds=(0.1, 100.0), inclusive_bounds=(False, True),
                          doc="a3 is searched in [0.1, a3_max] (not stated in the paper)")
    k_sweep_max = param.Integer(80, bounds=(80, 200),
                                doc="Table 1 and Figs. 10-12 cover k from 2 to this")
    n_sweep_runs = param.Integer(8, bounds=(1, 32),
                                 doc="improved-GA runs per harmonic order in the sweep")
    worst_k = param.Integer(20, bounds=(3, 511),
                            doc="the worst-case objective protects harmonics 2 to this")
    exp_n_samples = param.Integer(128, bounds=(32, 1024),
                                  doc="samples per revolution of the simulated experiment")
    mandrel_roundness_um = param.Number(3.0, bounds=(0.0, 100.0), inclusive_bounds=(False, True),
                                        doc="roundness of the simulated mandrel (paper: 3 µm)")
    exp_noise_um = param.Number(0.1, bounds=(0.0, 10.0),
                                doc="probe noise sd per sample, simulated experiment (µm)")
    async_um = param.Number(0.2, bounds=(0.0, 10.0),
                            doc="rms asynchronous error motion per axis at 600 r/min (µm)")
    async_exponent = param.Number(1.0, bounds=(0.0, 4.0),
                                  doc="asynchronous motion grows as (speed / 600) ** this")
    duration_s = param.Number(1.0, bounds=(0.0, 60.0), inclusive_bounds=(False, True),
                              doc="acquisition time of one measurement (s)")
    interleave = param.Integer(2, bounds=(1, 16),
                               doc="revolutions per full set of angles (Eqs. 1-2)")
    lowpass_harmonic = param.Integer(50, bounds=(2, 512),
                                     doc="low-pass FFT filter: harmonics above this removed")
    n_measurements = param.Integer(20, bounds=(3, 500),
                                   doc="repeated measurements per speed and layout")
    n_random_layouts = param.Integer(3, bounds=(1, 20),
                                     doc="random probe layouts of Fig. 21 (paper: 3)")
    exp_layout = param.Selector(default="paper", objects=["paper", "ours"],
                                doc="layout of the simulated experiment: the paper's or ours")
    output_dir = OutputFolder("figures/05_yang2021_spindle_four_point_ga",
                              doc="where figures and tables go")

    def memory_bytes(self) -> float:
        # libraries and figures, the noise study (8 arrays of 4 N (trials + 4 N) numbers), the
        # binary GA's random bits (4 arrays of 64 per individual and run), the GA histories, the
        # simulated experiment; 0.47 GB at the defaults, 0.33 GB measured
        runs = max(self.n_ga_runs, (self.k_sweep_max - 1) * self.n_sweep_runs)
        histories = (self.k_sweep_max - 1) * self.n_sweep_runs + 7 * self.n_ga_runs
        experiment = self.n_measurements * (self.duration_s * 50 + self.interleave)
        return (3e8 + 8 * 4 * self.n_samples * (self.n_noise_trials + 4 * self.n_samples) * 8
                + 8 * 64 * self.pop_size * runs * 4
                + 8 * (self.generations + 1) * histories * 2
                + 8 * 16 * experiment * self.exp_n_samples)

    def check(self) -> None:
        stem, n, n_exp = self.stem, self.n_samples, self.exp_n_samples
        positions = self.probe_positions
        if len(positions) != 4 or positions[0] != 0 or max(positions) >= n \
                or len(set(positions)) != 4:
            raise ParameterError(f"{stem}: probe_positions must be 4 distinct sample indices in "
                                 f"0..{n - 1} starting with 0, got {positions}")
        if self.lowpass_harmonic > n_exp // 2 or n_exp % self.interleave:
            raise ParameterError(f"{stem}: need lowpass_harmonic <= exp_n_samples / 2 and "
                                 f"interleave dividing exp_n_samples, got "
                                 f"{self.lowpass_harmonic}, {self.interleave}, {n_exp}")
        if self.worst_k >= min(n, n_exp) // 2:
            raise ParameterError(f"{stem}: worst_k must stay below N/2 = {min(n, n_exp) // 2}")
        if self.harmonic_k > self.k_sweep_max or self.pop_size % 2:
            raise ParameterError(f"{stem}: need harmonic_k <= k_sweep_max (the sweep supplies the "
                                 f"GA's best run at harmonic_k) and an even pop_size (parents are "
                                 f"paired), got {self.harmonic_k}, {self.k_sweep_max}, "
                                 f"{self.pop_size}")


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
            "{ours_gap:.3f}."),
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
