"""The optimisers of Yang et al. 2021, Section 2.2, on the probe layout.

A genetic algorithm (binary or real coded) with fixed rates, the same algorithm with the adaptive
rates of Eqs. 22-23 (:func:`mtaccuracy.optimise.ga.adaptive_rates`, with the paper's bounds
:data:`PC_MAX`, :data:`PC_MIN`, :data:`PM_MAX`, :data:`PM_MIN`), and differential evolution as
the baseline, all batched over independent runs and population (arrays of shape ``(runs,
population, 4)``; the only Python loop is over generations); the optimisers' own ties (equal
``H`` in a population) go to the lowest index.

The baseline differential evolution follows the scheme of ``scipy.optimize.differential_evolution``
but is written out batched over runs (:func:`_differential_evolution`): scipy runs one
optimisation at a time, looping over the population in Python, and hundreds of runs are needed.
"""

from __future__ import annotations

__all__ = ["PC_MAX", "PC_MIN", "PM_MAX", "PM_MIN", "GAResult", "run_ga", "run_de",
           "convergence_generation", "convergence_statistics", "speedup", "bootstrap_se",
           "reference_optimum", "reference_optima"]

import numpy as np
from scipy.optimize import minimize
from scipy.stats import bootstrap

from .. import validate
from ..optimise.ga import BinaryEncoding, GAResult, RealEncoding
from ..optimise.ga import run_ga as generic_ga
from .design import PAPER_BOX, _box, objective_H, objective_worst, optimal_a3, select_best

#: Probabilities of the improved GA (Section 2.2): crossover Pc max/min, mutation Pm max/min.
PC_MAX, PC_MIN, PM_MAX, PM_MIN = 0.99, 0.4, 0.09, 0.005


#: The reference optimum (:func:`reference_optima`) excludes layouts with |sin(phi_2 - phi_1)|
#: below this (weights above 1e4, closed-form H inaccurate).
_NEAR_DEGENERATE = 1e-4


def _make_objective(k, harmonics, n_runs):
    """``objective(x, runs=all)``: H of genes ``x`` (len(runs), pop, 4) for those runs."""
    if (k is None) == (harmonics is None):
        raise ValueError("give either k (one harmonic, Eq. 20) or harmonics (worst case)")
    if harmonics is not None:
        hs = np.asarray(harmonics)
        objective_worst(np.zeros(4) + 1.0, hs)  # validates
        return lambda x, runs=None: objective_worst(x, hs)
    ks = np.broadcast_to(np.asarray(k), (n_runs,)).astype(float)
    objective_H(np.array([0.3, 2.0, 5.0, 1.0]), ks)  # validates k

    def objective(x, runs=None):
        return objective_H(x, (ks if runs is None else ks[runs])[:, None])
    return objective


