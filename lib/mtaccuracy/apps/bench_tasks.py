"""The bench's tasks: each measures one speed target of the issues, in a process of its own.

Each ``task_*`` returns ``dict(time=..., note=..., [err_s1, err_st])``; :data:`TASKS` names
them for :mod:`mtaccuracy.apps.bench`, which runs each in a fresh Python process so that the
memory it reports is that task's alone.

Local imports: every task imports what it measures inside itself, so that a process running one
task loads only that task's libraries (its peak memory is the task's).
"""

from __future__ import annotations

import os
import time

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
    """One slider move of the explorer's Machine tab (``mtaccuracy.apps.explore``).

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
