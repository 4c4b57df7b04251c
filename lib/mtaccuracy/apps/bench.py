"""``make bench``: the speed targets named in the issues, measured, with the peers side by side.

Every task runs in a fresh Python process of its own (``python -m mtaccuracy.apps.bench --task
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
from pathlib import Path

import numpy as np

from ..compendium.provenance import ROOT
from .bench_tasks import (
    FULL_ONLY,
    PCE_CASES,
    PEERS,
    SALIB_MEMORY_N,
    SOBOL_MEMORY_N,
    TASK_IMPORTS,
    TASKS,
    ZHENG_SOBOL_N,
    _power,
    _rss_mb,
)


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
        res = subprocess.run([python or sys.executable, "-m", "mtaccuracy.apps.bench",
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
    return ROOT / "build" / "bench-openturns"


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


    with tempfile.TemporaryDirectory(prefix="mtaccuracy-bench-") as tmp:
        clone = Path(tmp) / "clone"
        subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True)
        (clone / ".venv").symlink_to(ROOT / ".venv")
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

    ap = argparse.ArgumentParser(prog="python -m mtaccuracy.apps.bench")
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