def run_ga(k=None, *, harmonics=None, bounds=PAPER_BOX, n_runs: int = 32, pop_size: int = 50,
           generations: int = 200, seed=0, adaptive: bool = True, pc: float = 0.8,
           pm: float = 0.05, eq23: str = "corrected", encoding: str = "real",
           mutation_scale: float = 0.1, bits: int = 16,
           pc_max=PC_MAX, pc_min=PC_MIN, pm_max=PM_MAX, pm_min=PM_MIN) -> GAResult:
    """Genetic algorithm minimising the layout's ``H`` (fitness ``F = 1/H``, Eq. 21), runs batched.

    The generic :func:`mtaccuracy.optimise.ga.run_ga` on the layout objective.  The paper gives
    neither the encoding nor the operators; ours, stated there: genes ``(phi_1, phi_2, phi_3, a_3)``
    in ``bounds``; uniform initial population; roulette-wheel selection; consecutive parents paired
    and crossed with probability ``Pc``; elitism. ``encoding="real"``
    (:class:`~mtaccuracy.optimise.ga.RealEncoding`: arithmetic crossover, Gaussian mutation of
    ``mutation_scale`` x the range, reflected) or ``"binary"``
    (:class:`~mtaccuracy.optimise.ga.BinaryEncoding`: ``bits`` bits per gene, single-point
    crossover, bit flips).

    ``adaptive=False``: the traditional GA, fixed ``pc`` and ``pm``.  ``adaptive=True``: Eq. 22
    for ``Pc`` with ``F`` the fitness of the fitter parent of the pair, Eq. 23 for ``Pm`` with
    ``F`` the fitness of the child's own parent; ``eq23`` picks the printed or the corrected sign
    (:func:`mtaccuracy.optimise.ga.adaptive_rates`).

    ``k`` (scalar, or one per run) optimises Eq. 20 at that harmonic; ``harmonics`` optimises the
    worst case over them.  ``seed`` seeds one ``numpy.random.Generator`` (or pass a Generator).

    Parameters
    ----------
    k : int or array (n_runs,), optional
        Harmonic order of Eq. 20.
    harmonics : sequence of int, optional
        Optimise the worst case over these instead.
    bounds : sequence of 4 (low, high)
        Box of ``phi_1, phi_2, phi_3`` (rad) and ``a_3``.
    n_runs, pop_size, generations : int
        Runs at once, individuals per run (even), generations.
    seed : None, int or numpy.random.Generator
        Seeds one generator for all runs (a Generator is used as it is).
    adaptive : bool
        The improved GA (Eqs. 22-23) or the traditional one.
    pc, pm : float
        Fixed probabilities of the traditional GA.
    eq23 : {"corrected", "printed"}
        Which Eq. 23.
    encoding : {"real", "binary"}
        Gene encoding.
    mutation_scale : float
        Real encoding: mutation step as a share of the range.
    bits : int
        Binary encoding: bits per gene.
    pc_max, pc_min, pm_max, pm_min : float
        Bounds of the adaptive probabilities.

    Returns
    -------
    GAResult
        Per run the best genes ``(n_runs, 4)`` and ``H`` ``(n_runs,)``, the best-so-far history
        ``(generations + 1, n_runs)`` and the mean rates used per generation.
    """
    if encoding not in ("real", "binary"):
        raise ValueError(f"encoding must be 'real' or 'binary', got {encoding!r}")
    n_runs = validate.integer(n_runs, "n_runs", low=1)       # before k is broadcast to it
    lo, hi = _box(bounds)
    objective = _make_objective(k, harmonics, n_runs)
    enc = (RealEncoding(lo, hi, mutation_scale) if encoding == "real"
           else BinaryEncoding(lo, hi, bits))
    rates = (dict(pc_max=pc_max, pc_min=pc_min, pm_max=pm_max, pm_min=pm_min, eq23=eq23)
             if adaptive else None)
    label = ("improved GA (Eqs. 22-23" + (", printed Eq. 23)" if eq23 == "printed" else ")")
             if adaptive else f"traditional GA (Pc={pc:g}, Pm={pm:g})")
    return generic_ga(objective, enc, n_runs=n_runs, pop_size=pop_size,
                      generations=generations, seed=seed, adaptive=rates,
                      pc=pc, pm=pm, label=f"{label}, {encoding}")


