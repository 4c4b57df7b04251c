"""``make bench``: the speed targets named in the issues, measured (median of repeats; the two
commands, ``make reproduce`` and ``make test``, min of two runs in a fresh clone, skipped with
``--quick``).

Targets are shown here, never asserted in timed tests.  Each row: what is timed, its size, the
wall-clock time, the target where an issue names one, and the paper's published time with our
ratio to it where there is one.
"""

from __future__ import annotations

import resource
import statistics
import time

import numpy as np

from . import errors, sensitivity
from .machines import build


def _median(fn, repeat: int = 3) -> float:
    fn()  # warm-up
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def _guo_rows():
    m = build("vertical_xyfz")
    b = errors.uniform_bounds(m.catalogue, {"positioning": (0, 3), "straightness": (0, 4),
                                            "angular": (0, 3.2e-5), "squareness": (0, 1.9)})
    x = sensitivity.latin_hypercube(1_000_000, b, 0)
    pose = dict(x=100.0, y=100.0, z=100.0)
    t = _median(lambda: m.pose_error(x, pose))
    yield ("Guo 2016", "vertical_xyfz pose error", "1e6 samples", t, "",
           f"{1e6 / t / 1e6:.2f} M samples/s", None)
    d = sensitivity.repeated_latin_hypercube(500, b, 200, 2)
    y = sensitivity.position_outputs(m.pose_error(d.reshape(-1, 21), pose)).reshape(200, 500, 4)
    t = _median(lambda: sensitivity.spearman(d, y))
    yield "Guo 2016", "Spearman, batched", "200 x 500 x 21 x 4", t, "", "", None


def _zheng_rows():
    m = build("ac_double_turntable")
    sd = np.array([e.to_library * (15.0 if e.translational else 10.0) / 3 for e in m.catalogue])
    pose = dict(x=106.1, y=-58.6, z=-255.3, A=np.deg2rad(60.7), C=np.deg2rad(56.7))
    x = np.random.default_rng(0).standard_normal((1_000_000, 41)) * sd
    t = _median(lambda: m.pose_error(x, pose))
    yield ("Zheng 2024", "ac_double_turntable pose error", "1e6 samples", t,
           ">= 1 M samples/s", f"{1e6 / t / 1e6:.2f} M samples/s", None)

    def pce(components):
        u = sensitivity.base_samples(1000, 41, "lhs", 1)[0]
        xi = sensitivity.from_unit_normal(u, np.ones(41))
        yv = m.pose_error(xi * sd, pose)
        alphas = sensitivity.multi_indices(41, 3)
        psi = sensitivity.design_matrix(xi, alphas)
        return [sensitivity.pce_sobol(sensitivity.fit_pce(xi, yv[:, k], psi=psi, alphas=alphas))
                for k in components]
    t = _median(lambda: pce([0]))
    yield ("Zheng 2024", "PCE pipeline, one component", "1e3 samples, 13244-term basis, OMP",
           t, "<= 1.5 s", "", 7.8761)
    t = _median(lambda: pce(range(6)), 1)
    yield ("Zheng 2024", "PCE pipeline, all six components", "1e3 samples, degree 3", t, "", "",
           7.8761)

    def mcs():
        ua, ub = sensitivity.base_samples(100_000, 41, "mc", 2)
        a, b = sensitivity.from_unit_normal(ua, sd), sensitivity.from_unit_normal(ub, sd)
        return sensitivity.sobol_indices(lambda z: m.pose_error(z, pose), a, b, chunk=250_000)
    t = _median(mcs, 1)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    yield ("Zheng 2024", "MCS Sobol (S1, ST), one pose", "N = 1e5, 4.3e6 runs", t, "<= 5 s",
           f"chunked; bench process peak RSS {peak / 1024:.0f} MB", 244.0789)


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
    import os
    import subprocess
    import sys
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
            yield ("all", f"make {target} (fresh clone)", f"min of {repeat}", best[0], goal,
                   f"peak RSS of its largest process {max(r[1] for r in runs) / 1024:.0f} MB"
                   + ("" if all(r[2] == 0 for r in runs) else "; A RUN FAILED"), None)


def rows(commands: bool = True):
    yield from _guo_rows()
    yield from _zheng_rows()
    if commands:
        yield from _command_rows()


def main(argv=None) -> int:
    import argparse

    ap = argparse.ArgumentParser(prog="python -m mtaccuracy.bench")
    ap.add_argument("--quick", action="store_true",
                    help="skip timing make reproduce and make test (a few minutes)")
    ap.add_argument("--from-env", action="store_true",
                    help="also read arguments from $BENCH_ARGS (as make bench passes them)")
    args = ap.parse_args(argv)
    if args.from_env:
        import os
        import shlex

        args = ap.parse_args([*(argv or []), *shlex.split(os.environ.get("BENCH_ARGS", ""))])
    head = f"{'paper':<11} {'what':<34} {'size':<36} {'median':>9}  {'target':<17} " \
           f"{'published':>9} {'ratio':>7}  note"
    print(head)
    print("-" * len(head))
    for paper, what, size, t, target, note, published in rows(commands=not args.quick):
        pub = f"{published:>8.2f}s" if published else f"{'':>9}"
        ratio = f"{t / published:>7.3f}" if published else f"{'':>7}"
        print(f"{paper:<11} {what:<34} {size:<36} {t:>8.2f}s  {target:<17} {pub} {ratio}  {note}",
              flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
