"""``make bench``: the speed targets named in the issues, measured, with the peers side by side.

Every task runs in a fresh Python process of its own (``python -m mtaccuracy.compendium.bench --task
NAME``), so its memory is that task's alone: the row gives the process's peak RSS and, of it,
what the task added above the RSS the process had when the task started (imports and inputs).
Times are the minimum of ``repeat`` runs (3 unless a row says otherwise) after one warm-up run
(caches of multi-indices and polynomial families filled), wall clock.  Targets are shown here,
never asserted in timed tests.  ``make reproduce`` and ``make test`` are timed in a fresh clone
(min of two; skipped with ``--quick``).

Peers are measured in the same run, each in a process of its own, and every ratio printed is
of two rows of that run (the ratio stands in the note of our row: the peer's time and memory
over ours):

* SALib (``SALib.sample.sobol.sample`` with ``calc_second_order=False``, the model, then
  ``SALib.analyze.sobol.analyze`` on each output) against our ``sobol_indices``, on the Zheng
  et al. machine (``ac_double_turntable.pose_error`` at the paper's pose, the 41 errors normal
  with the ranges of ``_zheng``) and on its first-order model (the memory rows).  Accuracy is
  made equal, not argued: both draw the same design (one scrambled Sobol' sequence from
  ``numpy.random.default_rng(SEED)``, N a power of two: 2^14 in ``--quick``, 2^17 beside the
  paper's N = 1e5, 2^13 and 2^17 for the memory rows) and apply the same estimators (Saltelli
  2010, Jansen), so their indices agree to rounding; the note of our row says to how many
  digits, and both rows give the largest error of S1 and ST against the closed form
  (``linear_indices`` on the Jacobian: exact for the linear model, the first-order answer for
  the machine).  What SALib is asked for is what we compute: no second-order indices, and its
  bootstrap (which it cannot switch off) at its smallest, two resamples.  Both evaluate the
  model 250 000 runs per call, so the model's temporaries are the same; SALib then holds its
  sample matrix (N (D + 2) x D floats: 1.8 GB at N = 2^17) and all outputs, which is its
  design, and is why it runs no row above N = 2^17 (14.8 GB at 2^20).  Rows of N >= 2^17 and
  the memory rows are one run each (no warm-up) for both tools; the quick rows min of 3.
* OpenTURNS (``FunctionalChaosAlgorithm``, LARS with corrected LOO, the Legendre basis at a
  fixed degree) against our ``fit_sparse_pce`` (OMP and LARS, basis and length validated) on the
  sparse-PCE benchmarks with exact indices, the same samples: each row prints the time and the
  largest error of S1 and ST, accuracy beside time.  OpenTURNS never enters the project's
  environment: ``--with-openturns`` makes (once) a virtual environment of its own under
  ``build/bench-openturns/`` that sees the project's packages (a ``.pth`` file) and has
  ``OPENTURNS_REQUIREMENT`` installed from PyPI, and runs the OpenTURNS tasks with its Python;
  without the flag those rows say how to get them.

Local imports: each task imports what it measures inside its function, so that its time and
memory are its own (a task runs in a process of its own; a peer's package is imported before
the task's memory baseline is taken, as ours is).
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

REPEAT = 3


def _rss_mb() -> float:
    """Current resident set size of this process, MB (Linux /proc)."""
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def _min_time(fn, repeat: int = REPEAT):
    """Warm-up run, then the minimum wall time of ``repeat`` runs; returns (seconds, result)."""
    out = fn()
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


# ------------------------------------------------------------------------------------------
# Tasks: each returns dict(time=..., note=..., [err_s1, err_st]) and runs in its own process.
# ------------------------------------------------------------------------------------------

def _zheng():
    from ..machines import build

    m = build("ac_double_turntable")
    sd = np.array([e.to_library * (15.0 if e.translational else 10.0) / 3 for e in m.catalogue])
    pose = dict(x=106.1, y=-58.6, z=-255.3, A=np.deg2rad(60.7), C=np.deg2rad(56.7))
    return m, sd, pose


def task_guo_pose_error():
    from .. import errors, sensitivity
    from ..machines import build

    m = build("vertical_xyfz")
    b = errors.uniform_bounds(m.catalogue, {"positioning": (0, 3), "straightness": (0, 4),
                                            "angular": (0, 3.2e-5), "squareness": (0, 1.9)})
    x = sensitivity.latin_hypercube(1_000_000, b, 0)
    pose = dict(x=100.0, y=100.0, z=100.0)
    t, _ = _min_time(lambda: m.pose_error(x, pose))
    return dict(time=t, note=f"{1 / t:.2f} M samples/s")


def task_guo_spearman():
    from .. import errors, sensitivity
    from ..machines import build

    m = build("vertical_xyfz")
    b = errors.uniform_bounds(m.catalogue, {"positioning": (0, 3), "straightness": (0, 4),
                                            "angular": (0, 3.2e-5), "squareness": (0, 1.9)})
    pose = dict(x=100.0, y=100.0, z=100.0)
    d = sensitivity.repeated_latin_hypercube(500, b, repeats=200, seed=2)
    y = sensitivity.position_outputs(m.pose_error(d.reshape(-1, 21), pose)).reshape(200, 500, 4)
    t, _ = _min_time(lambda: sensitivity.spearman(d, y))
    return dict(time=t, note="")


def task_zheng_pose_error():
    m, sd, pose = _zheng()
    x = np.random.default_rng(0).standard_normal((1_000_000, 41))
    x *= sd
    t, _ = _min_time(lambda: m.pose_error(x, pose))
    return dict(time=t, note=f"{1 / t:.2f} M samples/s (task MB: the 328 MB input, the output)")


def _zheng_pce(components):
    from .. import sensitivity as S

    m, sd, pose = _zheng()
    u = S.base_samples(1000, 41, method="lhs", seed=1)[0]
    xi = S.Inputs.normal(0.0, np.ones(41)).from_unit(u)
    yv = m.pose_error(xi * sd, pose)

    def run():
        alphas = S.multi_indices(41, 3)
        psi = S.design_matrix(xi, alphas)
        fits = S.fit_pce_outputs(xi, yv[:, list(components)], psi=psi, alphas=alphas)
        return [S.pce_sobol(f) for f in fits]
    t, out = _min_time(run)
    return dict(time=t, note=f"terms kept: {', '.join(str(int((o[1] > 0).sum())) for o in out)}"
                             " inputs with an index")


def task_zheng_pce_one():
    return _zheng_pce([0])


def task_zheng_pce_six():
    return _zheng_pce(range(6))


def task_zheng_mcs():
    from .. import sensitivity as S

    m, sd, pose = _zheng()
    design = S.SobolDesign(100_000, S.Inputs.normal(0.0, sd), method="mc", seed=2)

    def run():   # sampling included; streamed: the base rows and AB runs are never all held
        return S.sobol_indices(lambda z: m.pose_error(z, pose), design, chunk=250_000)
    t, (s1, st) = _min_time(run)
    lin = S.linear_indices(m.jacobian(pose), sd=sd)[0]
    return dict(time=t, note=f"largest |ST - linear closed form| {np.abs(st - lin).max():.1e}")


#: seed of the Sobol' designs that ours and SALib share (``numpy.random.default_rng(SEED)``)
SEED = 2

#: model runs per call, for ours and for SALib alike
CHUNK = 250_000

#: base rows N of the memory-against-N rows (the last only without --quick): powers of two, so
#: that the Sobol' design keeps its balance and SALib's sampler takes the same N
SOBOL_MEMORY_N = [2**13, 2**17, 2**20, 2**23]

#: N of the rows where SALib runs the memory task too (its sample matrix: 14.8 GB at 2^20)
SALIB_MEMORY_N = [2**13, 2**17]

#: N of the Zheng Sobol' rows, ours and SALib's (2^17 only without --quick)
ZHENG_SOBOL_N = [2**14, 2**17]


def _power(n: int) -> str:
    """``2^k`` for a power of two ``n``."""
    return f"2^{n.bit_length() - 1}"


def _sobol_case(case: str):
    """(model, sd, exact indices (41, 6)) of a Sobol' comparison case.

    ``zheng``: the machine's pose error at the paper's pose; ``linear``: its first-order model
    ``e @ J.T`` (runs cost little, so the memory is the estimator's), for which the closed form
    is exact."""
    from .. import sensitivity as S

    m, sd, pose = _zheng()
    if case == "zheng":
        return (lambda e: m.pose_error(e, pose)), sd, S.linear_indices(m.jacobian(pose), sd=sd)[0]
    jac = m.jacobian(pose).reshape(6, 41)
    return (lambda e: e @ jac.T), sd, S.linear_indices(jac, sd=sd)


def ours_sobol(model, sd, n: int):
    """Our Sobol' indices (S1, ST), streamed from a scrambled Sobol' design of ``n`` base rows.

    Parameters
    ----------
    model : callable
        ``(m, D)`` errors to ``(m, q)`` outputs.
    sd : array (D,)
        Standard deviations of the normal, zero-mean errors.
    n : int
        Base rows N (a power of two).

    Returns
    -------
    s1, st : arrays (D, q)
        First-order and total indices.
    """
    from .. import sensitivity as S

    design = S.SobolDesign(n, S.Inputs.normal(0.0, sd), method="sobol", seed=SEED)
    s1, st = S.sobol_indices(model, design, chunk=CHUNK)
    return s1, st


def salib_sobol(model, sd, n: int, *, stages: dict | None = None):
    """SALib's Sobol' indices (S1, ST) of ``model``: its sampler, the runs, its analysis.

    The same design as :func:`ours_sobol` (the Sobol' sequence of
    ``numpy.random.default_rng(SEED)``, the errors normal through ``dists="norm"``), the model
    run ``CHUNK`` rows per call, then ``sobol.analyze`` on each output without second-order
    indices and with its bootstrap at its smallest (two resamples).

    Parameters
    ----------
    model : callable
        ``(m, D)`` errors to ``(m, q)`` outputs.
    sd : array (D,)
        Standard deviations of the normal, zero-mean errors.
    n : int
        Base rows N (a power of two).
    stages : dict, optional
        Filled with the seconds of ``sample``, ``model`` and ``analyze``.

    Returns
    -------
    s1, st : arrays (D, q)
        First-order and total indices.
    """
    from SALib.analyze import sobol as analyze
    from SALib.sample import sobol as sample

    d = len(sd)
    problem = dict(num_vars=d, names=[f"e{i + 1}" for i in range(d)],
                   bounds=[[0.0, float(s)] for s in sd], dists=["norm"] * d)
    t0 = time.perf_counter()
    x = sample.sample(problem, n, calc_second_order=False, seed=np.random.default_rng(SEED))
    t1 = time.perf_counter()
    y = np.concatenate([model(x[s:s + CHUNK]) for s in range(0, len(x), CHUNK)])
    del x
    t2 = time.perf_counter()
    res = [analyze.analyze(problem, y[:, k], calc_second_order=False, num_resamples=2, seed=1)
           for k in range(y.shape[1])]
    t3 = time.perf_counter()
    if stages is not None:
        stages.update(sample=t1 - t0, model=t2 - t1, analyze=t3 - t2)
    return (np.array([r["S1"] for r in res]).T, np.array([r["ST"] for r in res]).T)


def _sobol_task(tool: str, case: str, n: int, repeat: int) -> dict:
    """One Sobol' row: ``tool`` (ours, salib) on ``case`` with N = ``n``; ``repeat`` 0 is one run.

    Returns the time, the largest errors of S1 and ST against the closed form, the indices
    themselves (for the comparison of the two tools) and a note."""
    model, sd, exact = _sobol_case(case)
    stages: dict = {}

    def run():
        if tool == "ours":
            return ours_sobol(model, sd, n), {}
        seconds: dict = {}
        return salib_sobol(model, sd, n, stages=seconds), seconds
    if repeat:
        run()                                   # warm-up
    t = np.inf
    for _ in range(max(repeat, 1)):             # the best run, with its own stages
        t0 = time.perf_counter()
        (s1, st), seconds = run()
        dt = time.perf_counter() - t0
        if dt < t:
            t, stages = dt, seconds
    how = f"min of {repeat}" if repeat else "one run"
    note = f"{how}; {n * (len(sd) + 2) / t / 1e6:.2g} M runs/s"
    if stages:
        note += "; " + ", ".join(f"{k} {v:.2f} s" for k, v in stages.items())
    return dict(time=t, err_s1=float(np.abs(s1 - exact).max()),
                err_st=float(np.abs(st - exact).max()),
                indices=[np.asarray(s1).tolist(), np.asarray(st).tolist()], note=note)


def _sobol_memory(n: int) -> dict:
    """Sobol' indices of the Zheng machine's first-order model, streamed; one run.

    41 errors, six outputs (``e @ J.T``: runs cost little, so the memory is the estimator's),
    from a Sobol' design of ``n`` base rows (``SobolDesign``), sampling included.  The peak
    should not grow with n once n exceeds ``sensitivity.BASE_ROWS``."""
    return _sobol_task("ours", "linear", n, 0)


def task_zheng_linear_pose():
    """All 41 x 6 closed-form indices at one pose, the Jacobian included.

    One call is too quick for the timer, so a loop of 1000 calls is timed and divided."""
    from .. import sensitivity as S

    m, sd, pose = _zheng()
    loop = 1000

    def each(fn):
        def run():
            for _ in range(loop):
                out = fn()
            return out
        return run
    t, s = _min_time(each(lambda: S.linear_indices(m.jacobian(pose), sd=sd)))
    t_jac, jac = _min_time(each(lambda: m.jacobian(pose)))
    t_idx, _ = _min_time(each(lambda: S.linear_indices(jac, sd=sd)))
    return dict(time=t / loop,
                note=f"{t / loop * 1e3:.3f} ms per call (loop of {loop} timed); of it Jacobian "
                     f"{t_jac / loop * 1e3:.3f} "
                     f"ms, indices {t_idx / loop * 1e6:.0f} us; {s.shape[-2]} x "
                     f"{s.shape[-1]} indices")


def task_zheng_linear_atlas():
    from .. import sensitivity as S

    m, sd, _ = _zheng()
    rng = np.random.default_rng(0)
    poses = {k: rng.uniform(lo, hi, 10_000) for k, (lo, hi) in m.travels.items()}
    var = sd**2
    t, s = _min_time(lambda: S.indices_at_poses(m.jacobian(poses), var=var))
    t_jac, jac = _min_time(lambda: m.jacobian(poses))
    return dict(time=t, note=f"{len(s) / t / 1e3:.0f} k poses/s; of it Jacobian "
                             f"{t_jac * 1e3:.0f} ms; output {s.shape}")


PCE_CASES = {  # name: (benchmark, n, degrees for ours, OpenTURNS degree, OpenTURNS repeats)
    "ishigami": ("ishigami", 1000, range(1, 15), 12, REPEAT),
    "g_function_8d": ("g_function_8d", 500, range(1, 7), 6, REPEAT),
    "g_function_41d": ("g_function_41d", 1000, (1, 2, 3), 3, 0),
    "interaction_polynomial": ("interaction_polynomial", 120, (1, 2, 3), 2, REPEAT),
}


def _case(name):
    from ..sensitivity.benchmarks import BENCHMARKS

    bench, n, degrees, ot_degree, ot_repeat = PCE_CASES[name]
    b = BENCHMARKS[bench]()
    x = b.sample(n, 1)
    return b, x, b.model(x), degrees, ot_degree, ot_repeat


def _errors(b, s1, st):
    top = np.argsort(-np.asarray(st), kind="stable")
    rank = "" if b.dim < 10 else ("; top six right" if set(top[:6]) == set(range(6))
                                  else f"; top six {sorted(int(i) for i in top[:6])}")
    return dict(err_s1=float(np.abs(s1 - b.s1).max()), err_st=float(np.abs(st - b.st).max()),
                rank=rank)


def _task_ours(name, method):
    import warnings

    from ..sensitivity import pce as P

    b, x, y, degrees, _, _ = _case(name)
    inp = b.inputs
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", P.PoorFitWarning)
        t, res = _min_time(lambda: P.fit_sparse_pce(x, y, inputs=inp, degrees=degrees,
                                                    method=method))
    f = res.fit
    return dict(time=t, **_errors(b, res.s1, res.st),
                note=f"degree {f.degree}, q {f.q_norm:g}, {len(f.coef)} terms of {f.n_candidates}"
                     f", validation {f.validation:.1e}, LOO {f.loo:.1e}"
                     + ("" if res.reliable else ", PoorFitWarning"))


def _task_openturns(name):
    try:
        import openturns as ot
    except ImportError:
        return dict(time=float("nan"), note="OpenTURNS not importable in this Python: skipped "
                                            "(--with-openturns runs it in a venv of its own)")
    b, x, y, _, degree, repeat = _case(name)
    d = x.shape[1]
    dists = [ot.Uniform(*m.support()) for m in b.inputs.marginals]

    def run():
        enum = ot.HyperbolicAnisotropicEnumerateFunction(d, 1.0)
        basis = ot.OrthogonalProductPolynomialFactory(
            [ot.StandardDistributionPolynomialFactory(m) for m in dists], enum)
        adaptive = ot.FixedStrategy(basis, enum.getStrataCumulatedCardinal(degree))
        proj = ot.LeastSquaresStrategy(ot.LeastSquaresMetaModelSelectionFactory(
            ot.LARS(), ot.CorrectedLeaveOneOut()))
        algo = ot.FunctionalChaosAlgorithm(ot.Sample(x), ot.Sample(y[:, None]),
                                           ot.JointDistribution(dists), adaptive, proj)
        algo.run()
        res = algo.getResult()
        sens = ot.FunctionalChaosSobolIndices(res)
        return (np.array([sens.getSobolIndex(i) for i in range(d)]),
                np.array([sens.getSobolTotalIndex(i) for i in range(d)]),
                res.getIndices().getSize())
    if repeat:
        t, (s1, st, terms) = _min_time(run, repeat)
    else:  # one run, no warm-up (g_function_41d: over 25 min with openturns 1.27.post1 here)
        t0 = time.perf_counter()
        s1, st, terms = run()
        t = time.perf_counter() - t0
    return dict(time=t, **_errors(b, s1, st),
                note=f"LARS + corrected LOO, Legendre degree {degree}, {terms} terms"
                     + ("" if repeat else "; one run"))


def _pce_tasks():
    for name in PCE_CASES:
        for method in ("omp", "lars"):
            yield f"pce_{name}_{method}", (lambda nm=name, me=method: _task_ours(nm, me))
        yield f"pce_{name}_openturns", (lambda nm=name: _task_openturns(nm))


def _thermal_limit_data(n_exp=10, n_meas=100, n_sens=100, n_pos=500, seed=0, dt=3.0):
    """A thermal dataset at the reader's size limits (issue 22), from a small model of its own:
    first-order thermal nodes (time constants 5-150 min) driven by the drive's heat and the
    air; errors k(T) x + b(T) + a bow + 0.3 um noise."""
    import pandas as pd

    from ..thermal import ThermalData

    rng = np.random.default_rng(seed)
    t = np.arange(n_meas) * dt
    tau = np.exp(rng.uniform(np.log(5), np.log(150), n_sens))
    gain = rng.uniform(0.2, 1.0, n_sens) * np.where(rng.random(n_sens) < 0.3, 0.1, 1.0)
    air = rng.uniform(0.1, 1.0, n_sens)
    feeds = rng.choice([1000, 2000, 3000, 4000, 5000, 6000], n_exp)
    x = np.linspace(0.0, 998.0, n_pos)
    a = np.exp(-dt / tau)
    rows, temps, errs = [], [], []
    for e in range(n_exp):
        stop = rng.uniform(0.5, 1.0) * t[-1]
        drive = np.where(t < stop, feeds[e] / 1000.0 * rng.uniform(0.8, 1.2), 0.0)
        amb = 20 + rng.uniform(-2, 2) + np.sin(2 * np.pi * (t + rng.uniform(0, 600)) / 600)
        rise = np.zeros((n_meas, n_sens))
        for i in range(1, n_meas):   # first-order nodes, exact steps (a loop over time)
            rise[i] = a * rise[i - 1] + (1 - a) * gain * 4.0 * drive[i - 1]
        temp = amb[0] + air * (amb - amb[0])[:, None] + rise + rng.normal(0, 0.02, rise.shape)
        d = temp - temp[0]
        k = 3.0 * (temp[:, 3] - 20) - 1.5 * (temp[:, 40] - 20) + 0.8 * (temp[:, 77] - 20)
        b = 2.0 * d[:, 10] + 1.2 * d[:, 55] - 0.7 * d[:, 90]
        bow = 0.3 * (np.abs(d[:, 22]) ** 1.5)[:, None] * np.sin(np.pi * x / x[-1])
        errs.append(k[:, None] * x / 1000 + b[:, None] + bow + 0.2 * np.sin(x / 37.0)
                    + rng.normal(0, 0.3, (n_meas, n_pos)))
        rows.append(pd.DataFrame({"experiment": e + 1, "measurement": np.arange(1, n_meas + 1),
                                  "time_min": t}))
        temps.append(temp)
    return ThermalData(pd.concat(rows, ignore_index=True),
                       pd.DataFrame(np.vstack(temps), columns=[f"T{j + 1}" for j in range(n_sens)]),
                       np.vstack(errs), x + 100.0, {e + 1: float(f) for e, f in enumerate(feeds)},
                       source="bench")


def task_xu_split_limit():
    """One train/test split of notebook 04 at the reader's limits; one run.

    The limits are 1000 measurements x 100 sensors x 500 positions; the split runs selection,
    point-by-point MLR, decoupled MLR and SVR."""
    from .. import thermal

    data = _thermal_limit_data()
    t0 = time.perf_counter()
    thermal.evaluate_split(data, train=list(range(1, 10)), test=[10], n_clusters=3)
    return dict(time=time.perf_counter() - t0, note="one run (not min of 3)")


def task_explore_update():
    """One slider move of the explorer's Machine tab (``mtaccuracy.compendium.explore``).

    The move computes the closed-form indices at the pose and the dominant-error map over a 25 x 25
    grid, for each of the papers' three machines at its starting pose; min of 10 runs each after a
    warm-up.  The time is the slowest machine's."""
    from . import explore_model as M

    times = {name: M.time_slider_update(M.machine_setup(name), repeat=10)
             for name in M.MACHINES}
    return dict(time=max(times.values()),
                note="; ".join(f"{n} {t * 1e3:.1f} ms" for n, t in times.items()))


TASKS = {
    "xu_split_limit": task_xu_split_limit,
    "explore_update": task_explore_update,
    "guo_pose_error": task_guo_pose_error,
    "guo_spearman": task_guo_spearman,
    "zheng_pose_error": task_zheng_pose_error,
    "zheng_pce_one": task_zheng_pce_one,
    "zheng_pce_six": task_zheng_pce_six,
    "zheng_mcs": task_zheng_mcs,
    "zheng_linear_pose": task_zheng_linear_pose,
    "zheng_linear_atlas": task_zheng_linear_atlas,
    **{f"zheng_sobol_n{n}": (lambda n=n: _sobol_task("ours", "zheng", n, 0 if n >= 2**17
                                                     else REPEAT)) for n in ZHENG_SOBOL_N},
    **{f"zheng_salib_n{n}": (lambda n=n: _sobol_task("salib", "zheng", n, 0 if n >= 2**17
                                                     else REPEAT)) for n in ZHENG_SOBOL_N},
    **dict(_pce_tasks()),
    **{f"sobol_memory_n{n}": (lambda n=n: _sobol_memory(n)) for n in SOBOL_MEMORY_N},
    **{f"sobol_memory_salib_n{n}": (lambda n=n: _sobol_task("salib", "linear", n, 0))
       for n in SALIB_MEMORY_N},
}

#: modules a task's process imports before its memory baseline, by a word of the task's name
#: (a peer's package counts as ours does: not in the task's memory)
TASK_IMPORTS = {"salib": ("SALib.sample.sobol", "SALib.analyze.sobol"),
                "openturns": ("openturns",)}

#: our task -> the peer's task it is compared with (the ratio goes in our row's note)
PEERS = {**{f"zheng_sobol_n{n}": f"zheng_salib_n{n}" for n in ZHENG_SOBOL_N},
         **{f"sobol_memory_n{n}": f"sobol_memory_salib_n{n}" for n in SALIB_MEMORY_N},
         **{f"pce_{c}_{m}": f"pce_{c}_openturns" for c in PCE_CASES for m in ("omp", "lars")}}

#: rows left out by --quick (a few minutes)
FULL_ONLY = {f"sobol_memory_n{2**23}", f"zheng_sobol_n{2**17}", f"zheng_salib_n{2**17}",
             f"sobol_memory_salib_n{2**17}"}


def _sobol_rows():
    """The rows of the Zheng Sobol' comparison, ours then SALib's at each N."""
    for n in ZHENG_SOBOL_N:
        size = f"N {_power(n)}, {n * 43:.1e} runs"
        yield ("Zheng 2024", f"zheng_sobol_n{n}", "Sobol' (S1, ST), ours", size, "", None)
        yield ("Zheng 2024", f"zheng_salib_n{n}", "Sobol' (S1, ST), SALib", size, "", None)


def _memory_rows():
    """The memory-against-N rows, SALib's beside ours where it runs."""
    for n in SOBOL_MEMORY_N:
        size = f"N {_power(n)}, 43 N runs"
        yield ("memory", f"sobol_memory_n{n}", "Sobol streamed, linear 41 x 6", size,
               "peak flat in N", None)
        if n in SALIB_MEMORY_N:
            yield ("memory", f"sobol_memory_salib_n{n}", "SALib, linear 41 x 6", size, "", None)


#: (paper, task, what, size, target, published seconds)
ROWS = [
    ("Xu 2022", "xu_split_limit", "one split: selection, MLR, SVR", "1000 x 100 x 500",
     "<= 60 s", None),
    ("Guo 2016", "guo_pose_error", "vertical_xyfz pose error", "1e6 samples", "", None),
    ("Guo 2016", "guo_spearman", "Spearman, batched", "200 x 500 x 21 x 4", "", None),
    ("Zheng 2024", "zheng_pose_error", "ac_double_turntable pose error", "1e6 samples",
     ">= 2 M samples/s", None),
    ("Zheng 2024", "zheng_pce_one", "PCE, one component", "n 1e3, degree 3, 13244 terms",
     "<= 0.5 s", 7.8761),
    ("Zheng 2024", "zheng_pce_six", "PCE, all six components", "n 1e3, degree 3", "", 7.8761),
    ("Zheng 2024", "zheng_mcs", "MCS Sobol (S1, ST), one pose", "N 1e5, 4.3e6 runs",
     "<= 3 s, <= 300 MB", 244.0789),
    *_sobol_rows(),
    *_memory_rows(),
    ("Zheng 2024", "zheng_linear_pose", "linear closed form, one pose", "41 x 6, Jacobian incl.",
     "<= 1 ms", None),
    ("Zheng 2024", "zheng_linear_atlas", "linear closed form, pose atlas", "1e4 poses in travels",
     "<= 10 s", None),
    ("explorer", "explore_update", "slider move: indices + map", "3 machines, 25 x 25 grid",
     "<= 0.1 s", None),
]
for _name, (_b, _n, _deg, _otd, _) in PCE_CASES.items():
    for _m in ("omp", "lars", "openturns"):
        ROWS.append(("PCE bench", f"pce_{_name}_{_m}", f"{_name} ({_m})",
                     f"n {_n}, degree <= {max(_deg) if _m != 'openturns' else _otd}",
                     "<= 3 s" if _name == "g_function_41d" and _m == "omp" else "", None))


def run_task(name: str) -> dict:
    """Run one task in this process; its time, peak RSS and the task's own memory.

    The task's own memory is its peak RSS above the process with the library imported (numpy,
    scipy, pandas, scikit-learn, chaospy: about 120 MB, the same for every task) and the peer's
    package a peer's task measures (``TASK_IMPORTS``), MB."""
    import importlib

    from .. import machines, sensitivity  # noqa: F401

    for word, modules in TASK_IMPORTS.items():
        if word in name:
            for module in modules:
                try:
                    importlib.import_module(module)
                except ImportError:   # the task says so itself
                    pass
    start = _rss_mb()
    out = TASKS[name]()
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return dict(out, peak_mb=peak, task_mb=peak - start)


def _failed(note: str) -> dict:
    """A row that has no measurement, with the reason."""
    return dict(time=float("nan"), peak_mb=float("nan"), task_mb=float("nan"), note=note)


def _lib_dir() -> str:
    """The folder holding the ``mtaccuracy`` package this bench runs from."""
    return str(Path(__file__).resolve().parents[2])


def _in_subprocess(name: str, timeout: float | None = None, python: str | None = None) -> dict:
    """Run task ``name`` in a fresh process of ``python`` (default: this one); its JSON."""
    path = os.environ.get("PYTHONPATH", "")
    env = dict(os.environ, PYTHONPATH=_lib_dir() + (os.pathsep + path if path else ""))
    try:
        res = subprocess.run([python or sys.executable, "-m", "mtaccuracy.compendium.bench",
                              "--task", name], capture_output=True, text=True, timeout=timeout,
                             env=env)
    except subprocess.TimeoutExpired:
        return _failed(f"stopped after {timeout:.0f} s (--timeout)")
    if res.returncode != 0:
        return _failed("FAILED: " + (res.stderr.strip().splitlines() or ["?"])[-1])
    return json.loads(res.stdout.strip().splitlines()[-1])


# ------------------------------------------------------------------------------------------
# OpenTURNS in an environment of its own (--with-openturns)
# ------------------------------------------------------------------------------------------

#: what ``--with-openturns`` installs into ``build/bench-openturns/`` (from PyPI)
OPENTURNS_REQUIREMENT = "openturns==1.27.post1"

#: the .pth file through which the OpenTURNS environment sees the project's packages
PROJECT_PTH = "mtaccuracy-bench-project.pth"

NO_OPENTURNS = ("not run: --with-openturns (BENCH_ARGS=--with-openturns make bench) installs "
                "OpenTURNS into build/bench-openturns/, a venv of its own, and runs these rows")


def openturns_env() -> Path:
    """The folder of the bench's OpenTURNS environment, ``build/bench-openturns/``.

    Returns
    -------
    pathlib.Path
        Under the repository's root (``build/`` is ignored by git).
    """
    from . import paths

    return paths.ROOT / "build" / "bench-openturns"


def openturns_env_commands(env: Path, *, python: str | None = None) -> list[list[str]]:
    """The commands that make the OpenTURNS environment: a venv, then pip install into it.

    The venv is made by this Python (so it is of the same version) without
    ``--system-site-packages`` (that would show the base interpreter's packages, not the
    project's); :func:`ensure_openturns_env` writes the ``.pth`` file through which it sees
    the project's between the two.  pip runs as the new environment's Python, so OpenTURNS
    (and only what it lacks of its dependencies) lands there, never in the project's.

    Parameters
    ----------
    env : pathlib.Path
        The environment's folder.
    python : str, optional
        The Python that makes the venv (default: this one, ``sys.executable``).

    Returns
    -------
    list of list of str
        The ``venv`` command, then the ``pip install`` command.
    """
    env_python = str(env / "bin" / "python")
    return [[python or sys.executable, "-m", "venv", str(env)],
            [env_python, "-m", "pip", "install", "--quiet", "--disable-pip-version-check",
             OPENTURNS_REQUIREMENT]]


def project_pth(site_dirs) -> str:
    """The ``.pth`` text that adds the project's site folders (and their own .pth files).

    Parameters
    ----------
    site_dirs : sequence of str
        The project environment's site-packages folders.

    Returns
    -------
    str
        One ``import site; site.addsitedir(...)`` line per folder (``addsitedir`` also
        processes the folder's ``.pth`` files, e.g. an editable install's).
    """
    return "".join(f"import site; site.addsitedir({str(d)!r})\n" for d in site_dirs)


def _site_dirs() -> list[str]:
    """This environment's site-packages folders (pure and platform), once each."""
    import sysconfig

    return list(dict.fromkeys(sysconfig.get_paths()[k] for k in ("purelib", "platlib")))


def ensure_openturns_env(env: Path | None = None, *, run=subprocess.run) -> Path:
    """The Python of the bench's OpenTURNS environment, made the first time it is asked for.

    An environment whose Python imports ``openturns`` is used as it is; otherwise it is made:
    :func:`openturns_env_commands`' venv, the ``.pth`` file of :func:`project_pth` in its
    site-packages (so that it runs the project's numpy, scipy, ... and this library), then
    the pip install.

    Parameters
    ----------
    env : pathlib.Path, optional
        The environment's folder (default :func:`openturns_env`).
    run : callable
        Runs a command (``subprocess.run``'s signature; a test passes a recorder).

    Returns
    -------
    pathlib.Path
        The environment's Python.

    Raises
    ------
    subprocess.CalledProcessError
        If making the venv or installing OpenTURNS fails (e.g. PyPI unreachable).
    """
    env = openturns_env() if env is None else env
    python = env / "bin" / "python"
    if python.exists() and run([str(python), "-c", "import openturns"],
                               capture_output=True).returncode == 0:
        return python
    make_venv, install = openturns_env_commands(env)
    run(make_venv, check=True)
    version = f"python{sys.version_info.major}.{sys.version_info.minor}"
    site = env / "lib" / version / "site-packages"
    (site / PROJECT_PTH).write_text(project_pth(_site_dirs()), encoding="utf-8")
    run(install, check=True)
    return python


def _peer_note(ours: dict, peer: dict, name: str) -> str:
    """``; SALib 20x the time, ...``: the peer's time and memory over ours, and the indices."""
    if not (peer.get("time", float("nan")) > 0 and ours.get("time", float("nan")) > 0):
        return ""
    def times(x):
        return f"{x:.1f}x" if x >= 1 else f"{x:.2g}x"
    note = (f"; {name} {times(peer['time'] / ours['time'])} the time, "
            f"{times(peer['task_mb'] / max(ours['task_mb'], 1.0))} the task MB, "
            f"{times(peer['peak_mb'] / ours['peak_mb'])} the peak")
    if "indices" in ours and "indices" in peer:
        diff = np.abs(np.asarray(ours["indices"]) - np.asarray(peer["indices"])).max()
        note += f"; indices agree to {diff:.0e}"
    return note


_MEASURE = """
import resource, subprocess, sys, time
t0 = time.perf_counter()
rc = subprocess.run(sys.argv[1:], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL).returncode
print(time.perf_counter() - t0, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss, rc)
"""


def _command_rows(repeat: int = 2):
    """Issue 11's targets: ``make reproduce`` <= 90 s and ``make test`` <= 150 s, each in a
    fresh clone of HEAD sharing this checkout's .venv (the environment exists), min of
    ``repeat`` runs; memory: the largest single process of the run (peak RSS)."""
    import tempfile
    from pathlib import Path

    from . import paths

    with tempfile.TemporaryDirectory(prefix="mtaccuracy-bench-") as tmp:
        clone = Path(tmp) / "clone"
        subprocess.run(["git", "clone", "-q", str(paths.ROOT), str(clone)], check=True)
        (clone / ".venv").symlink_to(paths.ROOT / ".venv")
        env = dict(os.environ, PYTHONPATH=str(clone / "lib"))
        for target, goal in (("reproduce", "<= 90 s"), ("test", "<= 150 s")):
            runs = []
            for _ in range(repeat):
                res = subprocess.run([sys.executable, "-c", _MEASURE, "make", "-C", str(clone),
                                      target], env=env, capture_output=True, text=True)
                seconds, rss, rc = res.stdout.split()
                runs.append((float(seconds), int(rss), int(rc)))
            best = min(runs)
            yield (f"make {target} (fresh clone)", f"min of {repeat}", goal,
                   dict(time=best[0], peak_mb=max(r[1] for r in runs) / 1024,
                        task_mb=float("nan"),
                        note="" if all(r[2] == 0 for r in runs) else "A RUN FAILED"))


def main(argv=None) -> int:
    """Run the rows (each task in a process of its own) and print the table, or one task.

    Parameters
    ----------
    argv : list of str, optional
        Command-line arguments (default ``sys.argv[1:]``); ``--help`` lists them.

    Returns
    -------
    int
        The exit status, 0.
    """
    import argparse
    import shlex

    ap = argparse.ArgumentParser(prog="python -m mtaccuracy.compendium.bench")
    ap.add_argument("--quick", action="store_true",
                    help="skip timing make reproduce and make test, the N = 2^23 memory row "
                         "and the N = 2^17 SALib rows (a few minutes)")
    ap.add_argument("--from-env", action="store_true",
                    help="also read arguments from $BENCH_ARGS (as make bench passes them)")
    ap.add_argument("--task", choices=sorted(TASKS), help="run one task here, print JSON")
    ap.add_argument("--only", default="",
                    help="run only the rows whose task contains this (and their peers)")
    ap.add_argument("--with-openturns", action="store_true",
                    help="run the OpenTURNS rows in build/bench-openturns/, a venv of their own "
                         "that is made (with OpenTURNS from PyPI) the first time")
    ap.add_argument("--timeout", type=float, default=600.0,
                    help="stop an OpenTURNS task after this many seconds (default 600)")
    args = ap.parse_args(argv)
    if args.from_env:
        args = ap.parse_args([*(argv or []), *shlex.split(os.environ.get("BENCH_ARGS", ""))])
    if args.task:
        print(json.dumps(run_task(args.task)))
        return 0
    left_out = FULL_ONLY if args.quick else set()
    chosen = {t for _, t, *_ in ROWS if args.only in t} - left_out
    chosen |= ({p for t, p in PEERS.items() if t in chosen}
               | {t for t, p in PEERS.items() if p in chosen}) - left_out
    ot_python, ot_note = None, NO_OPENTURNS
    if args.with_openturns and any(t.endswith("openturns") for t in chosen):
        print(f"OpenTURNS environment: {openturns_env()} ({OPENTURNS_REQUIREMENT}; made once)",
              flush=True)
        try:
            ot_python = str(ensure_openturns_env())
        except (OSError, subprocess.CalledProcessError) as exc:
            ot_note = f"FAILED to make the OpenTURNS environment: {exc}"
    head = (f"{'paper':<10} {'what':<34} {'size':<30} {'min time':>9}  {'target':<18} "
            f"{'peak MB':>8} {'task MB':>8} {'err S1':>8} {'err ST':>8}  note")
    print(head)
    print("-" * len(head), flush=True)

    def show(paper, what, size, target, r, published=None):
        e1 = f"{r['err_s1']:>8.1e}" if "err_s1" in r else f"{'':>8}"
        et = f"{r['err_st']:>8.1e}" if "err_st" in r else f"{'':>8}"
        note = r.get("note", "") + r.get("rank", "")
        if published:
            note += f"; paper {published:.2f} s (ratio {r['time'] / published:.3f})"
        print(f"{paper:<10} {what:<34} {size:<30} {r['time']:>8.3f}s  {target:<18} "
              f"{r['peak_mb']:>8.0f} {r['task_mb']:>8.0f} {e1} {et}  {note}", flush=True)

    results: dict = {}

    def result(task):
        if task not in results:
            if not task.endswith("openturns"):
                results[task] = _in_subprocess(task)
            elif ot_python is None:
                results[task] = _failed(ot_note)
            else:
                results[task] = _in_subprocess(task, args.timeout, python=ot_python)
        return results[task]

    for paper, task, what, size, target, published in ROWS:
        if task in chosen:
            r = dict(result(task))
            if PEERS.get(task) in chosen:
                peer = PEERS[task]
                r["note"] = r.get("note", "") + _peer_note(
                    r, result(peer), "OpenTURNS" if peer.endswith("openturns") else "SALib")
            show(paper, what, size, target, r, published)
    if not args.quick and not args.only:
        for what, size, target, r in _command_rows():
            show("all", what, size, target, r)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