def _differential_evolution(objective, lo, hi, n_runs: int, n_pop: int, generations: int, rng,
                            *, tol: float = 0.0, mutation=(0.5, 1.0),
                            recombination: float = 0.7):
    """Differential evolution, scipy's default scheme, ``n_runs`` independent runs at once.

    The scheme of ``scipy.optimize.differential_evolution`` with ``strategy="best1bin"``,
    ``mutation=(0.5, 1)`` (dithered: a new factor per run and generation),
    ``recombination=0.7``, ``init="latinhypercube"``, ``updating="deferred"`` and ``tol``
    (a run stops when the standard deviation of its population's energies is at most ``tol``
    times their mean): the trial of member ``i`` is ``best + F (x_r0 - x_r1)`` with ``r0, r1, i``
    distinct, crossed binomially with member ``i`` (one gene always from the trial); genes that
    leave the box are redrawn uniformly in it; a trial replaces its member when not worse.
    Hand-written because scipy runs one optimisation at a time with a Python loop over the
    population every generation, and the compendium needs hundreds of runs: here every step is
    an array over (runs, population, genes) and the only loop is over generations.

    ``objective(x, runs)``: energies ``(len(runs), n_pop)`` of genes ``x`` ``(len(runs), n_pop,
    d)`` for the runs with indices ``runs``.  Returns ``(population, energies, history,
    generations_run)``: the final population ``(n_runs, n_pop, d)`` and its energies, the best
    energy after each generation ``(generations + 1, n_runs)`` (row 0: the initial population;
    a stopped run keeps its value), and the number of generations each run made.
    """
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    s, p, d = n_runs, n_pop, lo.size
    if p < 4:
        raise ValueError(f"differential evolution needs at least 4 members, got {p}")
    every = np.arange(s)

    def energy(unit, runs):
        with np.errstate(over="ignore", invalid="ignore"):
            e = np.asarray(objective(lo + unit * (hi - lo), runs), dtype=float)
        return np.where(np.isfinite(e), np.minimum(e, 1e300), 1e300)

    # Latin hypercube: one point in each of n_pop slices of every gene, slices shuffled per gene
    unit = (rng.random((s, p, d)) + np.arange(p)[:, None]) / p
    unit = np.take_along_axis(unit, np.argsort(rng.random((s, p, d)), axis=1), axis=1)
    e = energy(unit, every)
    hist = np.empty((generations + 1, s))
    hist[0] = e.min(axis=1)
    done = np.zeros(s, dtype=bool)
    made = np.zeros(s, dtype=np.int64)
    member = np.arange(p)
    for g in range(1, generations + 1):
        runs = np.flatnonzero(~done)
        if runs.size:
            m = runs.size
            pop, en = unit[runs], e[runs]
            rows = np.arange(m)[:, None]
            best = pop[np.arange(m), np.argmin(en, axis=1)]          # first index on ties
            f = rng.uniform(mutation[0], mutation[1], size=(m, 1, 1))
            r0 = rng.integers(0, p - 1, size=(m, p))
            r0 = r0 + (r0 >= member)                                  # r0 != i
            r1 = rng.integers(0, p - 2, size=(m, p))
            first, second = np.minimum(member, r0), np.maximum(member, r0)
            r1 = r1 + (r1 >= first)
            r1 = r1 + (r1 >= second)                                  # r1 != i, r0
            mutant = best[:, None, :] + f * (pop[rows, r0] - pop[rows, r1])
            cross = rng.random((m, p, d)) < recombination
            cross[rows, member, rng.integers(0, d, size=(m, p))] = True
            trial = np.where(cross, mutant, pop)
            outside = (trial < 0) | (trial > 1)
            trial = np.where(outside, rng.random((m, p, d)), trial)
            et = energy(trial, runs)
            take = et <= en
            unit[runs] = np.where(take[..., None], trial, pop)
            e[runs] = np.where(take, et, en)
            made[runs] += 1
            if tol > 0:
                with np.errstate(over="ignore", invalid="ignore"):
                    spread = e[runs].std(axis=1) <= tol * np.abs(e[runs].mean(axis=1))
                done[runs] = spread
        hist[g] = e.min(axis=1)
    return lo + unit * (hi - lo), e, hist, made


def _polish(fun, x0, lo, hi):
    """L-BFGS-B from ``x0`` within the box (what scipy's ``polish=True`` does); returns
    ``(x, f)`` of the better of the start and the end point."""
    f0 = float(fun(x0))
    res = minimize(fun, x0, method="L-BFGS-B", bounds=list(zip(lo, hi, strict=True)))
    if res.fun < f0:
        return np.clip(res.x, lo, hi), float(res.fun)
    return np.asarray(x0, dtype=float), f0


