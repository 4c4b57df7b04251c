"""``make bench``: the speed targets named in the issues, measured.

Every task runs in a fresh Python process of its own (``python -m mtaccuracy.compendium.bench --task
NAME``), so its memory is that task's alone: the row gives the process's peak RSS and, of it,
what the task added above the RSS the process had when the task started (imports and inputs).
Times are the minimum of ``repeat`` runs (3 unless a row says otherwise) after one warm-up run
(caches of multi-indices and polynomial families filled), wall clock.  Targets are shown here,
never asserted in timed tests.  ``make reproduce`` and ``make test`` are timed in a fresh clone
(min of two; skipped with ``--quick``).

The sparse-PCE benchmarks (issue 13) run the same cases, on the same samples, through our
``fit_sparse_pce`` (OMP and LARS, basis and length validated) and through OpenTURNS
(``FunctionalChaosAlgorithm``, LARS with corrected LOO, the Legendre basis at a fixed degree),
an optional dependency of the bench only: without it those rows say so and the rest runs.  Each
prints the time and the largest error of S1 and ST against the exact indices.

Local imports: each task imports what it measures inside its function, so that its time and
memory are its own (a task runs in a process of its own).
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
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


#: base rows N of the memory-against-N rows (the last only without --quick)
SOBOL_MEMORY_N = {"1e4": 10_000, "1e5": 100_000, "1e6": 1_000_000, "1e7": 10_000_000}


def _sobol_memory(n: int) -> dict:
    """Sobol indices (S1, ST) of the Zheng machine's first-order model at one pose (41 errors,
    six outputs: ``e @ J.T``, runs cost little, so the memory is the estimator's), streamed
    from a Monte Carlo design of ``n`` base rows (``SobolDesign``): one run, sampling
    included.  The peak should not grow with n once n exceeds ``sensitivity.BASE_ROWS``."""
    from .. import sensitivity as S

    m, sd, pose = _zheng()
    jac = m.jacobian(pose).reshape(6, 41)
    design = S.SobolDesign(n, S.Inputs.normal(0.0, sd), method="mc", seed=2)
    t0 = time.perf_counter()
    s1, st = S.sobol_indices(lambda e: e @ jac.T, design, chunk=250_000)
    t = time.perf_counter() - t0
    exact = S.linear_indices(jac, sd=sd)             # (41, 6), exact for a linear model: S1 = ST
    return dict(time=t, err_s1=float(np.abs(s1 - exact).max()),
                err_st=float(np.abs(st - exact).max()),
                note=f"one run; {n * 43 / t / 1e6:.1f} M runs/s")


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
        return dict(time=float("nan"), note="OpenTURNS not installed (pip install openturns): "
                                            "skipped")
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
    else:  # one run (a minute): no warm-up
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
    **dict(_pce_tasks()),
    **{f"sobol_memory_{k}": (lambda n=n: _sobol_memory(n)) for k, n in SOBOL_MEMORY_N.items()},
}

#: rows left out by --quick (a few minutes)
FULL_ONLY = {"sobol_memory_1e7"}

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
    *[("memory", f"sobol_memory_{k}", "Sobol streamed, linear 41 x 6", f"N {k}, 43 N runs",
       "peak flat in N", None) for k in SOBOL_MEMORY_N],
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
    scipy, pandas, scikit-learn, chaospy: about 120 MB, the same for every task), MB."""
    from .. import machines, sensitivity  # noqa: F401

    start = _rss_mb()
    out = TASKS[name]()
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return dict(out, peak_mb=peak, task_mb=peak - start)


def _in_subprocess(name: str, timeout: float | None = None) -> dict:
    try:
        res = subprocess.run([sys.executable, "-m", "mtaccuracy.compendium.bench", "--task", name],
                             capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return dict(time=float("nan"), peak_mb=float("nan"), task_mb=float("nan"),
                    note=f"stopped after {timeout:.0f} s (--timeout)")
    if res.returncode != 0:
        return dict(time=float("nan"), peak_mb=float("nan"), task_mb=float("nan"),
                    note="FAILED: " + (res.stderr.strip().splitlines() or ["?"])[-1])
    return json.loads(res.stdout.strip().splitlines()[-1])


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
    import argparse
    import shlex

    ap = argparse.ArgumentParser(prog="python -m mtaccuracy.compendium.bench")
    ap.add_argument("--quick", action="store_true",
                    help="skip timing make reproduce and make test, and the N = 1e7 "
                         "memory row (a few minutes)")
    ap.add_argument("--from-env", action="store_true",
                    help="also read arguments from $BENCH_ARGS (as make bench passes them)")
    ap.add_argument("--task", choices=sorted(TASKS), help="run one task here, print JSON")
    ap.add_argument("--only", default="", help="run only the rows whose task contains this")
    ap.add_argument("--timeout", type=float, default=600.0,
                    help="stop an OpenTURNS task after this many seconds (default 600)")
    args = ap.parse_args(argv)
    if args.from_env:
        args = ap.parse_args([*(argv or []), *shlex.split(os.environ.get("BENCH_ARGS", ""))])
    if args.task:
        print(json.dumps(run_task(args.task)))
        return 0
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

    for paper, task, what, size, target, published in ROWS:
        if args.only in task and not (args.quick and task in FULL_ONLY):
            limit = args.timeout if task.endswith("openturns") else None
            show(paper, what, size, target, _in_subprocess(task, limit), published)
    if not args.quick and not args.only:
        for what, size, target, r in _command_rows():
            show("all", what, size, target, r)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
