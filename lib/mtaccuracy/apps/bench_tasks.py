"""The bench's rows (:data:`ROWS`) and the tasks that measure them, each in a process of its own.

A task returns ``dict(time=..., note=..., [err_s1, err_st, indices])``; :mod:`.bench` runs it in
a fresh Python process and adds the memory.  Local imports: a task imports the modules only it
needs (thermal, the explorer, SALib, OpenTURNS) inside itself, so that they count in its memory
as what it measures; the library's machines and sensitivity are imported before the baseline.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from functools import partial
from typing import NamedTuple

import numpy as np

from .. import errors
from .. import sensitivity as S
from ..machines import build
from ..sensitivity.benchmarks import BENCHMARKS

REPEAT = 3        # timed runs after the warm-up, unless a row says otherwise
SEED = 2          # the Sobol' designs ours and SALib share: numpy.random.default_rng(SEED)
CHUNK = 250_000   # model runs per call, ours and SALib's alike


def rss_mb() -> float:
    """The resident set size of this process now, MB (Linux /proc)."""
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def timed(fn: Callable, repeat: int = REPEAT, number: int = 1) -> tuple[float, object]:
    """``(seconds a call, result)``: the fastest of ``repeat`` runs (0: one) of ``number`` calls.

    A warm-up run goes first unless ``repeat`` is 0.  At most two results are held at a time
    (the best and the one being made), so that a task's memory is what it makes."""
    best = (np.inf, None)
    for i in range(repeat + 1 if repeat else 1):
        t0 = time.perf_counter()
        for _ in range(number):
            out = fn()
        dt = (time.perf_counter() - t0) / number
        if (i or not repeat) and dt < best[0]:
            best = (dt, out)
        del out
    return best


def _zheng():
    """The Zheng et al. machine, its 41 errors' standard deviations and the paper's pose."""
    m = build("ac_double_turntable")
    sd = np.array([e.to_library * (15.0 if e.translational else 10.0) / 3 for e in m.catalogue])
    return m, sd, dict(x=106.1, y=-58.6, z=-255.3, A=np.deg2rad(60.7), C=np.deg2rad(56.7))


def _guo():
    """The Guo et al. machine, its 21 errors' uniform bounds and the pose."""
    m = build("vertical_xyfz")
    b = errors.uniform_bounds(m.catalogue, {"positioning": (0, 3), "straightness": (0, 4),
                                            "angular": (0, 3.2e-5), "squareness": (0, 1.9)})
    return m, b, dict(x=100.0, y=100.0, z=100.0)


def pose_error(machine: str) -> dict:
    """The pose error of ``machine`` (Guo's, Zheng's) for 1e6 error samples."""
    if machine == "guo":
        m, b, pose = _guo()
        x, note = S.latin_hypercube(1_000_000, b, 0), ""
    else:
        m, sd, pose = _zheng()
        x = np.random.default_rng(0).standard_normal((1_000_000, 41))
        x *= sd
        note = " (task MB: the 328 MB input, the output)"
    t, _ = timed(lambda: m.pose_error(x, pose))
    return dict(time=t, note=f"{1 / t:.2f} M samples/s{note}")


def guo_spearman() -> dict:
    """Spearman's coefficients of 200 repeats of 500 samples, 21 errors, 4 outputs, batched."""
    m, b, pose = _guo()
    d = S.repeated_latin_hypercube(500, b, repeats=200, seed=2)
    y = S.position_outputs(m.pose_error(d.reshape(-1, 21), pose)).reshape(200, 500, 4)
    return dict(time=timed(lambda: S.spearman(d, y))[0], note="")


def zheng_pce(components) -> dict:
    """Zheng et al.'s degree-3 PCE of the pose error's ``components`` from 1000 LHS samples."""
    m, sd, pose = _zheng()
    xi = S.Inputs.normal(0.0, np.ones(41)).from_unit(
        S.base_samples(1000, 41, method="lhs", seed=1)[0])
    yv = m.pose_error(xi * sd, pose)

    def run():
        alphas = S.multi_indices(41, 3)
        psi = S.design_matrix(xi, alphas)
        fits = S.fit_pce_outputs(xi, yv[:, list(components)], psi=psi, alphas=alphas)
        return [S.pce_sobol(f) for f in fits]
    t, out = timed(run)
    kept = ", ".join(str(int((o[1] > 0).sum())) for o in out)
    return dict(time=t, note=f"terms kept: {kept} inputs with an index")