def run_de(k=None, *, harmonics=None, bounds=PAPER_BOX, n_runs: int = 32, popsize: int = 13,
           generations: int = 200, seed: int = 0, polish: bool = False) -> GAResult:
    """Baseline: differential evolution on the GA's genes and objective, ``n_runs`` runs at once.

    scipy's default scheme (:func:`_differential_evolution`), ``popsize * 4`` members, no early
    stop, so every run lasts ``generations``; ``polish`` refines each run's best with L-BFGS-B as
    scipy's ``polish=True`` does.  ``seed`` seeds one ``numpy.random.Generator`` for all runs (or
    pass a Generator).

    Parameters
    ----------
    k : int or array (n_runs,), optional
        Harmonic order of Eq. 20.
    harmonics : sequence of int, optional
        Optimise the worst case over these instead.
    bounds : sequence of 4 (low, high)
        The box of the genes.
    n_runs, popsize, generations : int
        Runs at once (>= 1), members per gene (>= 1; ``4 popsize`` members), generations
        (>= 1).
    seed : None, int or numpy.random.Generator
        Seeds one generator for all runs (a Generator is used as it is).
    polish : bool
        Refine each run's best with L-BFGS-B.

    Returns
    -------
    GAResult
        As :func:`run_ga`; the rates ``pc``, ``pm`` are NaN.
    """
    n_runs = validate.integer(n_runs, "n_runs", low=1)
    popsize = validate.integer(popsize, "popsize", low=1)
    generations = validate.integer(generations, "generations", low=1)
    if k is not None and np.ndim(k) != 0:
        raise ValueError("run_de takes one harmonic order k")
    lo, hi = _box(bounds)
    objective = _make_objective(k, harmonics, n_runs)
    rng = validate.rng(seed)
    pop, e, hist, _ = _differential_evolution(lambda x, runs: objective(x, runs), lo, hi,
                                              n_runs, popsize * 4, generations, rng)
    ib = np.argmin(e, axis=1)
    best_x = pop[np.arange(n_runs), ib]
    best_h = e[np.arange(n_runs), ib]
    if polish:
        for r in range(n_runs):
            def fun(x, r=r):
                return float(np.minimum(objective(np.asarray(x)[None, None], np.array([r]))
                                        [0, 0], 1e300))
            best_x[r], best_h[r] = _polish(fun, best_x[r], lo, hi)
    best_h = np.asarray(objective(best_x[:, None], np.arange(n_runs))[:, 0], dtype=float)
    return GAResult(best_x=best_x, best_h=best_h, history=hist,
                    pc=np.full(generations + 1, np.nan), pm=np.full(generations + 1, np.nan),
                    evaluations_per_generation=popsize * 4,
                    label="differential evolution (best1bin" + (", polished)" if polish else ")"))


def convergence_generation(history, target, rel_tol: float = 0.01) -> np.ndarray:
    """First generation whose best-so-far objective is within ``rel_tol`` of ``target``; -1 never.

    Parameters
    ----------
    history : array (generations + 1, runs)
        Best-so-far objective.
    target : float or array (runs,)
        The value to reach.
    rel_tol : float
        Relative distance that counts as reached.

    Returns
    -------
    array of int (runs,)
        The generation (row of ``history``) per run, ``-1`` for a run that never reaches it.
    """
    hist = np.asarray(history, dtype=float)
    if hist.ndim != 2:
        raise ValueError("history must be (generations + 1, runs)")
    if not rel_tol >= 0:
        raise ValueError(f"rel_tol must be >= 0, got {rel_tol!r}")
    ok = hist <= np.asarray(target, dtype=float) * (1 + rel_tol)
    return np.where(ok.any(axis=0), ok.argmax(axis=0), -1)


