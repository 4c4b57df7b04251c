"""``make bench``: the speed targets named in the issues, measured, with the peers side by side.

Each task of :data:`.bench_tasks.ROWS` runs in a fresh Python process (``python -m
mtaccuracy.apps.bench --task NAME``): its row gives that process's peak RSS and what the task
added above the process with the library (and a peer's package) imported.  Times are wall clock,
the minimum of three runs after a warm-up unless the note says otherwise; targets are shown,
never asserted.  The full mode also times ``make reproduce`` and ``make test``, each run in a
fresh clone of HEAD.  A peer's time and memory over ours stand in our row's note:

* SALib runs the same model, the same Sobol' design (one scrambled sequence from
  ``default_rng(SEED)``) and the same estimators, so the indices agree to rounding (the note
  says to how many digits); it holds its N (D + 2) x D samples, so it runs no N above 2^17.
* OpenTURNS (sparse PCE, the same samples) runs with ``--with-openturns`` in a venv of its own
  under ``build/bench-openturns/``, which sees the project's packages through a ``.pth`` file;
  the project's environment never gets it.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import json
import os
import resource
import shlex
import subprocess
import sys
import sysconfig
import tempfile
from pathlib import Path

import numpy as np

from ..compendium.provenance import ROOT
from .bench_tasks import ROWS, TASKS, rss_mb

#: what ``--with-openturns`` installs from PyPI into :data:`OPENTURNS_ENV`, a venv of its own
OPENTURNS_REQUIREMENT = "openturns==1.27.post1"
OPENTURNS_ENV = ROOT / "build" / "bench-openturns"
PROJECT_PTH = "mtaccuracy-bench-project.pth"   # through which it sees the project's packages
NO_OPENTURNS = ("not run: --with-openturns (BENCH_ARGS=--with-openturns make bench) installs "
                "OpenTURNS into build/bench-openturns/, a venv of its own, and runs these rows")

#: a peer's modules, by a word of its tasks' names: imported before the memory baseline, as ours
PEER_MODULES = {"salib": ("SALib.sample.sobol", "SALib.analyze.sobol"),
                "openturns": ("openturns",)}

#: our task -> the peer's task it is compared with
PEERS = {r.task: r.peer for r in ROWS if r.peer}


def run_task(name: str) -> dict:
    """Run task ``name`` in this process: its result, the peak RSS and the task's own MB."""
    for word, modules in PEER_MODULES.items():
        for module in modules if word in name else ():
            with contextlib.suppress(ImportError):    # the task says so itself
                importlib.import_module(module)
    start = rss_mb()
    out = TASKS[name]()
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return dict(out, peak_mb=peak, task_mb=peak - start)


def _failed(note: str) -> dict:
    """A row without a measurement, with the reason."""
    return dict(time=float("nan"), peak_mb=float("nan"), task_mb=float("nan"), note=note)


def _in_subprocess(name: str, timeout: float | None = None, python: str | None = None) -> dict:
    """Task ``name``'s JSON from a fresh process of ``python`` (default: this one), this library."""
    lib = str(Path(__file__).resolve().parents[2])
    path = os.environ.get("PYTHONPATH", "")
    env = dict(os.environ, PYTHONPATH=lib + (os.pathsep + path if path else ""))
    try:
        res = subprocess.run([python or sys.executable, "-m", "mtaccuracy.apps.bench", "--task",
                              name], capture_output=True, text=True, timeout=timeout, env=env)
    except subprocess.TimeoutExpired:
        return _failed(f"stopped after {timeout:.0f} s (--timeout)")
    if res.returncode != 0:
        return _failed("FAILED: " + (res.stderr.strip().splitlines() or ["?"])[-1])
    return json.loads(res.stdout.strip().splitlines()[-1])


def ensure_openturns_env(env: Path = OPENTURNS_ENV, *, run=subprocess.run) -> Path:
    """The Python of the OpenTURNS environment ``env``, made the first time (``run`` runs commands).

    Made as: a venv by this Python (same version; not ``--system-site-packages``, the base
    interpreter's), a ``.pth`` file adding this environment's site folders (and so their ``.pth``
    files: the editable install), then the new Python's pip installs OpenTURNS there alone."""
    python = env / "bin" / "python"
    if python.exists() and run([str(python), "-c", "import openturns"],
                               capture_output=True).returncode == 0:
        return python
    run([sys.executable, "-m", "venv", str(env)], check=True)
    site = env / "lib" / f"python{sys.version_info[0]}.{sys.version_info[1]}" / "site-packages"
    dirs = dict.fromkeys(sysconfig.get_paths()[k] for k in ("purelib", "platlib"))
    (site / PROJECT_PTH).write_text(
        "".join(f"import site; site.addsitedir({d!r})\n" for d in dirs), encoding="utf-8")
    run([str(python), "-m", "pip", "install", "--quiet", "--disable-pip-version-check",
         OPENTURNS_REQUIREMENT], check=True)
    return python