def zheng_mcs() -> dict:
    """Monte Carlo Sobol' indices at N = 1e5, sampling included, streamed 250 000 runs a call."""
    m, sd, pose = _zheng()
    design = S.SobolDesign(100_000, S.Inputs.normal(0.0, sd), method="mc", seed=2)
    t, (s1, st) = timed(lambda: S.sobol_indices(lambda z: m.pose_error(z, pose), design,
                                                chunk=CHUNK))
    lin = S.linear_indices(m.jacobian(pose), sd=sd)[0]
    return dict(time=t, note=f"largest |ST - linear closed form| {np.abs(st - lin).max():.1e}")


def sobol_case(case: str):
    """``(model, sd, exact (41, 6))``: ``zheng``, the machine, or ``linear``, its linear model.

    The closed form on the Jacobian is exact for ``linear`` (whose runs cost little, so that
    its memory is the estimator's) and the first-order answer for ``zheng``."""
    m, sd, pose = _zheng()
    if case == "zheng":
        return (lambda e: m.pose_error(e, pose)), sd, S.linear_indices(m.jacobian(pose), sd=sd)[0]
    jac = m.jacobian(pose).reshape(6, 41)
    return (lambda e: e @ jac.T), sd, S.linear_indices(jac, sd=sd)


def ours_sobol(model, sd, n: int, stages: dict | None = None):
    """Our ``(S1, ST)`` of ``model``, errors normal of ``sd``, N = ``n`` (``stages`` unused)."""
    design = S.SobolDesign(n, S.Inputs.normal(0.0, sd), method="sobol", seed=SEED)
    return S.sobol_indices(model, design, chunk=CHUNK)


def salib_sobol(model, sd, n: int, stages: dict | None = None):
    """SALib's ``(S1, ST)`` on :func:`ours_sobol`'s design; ``stages`` gets each stage's seconds.

    Its sampler (``dists="norm"``, the same ``default_rng(SEED)``), the model run ``CHUNK``
    rows a call, then ``sobol.analyze`` on each output without second-order indices and with
    its bootstrap (which it cannot switch off) at its smallest, two resamples."""
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
    if stages is not None:
        stages.update(sample=t1 - t0, model=t2 - t1, analyze=time.perf_counter() - t2)
    return np.array([r["S1"] for r in res]).T, np.array([r["ST"] for r in res]).T


def sobol_task(tool, case: str, n: int, repeat: int = 0) -> dict:
    """One Sobol' row: ``tool`` (:func:`ours_sobol`, :func:`salib_sobol`) on ``case``, N = ``n``."""
    model, sd, exact = sobol_case(case)

    def run():
        stages: dict = {}
        return tool(model, sd, n, stages), stages
    t, ((s1, st), stages) = timed(run, repeat)
    note = (f"{f'min of {repeat}' if repeat else 'one run'}; "
            f"{n * (len(sd) + 2) / t / 1e6:.2g} M runs/s")
    if stages:
        note += "; " + ", ".join(f"{k} {v:.2f} s" for k, v in stages.items())
    return dict(time=t, err_s1=float(np.abs(s1 - exact).max()),
                err_st=float(np.abs(st - exact).max()),
                indices=[np.asarray(s1).tolist(), np.asarray(st).tolist()], note=note)