def reference_optima(ks, *, bounds=PAPER_BOX, n_starts: int = 2, seed: int = 0,
                     maxiter: int = 400, popsize: int = 30, rel_tol: float = 1e-9):
    """Best known ``H`` at every harmonic of ``ks`` within ``bounds`` (a numerical reference).

    Differential evolution over the three angles with the optimal ``a_3`` in closed form
    (:func:`optimal_a3`),
    ``n_starts`` runs per harmonic (all harmonics and starts in one batch, each run stopping
    when its population's energies agree to ``1e-12``), each polished with L-BFGS-B; the
    result's ``H`` is Eq. 20 evaluated at the genes found.  Layouts with
    ``|sin(phi_2 - phi_1)| < 1e-4`` are excluded: Eq. 15 would need weights above ``1e4``
    there, and the closed form of :func:`optimal_a3` loses its accuracy (it can even return
    values below the bound 1/4).

    Returns ``(H, genes)`` of shapes ``(K,)`` and ``(K, 4)``.  The best start is chosen by
    :func:`select_best` (starts whose ``H`` agree within ``rel_tol`` are ties, broken by the
    canonical layout), and the genes are the canonical member of the layout's symmetry class
    (:func:`canonical_genes`).  A numerical reference, not a proof.

    Parameters
    ----------
    ks : sequence of int (K,)
        Harmonic orders (>= 2).
    bounds : sequence of 4 (low, high)
        The box (only the angles are searched; ``a_3`` is closed form).
    n_starts : int
        Runs per harmonic (>= 1).
    seed : None, int or numpy.random.Generator
        Seeds the runs.
    maxiter, popsize : int
        Differential evolution's budget: generations (>= 1) and members per angle (>= 2, as
        the scheme needs four members at least).
    rel_tol : float
        Starts whose H agree within it are ties.

    Returns
    -------
    H : array (K,)
        Best known H per harmonic.
    genes : array (K, 4)
        Its canonical genes ``(phi_1, phi_2, phi_3, a_3)``.
    """
    ks = np.atleast_1d(np.asarray(ks))
    if ks.ndim != 1 or ks.size == 0:
        raise ValueError("ks must be a non-empty list of harmonic orders")
    objective_H(np.array([0.3, 2.0, 5.0, 1.0]), ks)  # validates the orders
    n_starts = validate.integer(n_starts, "n_starts", low=1)
    maxiter = validate.integer(maxiter, "maxiter", low=1)
    popsize = validate.integer(popsize, "popsize", low=2)
    lo, hi = _box(bounds)
    a3b = (lo[3], hi[3])
    k_run = np.repeat(ks.astype(float), n_starts)

    def objective(x3, runs):
        h = optimal_a3(x3, k_run[runs, None], a3b)[1]
        return np.where(np.abs(np.sin(x3[..., 1] - x3[..., 0])) < _NEAR_DEGENERATE, np.inf, h)

    rng = validate.rng(seed)
    pop, e, _, _ = _differential_evolution(objective, lo[:3], hi[:3], k_run.size, popsize * 3,
                                           maxiter, rng, tol=1e-12)
    n = k_run.size
    x3 = pop[np.arange(n), np.argmin(e, axis=1)]
    h = np.empty(n)
    for r in range(n):
        def fun(v, r=r):
            return float(np.minimum(objective(np.asarray(v)[None, None], np.array([r]))[0, 0],
                                    1e300))
        x3[r], _ = _polish(fun, x3[r], lo[:3], hi[:3])
    a3 = optimal_a3(x3, k_run, a3b)[0]
    genes = np.concatenate([x3, a3[:, None]], axis=1)
    h = np.where(np.abs(np.sin(x3[:, 1] - x3[:, 0])) < _NEAR_DEGENERATE, np.inf,
                 objective_H(genes, k_run))                     # Eq. 20 itself, as the GAs
    genes = genes.reshape(ks.size, n_starts, 4)
    h = h.reshape(ks.size, n_starts)
    best, genes_best = select_best(h, genes, bounds=bounds, rel_tol=rel_tol)
    return h[np.arange(ks.size), best], genes_best