def _peer_note(ours: dict, peer: dict, name: str) -> str:
    """``; SALib 20x the time, ...``: the peer's time and memory over ours, indices' agreement."""
    if not (peer.get("time", np.nan) > 0 and ours.get("time", np.nan) > 0):
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


# a process of its own, whose children are make's alone: its RUSAGE_CHILDREN is theirs
_MEASURE = """
import resource, subprocess, sys, time
t0 = time.perf_counter()
rc = subprocess.run(sys.argv[1:], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL).returncode
print(time.perf_counter() - t0, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss, rc)
"""


def make_in_clone(target: str, run=subprocess.run) -> tuple[float, float, int]:
    """``make target`` in a fresh clone of HEAD sharing this checkout's .venv: (s, peak MB, status).

    A clone per run, since in one clone a second ``make reproduce`` (Snakemake) has nothing to
    do.  The venv's stamp is passed as ``make -o``: the clone's environment.txt is newer than
    it, and make must not reinstall the shared .venv (nor point its editable install there)."""
    with tempfile.TemporaryDirectory(prefix="mtaccuracy-bench-") as tmp:
        run(["git", "clone", "-q", str(ROOT), tmp], check=True)
        (Path(tmp) / ".venv").symlink_to(ROOT / ".venv")
        stamp = run("cat environment.txt pyproject.toml | cksum", shell=True, cwd=tmp,
                    check=True, capture_output=True, text=True).stdout.split()[0]
        res = run([sys.executable, "-c", _MEASURE, "make", "-C", tmp, "-o",
                   f".venv/.installed-{stamp}", target], capture_output=True, text=True)
    seconds, rss, status = res.stdout.split()
    return float(seconds), int(rss) / 1024, int(status)


def _command_rows(repeat: int = 2):
    """Issue 11's ``make reproduce`` <= 90 s and ``make test`` <= 150 s, min of ``repeat`` runs."""
    for target, goal in (("reproduce", "<= 90 s"), ("test", "<= 150 s")):
        runs = [make_in_clone(target) for _ in range(repeat)]
        yield (f"make {target} (fresh clone)", f"min of {repeat}", goal,
               dict(time=min(r[0] for r in runs), peak_mb=max(r[1] for r in runs),
                    task_mb=np.nan, note="" if all(r[2] == 0 for r in runs) else "A RUN FAILED"))


def main(argv=None) -> int:
    """Print the table of the chosen rows (each task in a process of its own) or one task's JSON."""
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
    runs = {r.task for r in ROWS if not (args.quick and r.full)}
    chosen = {t for t in runs if args.only in t}
    chosen = runs & (chosen | {p for t, p in PEERS.items() if t in chosen}
                     | {t for t, p in PEERS.items() if p in chosen})
    ot_python, ot_note = None, NO_OPENTURNS
    if args.with_openturns and any(t.endswith("openturns") for t in chosen):
        print(f"OpenTURNS environment: {OPENTURNS_ENV} ({OPENTURNS_REQUIREMENT}; made once)",
              flush=True)
        try:
            ot_python = str(ensure_openturns_env())
        except (OSError, subprocess.CalledProcessError) as exc:
            ot_note = f"FAILED to make the OpenTURNS environment: {exc}"
    head = (f"{'paper':<10} {'what':<34} {'size':<30} {'min time':>9}  {'target':<18} "
            f"{'peak MB':>8} {'task MB':>8} {'err S1':>8} {'err ST':>8}  note")
    print(head + "\n" + "-" * len(head), flush=True)

    def show(paper, what, size, target, r, published=None):
        errs = " ".join(f"{r[k]:>8.1e}" if k in r else f"{'':>8}" for k in ("err_s1", "err_st"))
        note = r.get("note", "") + r.get("rank", "")
        if published:
            note += f"; paper {published:.2f} s (ratio {r['time'] / published:.3f})"
        print(f"{paper:<10} {what:<34} {size:<30} {r['time']:>8.3f}s  {target:<18} "
              f"{r['peak_mb']:>8.0f} {r['task_mb']:>8.0f} {errs}  {note}", flush=True)

    results: dict = {}

    def result(task):
        if task not in results:
            if not task.endswith("openturns"):
                results[task] = _in_subprocess(task)
            else:
                results[task] = (_failed(ot_note) if ot_python is None
                                 else _in_subprocess(task, args.timeout, python=ot_python))
        return results[task]

    for row in ROWS:
        if row.task in chosen:
            r = dict(result(row.task))
            if row.peer in chosen:
                r["note"] = r.get("note", "") + _peer_note(
                    r, result(row.peer), "OpenTURNS" if row.peer.endswith("openturns") else "SALib")
            show(row.paper, row.what, row.size, row.target, r, row.published)
    if not args.quick and not args.only:
        for what, size, target, r in _command_rows():
            show("all", what, size, target, r)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