def zheng_linear_pose(loop: int = 1000) -> dict:
    """All 41 x 6 closed-form indices at one pose, Jacobian included (``loop`` calls timed)."""
    m, sd, pose = _zheng()
    jac = m.jacobian(pose)
    t, s = timed(lambda: S.linear_indices(m.jacobian(pose), sd=sd), number=loop)
    t_jac, _ = timed(lambda: m.jacobian(pose), number=loop)
    t_idx, _ = timed(lambda: S.linear_indices(jac, sd=sd), number=loop)
    return dict(time=t, note=f"{t * 1e3:.3f} ms per call (loop of {loop} timed); of it Jacobian "
                             f"{t_jac * 1e3:.3f} ms, indices {t_idx * 1e6:.0f} us; "
                             f"{s.shape[-2]} x {s.shape[-1]} indices")


def zheng_linear_atlas() -> dict:
    """The closed-form indices at 1e4 random poses within the machine's travels."""
    m, sd, _ = _zheng()
    rng = np.random.default_rng(0)
    poses = {k: rng.uniform(lo, hi, 10_000) for k, (lo, hi) in m.travels.items()}
    var = sd**2
    t, s = timed(lambda: S.indices_at_poses(m.jacobian(poses), var=var))
    t_jac, _ = timed(lambda: m.jacobian(poses))
    return dict(time=t, note=f"{len(s) / t / 1e3:.0f} k poses/s; of it Jacobian "
                             f"{t_jac * 1e3:.0f} ms; output {s.shape}")


#: sparse-PCE benchmarks with exact indices: n, our degrees, OpenTURNS' degree and repeats
PCE_CASES = {"ishigami": (1000, range(1, 15), 12, REPEAT),
             "g_function_8d": (500, range(1, 7), 6, REPEAT),
             "g_function_41d": (1000, (1, 2, 3), 3, 0),   # OpenTURNS: over 25 min, one run
             "interaction_polynomial": (120, (1, 2, 3), 2, REPEAT)}


def _pce_case(name: str):
    """``(benchmark, x, y)``: benchmark ``name`` and its samples (seed 1), ours and OpenTURNS'."""
    b = BENCHMARKS[name]()
    x = b.sample(PCE_CASES[name][0], 1)
    return b, x, b.model(x)


def _pce_errors(b, s1, st) -> dict:
    """The largest errors of S1 and ST, and for many inputs whether the top six by ST are right."""
    top = sorted(int(i) for i in np.argsort(-np.asarray(st), kind="stable")[:6])
    rank = "" if b.dim < 10 else (
        "; top six right" if top == list(range(6)) else f"; top six {top}")
    return dict(err_s1=float(np.abs(s1 - b.s1).max()), err_st=float(np.abs(st - b.st).max()),
                rank=rank)


