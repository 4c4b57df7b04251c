"""Notebook 05's analyses of the paper: Table 1, the GA settings, Eq. 17, least squares.

Table 1 against Eqs. 15 and 20 (:func:`table1_consistency`); how the GA comparison of Figs. 8-9
depends on settings the paper omits (:func:`ga_settings_study`, :func:`single_run_speedups`);
Section 1.3's simulation under every mapping and convention
(:func:`mappings_and_conventions`); the printed Eq. 17 against its inverse
(:func:`eq17_sign_check`); the weighted sum against least squares
(:func:`least_squares_vs_weighted`); what sets the simulated experiment's trends with speed
(:func:`speed_trend_sources`).  The method itself is :mod:`mtaccuracy.spindle`.
"""

from __future__ import annotations

import itertools

import numpy as np
import pandas as pd

from ... import spindle as sp
from ..printed import half_unit

__all__ = ["table1_consistency", "ga_settings_study", "single_run_speedups",
           "mappings_and_conventions", "eq17_sign_check", "least_squares_vs_weighted",
           "speed_trend_sources"]


def table1_consistency(t1, sweep):
    """Table 1 against Eqs. 15, 20 and our optimum, row by printed row.

    For every printed row, H and the weights of every parameter set that rounds to the printed
    one (a 21^4 grid over half a unit of the last printed digit), the weights-only bound of H,
    and our GA and best known optima at that k.  ``t1``: the published table (strings);
    ``sweep``: the optimum per harmonic order.  ``H_as_printed`` is Eq. 20 evaluated at the
    printed angles with the printed weights, nothing corrected (they need not cancel the first
    harmonic); ``H_of_printed_parameters`` uses Eq. 15's weights at the printed angles and a3.
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
                         H_as_printed=float(sp.transfer(centre[:3], w_pr, [k])[0]),
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


#: Decimals (um) below which a separation's numbers are rounding noise (about 1e-14 um here).
NOISE_DECIMALS = 12


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
        ``mean_separated_error``, ``max_profile_error`` and ``max_error_motion_error`` (um),
        each to 1e-12 um (:data:`NOISE_DECIMALS`): below it they are the rounding of FFTs and
        pseudo-inverses, which another BLAS kernel changes, not a property of the method.
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
    table = pd.DataFrame(rows)
    numbers = table.columns[2:]
    table[numbers] = np.round(table[numbers].to_numpy(float), NOISE_DECIMALS) + 0.0
    return table


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


def speed_trend_sources(profile, dx, dy, layout, *, speeds, variants, seed: int, **settings):
    """What sets the simulated shape error's trends with speed: the campaign under other settings.

    Every ``(variant, speed)`` is one :func:`~mtaccuracy.spindle.measure_separated` campaign
    drawn from a fresh generator seeded ``seed`` (common random numbers: two variants differ by
    their settings only), with ``settings`` overridden by the variant's.

    Parameters
    ----------
    profile, dx, dy : arrays (N,)
        The true profile and synchronous error motion (mm).
    layout : tuple
        ``(positions, phi, w)`` of :func:`~mtaccuracy.spindle.grid_layout`.
    speeds : sequence of float
        Spindle speeds (r/min).
    variants : dict of str to dict
        Name to the settings it overrides; a ``duration_s`` that is a callable of the speed
        gives the acquisition time at each speed (e.g. a fixed number of revolutions).
    seed : int
        Seed of every campaign.
    **settings
        The keywords of ``measure_separated`` except ``rng`` and ``speed_rpm``.

    Returns
    -------
    pandas.DataFrame
        One row per variant and speed: ``variant``, ``speed_rpm``, ``revolutions``,
        ``mz_mean_um``, ``mz_std_um`` (minimum-zone roundness of the separated profile).
    """
    rows = []
    for name, change in variants.items():
        for speed in speeds:
            kw = {**settings, **change}
            if callable(kw["duration_s"]):
                kw["duration_s"] = kw["duration_s"](speed)
            s, n_rev = sp.measure_separated(profile, dx, dy, *layout, speed_rpm=speed,
                                            rng=np.random.default_rng(seed), **kw)
            mz = sp.mz_roundness(s.profile)[0] * 1e3
            rows.append(dict(variant=name, speed_rpm=speed, revolutions=n_rev,
                             mz_mean_um=mz.mean(), mz_std_um=mz.std(ddof=1)))
    return pd.DataFrame(rows)
