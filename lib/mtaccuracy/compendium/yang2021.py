"""The compendium's side of notebook 05 (Yang et al. 2021): checks of its parameters, figures."""

from __future__ import annotations

__all__ = ["check_run", "experiment_genes", "experiment_inputs", "ga_settings_study",
           "single_run_speedups"]

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