def pce_ours(name: str, method: str) -> dict:
    """Our ``fit_sparse_pce`` (``method``: omp, lars; basis and length validated) on ``name``."""
    import warnings

    b, x, y = _pce_case(name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", S.PoorFitWarning)
        t, res = timed(lambda: S.fit_sparse_pce(x, y, inputs=b.inputs,
                                                degrees=PCE_CASES[name][1], method=method))
    f = res.fit
    return dict(time=t, **_pce_errors(b, res.s1, res.st),
                note=f"degree {f.degree}, q {f.q_norm:g}, {len(f.coef)} terms of {f.n_candidates}"
                     f", validation {f.validation:.1e}, LOO {f.loo:.1e}"
                     + ("" if res.reliable else ", PoorFitWarning"))


def pce_openturns(name: str) -> dict:
    """OpenTURNS' ``FunctionalChaosAlgorithm`` (LARS, corrected LOO, Legendre) on ``name``."""
    try:
        import openturns as ot
    except ImportError:
        return dict(time=float("nan"), note="OpenTURNS not importable in this Python: skipped "
                                            "(--with-openturns runs it in a venv of its own)")
    b, x, y = _pce_case(name)
    _, _, degree, repeat = PCE_CASES[name]
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
    t, (s1, st, terms) = timed(run, repeat)
    return dict(time=t, **_pce_errors(b, s1, st),
                note=f"LARS + corrected LOO, Legendre degree {degree}, {terms} terms"
                     + ("" if repeat else "; one run"))


def _thermal_limit_data(n_exp=10, n_meas=100, n_sens=100, n_pos=500, seed=0, dt=3.0):
    """A thermal dataset at the reader's size limits (issue 22), from a small model of its own.

    First-order thermal nodes (time constants 5-150 min) driven by the drive's heat and the
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
    temps, errs = [], []
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
        temps.append(temp)
    index = pd.DataFrame({"experiment": np.repeat(np.arange(1, n_exp + 1), n_meas),
                          "measurement": np.tile(np.arange(1, n_meas + 1), n_exp),
                          "time_min": np.tile(t, n_exp)})
    return ThermalData(index,
                       pd.DataFrame(np.vstack(temps), columns=[f"T{j + 1}" for j in range(n_sens)]),
                       np.vstack(errs), x + 100.0, {e + 1: float(f) for e, f in enumerate(feeds)},
                       source="bench")


def xu_split_limit() -> dict:
    """One split of notebook 04 (selection, point-by-point and decoupled MLR, SVR) at the limits."""
    from .. import thermal

    data = _thermal_limit_data()
    t, _ = timed(lambda: thermal.evaluate_split(data, train=list(range(1, 10)), test=[10],
                                                n_clusters=3), 0)
    return dict(time=t, note="one run (not min of 3)")


def explore_update() -> dict:
    """One slider move of the explorer's Machine tab on each of its three machines; the slowest."""
    from . import explore_model as M

    times = {name: timed(partial(M.slider_update, M.machine_setup(name)), 10)[0]
             for name in M.MACHINES}
    return dict(time=max(times.values()),
                note="; ".join(f"{n} {t * 1e3:.1f} ms" for n, t in times.items()))


def explore_browser() -> dict:
    """Slider moves of the explorer in Chromium, from the key to the new top-error table."""
    from .explore_bench import slider_latency

    r = slider_latency()
    if "skipped" in r:
        return dict(time=float("nan"), note=f"not run: {r['skipped']}")
    t, last = np.array(r["times"]) * 1e3, np.median(r["last"]) * 1e3
    server = f"{np.median(r['server_ms']):.0f} ms" if r["server_ms"] else "-"
    return dict(time=r["median"], note=f"median of {t.size} moves (min {t.min():.0f}, max "
                f"{t.max():.0f} ms); server update {server}; plots' data in by {last:.0f} ms")


def measure_identifiability() -> dict:
    """The test x error identifiability table of notebook 06's five-axis machine, ten tests."""
    from ..compendium.notebook import ROOT
    from ..measure import identifiability as ident
    from ..measure import instruments
    from ..measure.motions import motion_model
    from ..papers import your_machine

    p = your_machine.Parameters
    m = your_machine.read_machine(p.topology, *(ROOT / p.param[n].default
                                                for n in ("axis_table", "ranges_file")))
    model = motion_model(m.machine, degree=2)
    prior = model.prior_sd(m.bounds)
    plan = instruments.standard_plan(model, tool=120.0)
    ten = [t for t in plan if t.name.split()[0] in ("laser", "circle")]
    ten += [t for t in plan if t.name.startswith(("rotary ballbar C", "R-test C"))]
    ten = ten[:10]

    def table():
        return ident.identifiability_table([t.design() for t in ten], prior_sd=prior)

    seconds, out = timed(table)
    return dict(time=seconds, note=f"{len(ten)} tests, {sum(t.n_obs for t in ten)} readings, "
                f"{model.n_params} parameters; designs included; plan: "
                f"{(out['plan'] == 'seen').sum()} seen")


class Row(NamedTuple):
    """One row of the table: paper, task, what is measured, size, target, measuring function."""

    paper: str
    task: str
    what: str
    size: str
    target: str
    run: Callable[[], dict]
    published: float | None = None   # the paper's seconds: the note gives the ratio
    peer: str | None = None           # the peer's task: the note gives its ratios to ours
    full: bool = False                # left out by --quick


def _rows():
    """The rows in the table's order, ours before the peer it is compared with."""
    z = "Zheng 2024"
    yield Row("Xu 2022", "xu_split_limit", "one split: selection, MLR, SVR", "1000 x 100 x 500",
              "<= 60 s", xu_split_limit)
    yield Row("Guo 2016", "guo_pose_error", "vertical_xyfz pose error", "1e6 samples", "",
              partial(pose_error, "guo"))
    yield Row("Guo 2016", "guo_spearman", "Spearman, batched", "200 x 500 x 21 x 4", "",
              guo_spearman)
    yield Row(z, "zheng_pose_error", "ac_double_turntable pose error", "1e6 samples",
              ">= 2 M samples/s", partial(pose_error, "zheng"))
    yield Row(z, "zheng_pce_one", "PCE, one component", "n 1e3, degree 3, 13244 terms",
              "<= 0.5 s", partial(zheng_pce, [0]), 7.8761)
    yield Row(z, "zheng_pce_six", "PCE, all six components", "n 1e3, degree 3", "",
              partial(zheng_pce, range(6)), 7.8761)
    yield Row(z, "zheng_mcs", "MCS Sobol (S1, ST), one pose", "N 1e5, 4.3e6 runs",
              "<= 3 s, <= 300 MB", zheng_mcs, 244.0789)
    for n in (2**14, 2**17):    # N >= 2^17: one run each, full mode only
        size, big = f"N 2^{n.bit_length() - 1}, {n * 43:.1e} runs", n >= 2**17
        yield Row(z, f"zheng_sobol_n{n}", "Sobol' (S1, ST), ours", size, "",
                  partial(sobol_task, ours_sobol, "zheng", n, 0 if big else REPEAT),
                  peer=f"zheng_salib_n{n}", full=big)
        yield Row(z, f"zheng_salib_n{n}", "Sobol' (S1, ST), SALib", size, "",
                  partial(sobol_task, salib_sobol, "zheng", n, 0 if big else REPEAT), full=big)
    for n in (2**13, 2**17, 2**20, 2**23):   # SALib to 2^17 (its sample matrix: 14.8 GB at 2^20)
        size, salib = f"N 2^{n.bit_length() - 1}, 43 N runs", n <= 2**17
        yield Row("memory", f"sobol_memory_n{n}", "Sobol streamed, linear 41 x 6", size,
                  "peak flat in N", partial(sobol_task, ours_sobol, "linear", n),
                  peer=f"sobol_memory_salib_n{n}" if salib else None, full=n == 2**23)
        if salib:
            yield Row("memory", f"sobol_memory_salib_n{n}", "SALib, linear 41 x 6", size, "",
                      partial(sobol_task, salib_sobol, "linear", n), full=n >= 2**17)
    yield Row(z, "zheng_linear_pose", "linear closed form, one pose", "41 x 6, Jacobian incl.",
              "<= 1 ms", zheng_linear_pose)
    yield Row(z, "zheng_linear_atlas", "linear closed form, pose atlas", "1e4 poses in travels",
              "<= 10 s", zheng_linear_atlas)
    yield Row("explorer", "explore_update", "slider move: indices + map",
              "3 machines, 25 x 25 grid", "<= 0.1 s", explore_update)
    yield Row("explorer", "explore_browser", "slider move to new numbers, Chromium",
              "AC double turntable, 1280 px", "<= 0.1 s median", explore_browser)
    yield Row("measure", "measure_identifiability", "test x error table, five-axis machine",
              "10 tests, 67 parameters", "<= 1 s", measure_identifiability)
    for name, (n, degrees, ot_degree, _) in PCE_CASES.items():
        for m in ("omp", "lars"):
            yield Row("PCE bench", f"pce_{name}_{m}", f"{name} ({m})",
                      f"n {n}, degree <= {max(degrees)}",
                      "<= 3 s" if (name, m) == ("g_function_41d", "omp") else "",
                      partial(pce_ours, name, m), peer=f"pce_{name}_openturns")
        yield Row("PCE bench", f"pce_{name}_openturns", f"{name} (openturns)",
                  f"n {n}, degree <= {ot_degree}", "", partial(pce_openturns, name))


ROWS = list(_rows())
TASKS = {r.task: r.run for r in ROWS}
