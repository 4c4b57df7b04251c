"""The compendium's side of notebook 05 (Yang et al. 2021): checks of its parameters, figures."""

from __future__ import annotations

__all__ = ["check_run", "eq17_sign_check", "experiment_genes", "experiment_inputs",
           "ga_settings_study", "least_squares_vs_weighted", "mappings_and_conventions",
           "noise_transfer_figure", "ranges_statement", "single_run_speedups",
           "speed_curves_figure", "table1_consistency_texts"]

import itertools

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from .. import spindle as sp
from .reproduction import printed_half_unit as half_unit


def check_run(params, stem: str) -> None:
    """Refuse notebook 05's parameters that contradict each other (each with a clear message).

    Parameters
    ----------
    params : mapping
        The notebook's parameters by name (its ``globals()``): ``probe_positions``,
        ``n_samples``, ``lowpass_harmonic``, ``exp_n_samples``, ``interleave``, ``worst_k``,
        ``harmonic_k``, ``k_sweep_max``, ``pop_size``.
    stem : str
        The notebook's stem, which starts every message.

    Raises
    ------
    ValueError
        Naming the parameters that contradict each other.
    """
    probe_positions, n_samples = params["probe_positions"], params["n_samples"]
    lowpass_harmonic, exp_n_samples = params["lowpass_harmonic"], params["exp_n_samples"]
    interleave, worst_k, harmonic_k = params["interleave"], params["worst_k"], params["harmonic_k"]
    k_sweep_max, pop_size = params["k_sweep_max"], params["pop_size"]
    if len(probe_positions) != 4 or probe_positions[0] != 0 \
            or max(probe_positions) >= n_samples or len(set(probe_positions)) != 4:
        raise ValueError(f"{stem}: probe_positions must be 4 distinct sample indices in "
                         f"0..{n_samples - 1} starting with 0, got {probe_positions}")
    if lowpass_harmonic > exp_n_samples // 2 or exp_n_samples % interleave:
        raise ValueError(f"{stem}: need lowpass_harmonic <= exp_n_samples / 2 and interleave "
                         f"dividing exp_n_samples, got {lowpass_harmonic}, {interleave}, "
                         f"{exp_n_samples}")
    if worst_k >= min(n_samples, exp_n_samples) // 2:
        raise ValueError(f"{stem}: worst_k must stay below N/2 = "
                         f"{min(n_samples, exp_n_samples) // 2}")
    if harmonic_k > k_sweep_max or pop_size % 2:
        raise ValueError(f"{stem}: need harmonic_k <= k_sweep_max (the sweep supplies the GA's "
                         f"best run at harmonic_k) and an even pop_size (parents are paired), got "
                         f"{harmonic_k}, {k_sweep_max}, {pop_size}")


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


def experiment_genes(facts):
    """The layout of the paper's lathe experiment, as printed: genes ``(phi_1, phi_2, phi_3, a_3)``.

    In rad, rad, rad, 1, from ``data/papers/yang2021_facts.csv`` (Table 1's k = 20 row, which
    Section 3 says the experiment used); ``a_1, a_2`` are left to Eq. 15.  ``facts``: the
    published facts indexed by quantity (strings).
    """
    phi = [float(v) for v in str(facts["experiment_angles"]).split()]
    if len(phi) != 3:
        raise ValueError(f"yang2021_facts.csv: experiment_angles needs 3 angles, got {phi}")
    return np.array([*phi, float(facts["experiment_a3"])])


def experiment_inputs(card, mandrel_roundness_um: float, calibration_um: float):
    """Declare the simulated lathe experiment's inputs on ``card``; ``(mandrel, simulation, sync)``.

    The mandrel is ``constructed`` when its roundness is the paper's calibration value (the
    value Table 2's shape errors, Fig. 21 and the abstract's deviation are compared with: the
    simulation then returns it by design), else ``simulated``; the noise, the asynchronous
    motion and the layouts are ``simulated``; the synchronous motion, the printed Section 1.3
    rotation error at every speed, is ``assumed``: it makes the separated curves coincide
    across speeds (Figs. 19-20) by design."""
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

    Returns a DataFrame, one row per setting: ``study`` ("generation count" or "fixed rates"),
    ``generations``, ``pc``, ``pm`` (the traditional GA's), ``runs``, the plateau medians of
    both GAs (``improved_median``, ``traditional_median``) and ``speedup_percent``
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

    ``100 (1 - g_i / g_t)`` for every improved-GA convergence generation ``g_i`` (runs,) and
    traditional-GA one ``g_t`` (runs,) with ``g_t > 0``; shape
    ``(n_improved * n_traditional_positive,)``.
    """
    gi = np.asarray(improved, float)[:, None]
    gt = np.asarray(traditional, float)
    gt = gt[gt > 0][None, :]
    return (100 * (1 - gi / gt)).ravel()


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