def reference_optimum(k: int, *, bounds=PAPER_BOX, n_starts: int = 4, seed: int = 0,
                      maxiter: int = 400):
    """Best known ``H`` at harmonic ``k`` in ``bounds``: :func:`reference_optima` for one ``k``.

    Parameters
    ----------
    k : int
        Harmonic order (>= 2).
    bounds : sequence of 4 (low, high)
        Box of ``phi_1, phi_2, phi_3`` (rad) and ``a_3``.
    n_starts : int
        Differential evolution runs (>= 1).
    seed : None, int or numpy.random.Generator
        Seeds the runs.
    maxiter : int
        Generations per run (>= 1).

    Returns
    -------
    H : float
        Best known H.
    genes : array (4,)
        Its canonical genes (:func:`canonical_genes`).
    """
    h, g = reference_optima([k], bounds=bounds, n_starts=n_starts, seed=seed, maxiter=maxiter)
    return float(h[0]), g[0]


def convergence_statistics(result, *, name: str, h_ref: float, rel_tol: float) -> dict:
    """How a set of GA (or DE) runs converged (Yang et al. 2021, Figs. 8-9, over many seeds).

    Parameters
    ----------
    result : GAResult
        ``history`` (generations + 1, runs) of best-so-far H, ``best_h`` (runs,), ``label``,
        ``evaluations_per_generation``.
    name : str
        The algorithm's name in the table.
    h_ref : float
        The best known H (:func:`reference_optimum`).
    rel_tol : float
        "Reached" means within this relative distance of ``h_ref``.

    Returns
    -------
    dict
        ``reached_fraction`` and the quartiles of the generation at which the runs that reach
        ``h_ref`` do so (``reached_*``), the quartiles of the generation at which each run comes
        within 1e-3 of its own final value (``plateau_*``), and the median, best and worst final
        H.  Quartiles of an empty set are NaN.
    """
    reach = convergence_generation(result.history, h_ref, rel_tol)
    plateau = convergence_generation(result.history, result.history[-1], 1e-3)
    ok = reach >= 0

    def q(v, p):
        return float(np.percentile(v, p)) if len(v) else np.nan
    return dict(algorithm=name, label=result.label, runs=result.history.shape[1],
                evaluations_per_generation=result.evaluations_per_generation,
                reached_fraction=ok.mean(), reached_median=q(reach[ok], 50),
                reached_q25=q(reach[ok], 25), reached_q75=q(reach[ok], 75),
                plateau_median=q(plateau, 50), plateau_q25=q(plateau, 25),
                plateau_q75=q(plateau, 75), final_H_median=np.median(result.best_h),
                final_H_best=result.best_h.min(), final_H_worst=result.best_h.max())


def speedup(improved, traditional, axis=-1):
    """Speed-up in percent, ``100 (1 - median(improved) / median(traditional))`` of generations.

    Parameters
    ----------
    improved, traditional : arrays (..., runs)
        Convergence generations of independent runs.
    axis : int
        The runs' axis.

    Returns
    -------
    array (...)
        Percent; positive when the improved algorithm converges earlier.
    """
    return 100 * (1 - np.median(improved, axis=axis) / np.median(traditional, axis=axis))


def bootstrap_se(statistic, *samples, rng, n_resamples: int = 2000) -> float:
    """Bootstrap standard error of a statistic of independent samples of runs.

    Parameters
    ----------
    statistic : callable
        ``statistic(*samples, axis)``, vectorised as ``scipy.stats.bootstrap`` expects.
    *samples : arrays (runs,)
        Independent samples (resampled separately).
    rng : numpy.random.Generator
        The resampling's generator.
    n_resamples : int
        Bootstrap resamples.

    Returns
    -------
    float
        The standard deviation of the statistic over the resamples (percentile bootstrap).
    """
    return bootstrap(samples, statistic, n_resamples=n_resamples, vectorized=True,
                     method="percentile", rng=rng).standard_error
