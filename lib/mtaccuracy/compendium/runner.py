"""Run notebooks with papermill after validating their parameters.

papermill only warns about a parameter the notebook does not declare; this runner refuses it,
and refuses a value of the wrong type or outside the declared constraints, naming the
parameter and the allowed ones, before any kernel starts.

The parameters a notebook declares, their constraints and the checks are the parameter
language of :mod:`mtaccuracy.compendium.parameters` (the notebooks import it, not this
module); the runner applies the same checks (:func:`validate`) before any kernel starts.

All or nothing: a run executes the notebook into ``notebooks/.running/`` and writes its
figures and tables into a staging folder (``<output>/.staging-<pid>/``); only when every cell
succeeded are the notebook and the output folder switched to the new run, by the journalled
commit of :mod:`mtaccuracy.compendium.commit`, so that a notebook and its ``figures/<stem>/``
(``reproduction.csv``, figures, ``provenance.json``) always come from one run, even after a
kill at any step.  A commit replaces only the files the previous run wrote (the folder's
manifest): what a user put in an output folder is left alone and named.  A run with
``output_dir`` elsewhere leaves ``notebooks/`` and ``figures/`` untouched: the executed
notebook is stored with its outputs, as ``<output_dir>/<stem>.ipynb``.  A failed
or interrupted run (Ctrl-C, SIGTERM) leaves the committed notebook and figures byte-identical
and is kept in ``notebooks/.failed/`` (the executed notebook and a ``<stem>.figures/`` folder
with what it had written); it ends with one line saying so.

Cells tagged ``measured`` print measurements of the machine (wall-clock times): their outputs
are not stored (a one-line note replaces them), so re-running an unchanged notebook leaves it
byte-identical.

Command line (``make reproduce NB=03 PARAMS="n_samples=1000 seed=2"`` calls this, passing
``NB`` and ``PARAMS`` through the environment, never through a shell)::

    python -m mtaccuracy.compendium.runner all|03|notebooks/03_....ipynb [name=value ...] [--check]
                                [--list] [--jobs N] [--copy-to DIR]

Several notebooks with one ``output_dir=X`` write one folder each, ``X/<stem>``; ``--copy-to``
takes a folder outside the repository and goes through the same checks, staging and commit.

``all`` runs the notebooks two at a time on a machine with two cores or more (each kernel with
one BLAS thread, so that they do not compete), the longest first.

Local imports: papermill and nbformat (slow to import) are imported when a notebook runs,
so that ``--check``, ``--list`` and Ctrl-C answer at once.
"""

from __future__ import annotations

import argparse
import contextlib
import copy
import json
import os
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from . import commit, paths
from .parameters import (  # noqa: F401 (re-exported: the runner's users find them here too)
    Parameter,
    ParameterError,
    all_notebooks,
    check_parameters,
    memory_estimate,
    notebook_path,
    parse_value,
    read_parameters,
    validate,
)
from .provenance import git_commit


class Interrupted(Exception):
    """The run was stopped by SIGINT (Ctrl-C) or SIGTERM."""


# --- running -----------------------------------------------------------------------------

MEASURED_NOTE = ("[output of a cell tagged 'measured' (wall-clock times of the machine that ran "
                 "it): not stored, so that re-running an unchanged notebook leaves it unchanged; "
                 "the values are in the output files declared measured]\n")


def _strip_injected(nb: dict) -> dict:
    nb = copy.deepcopy(nb)
    nb["cells"] = [c for c in nb["cells"]
                   if "injected-parameters" not in c.get("metadata", {}).get("tags", [])]
    return nb


def _normalise(nb: dict, rel: str) -> dict:
    """Remove what makes two identical runs differ (timestamps, durations, temp paths, the
    outputs of cells tagged ``measured``)."""
    meta = nb.get("metadata", {}).get("papermill", {})
    for k in ("start_time", "end_time", "duration", "environment_variables", "exception"):
        meta.pop(k, None)
    if meta:
        meta["input_path"] = meta["output_path"] = rel
    for c in nb.get("cells", []):
        md = c.get("metadata", {})
        md.pop("papermill", None)
        md.pop("execution", None)
        if c.get("cell_type") != "code":
            continue
        if "measured" in md.get("tags", []):
            c["outputs"] = [{"name": "stdout", "output_type": "stream", "text": [MEASURED_NOTE]}]
        c["outputs"] = _merge_streams(c.get("outputs", []))
    return nb


def _merge_streams(outputs: list) -> list:
    """Consecutive stream outputs of one stream as one: the kernel splits a cell's printing
    into pieces depending on timing, which is not part of the result."""
    merged: list = []
    for o in outputs:
        prev = merged[-1] if merged else None
        if (o.get("output_type") == "stream" and prev is not None
                and prev.get("output_type") == "stream" and prev.get("name") == o.get("name")):
            text = "".join(prev["text"]) + "".join(o["text"])
            prev["text"] = text.splitlines(keepends=True)
        else:
            if o.get("output_type") == "stream":
                o = dict(o, text="".join(o["text"]).splitlines(keepends=True))
            merged.append(o)
    return merged


def _parameterised(path: Path, params: dict) -> dict:
    """The notebook with papermill's injected-parameters cell (built here, so that papermill
    does not guess at the parameters cell and warn about what this runner already checked)."""
    import nbformat
    from papermill.parameterize import parameterize_notebook

    nb = nbformat.reads(json.dumps(_strip_injected(json.loads(path.read_text("utf-8")))),
                        as_version=4)
    nb.metadata.setdefault("papermill", {})
    for c in nb.cells:  # papermill's own loader does this too
        c.metadata.setdefault("tags", [])
    if params:
        nb = parameterize_notebook(nb, params, kernel_name="python3", language="python")
    return nb


_rel = paths.relative


#: The signals :func:`_on_signal` received during the current run (a library may wrap the
#: :class:`Interrupted` it raised in an error of its own, nbformat's ``VisitError`` say).
_RECEIVED: list[int] = []


def _on_signal(signum, frame):
    _RECEIVED.append(signum)
    raise Interrupted(signal.Signals(signum).name)


def _install(handler) -> dict:
    old = {}
    for sig in (signal.SIGINT, signal.SIGTERM):
        try:
            old[sig] = signal.signal(sig, handler)
        except ValueError:  # not the main thread: leave signals alone
            pass
    return old


@contextlib.contextmanager
def _deferred_signals():
    """SIGINT and SIGTERM held back while a commit switches the files (a few renames); yields
    the list of the signals that arrived meanwhile."""
    got: list[int] = []
    old = _install(lambda signum, frame: got.append(signum))
    try:
        yield got
    finally:
        for sig, h in old.items():
            signal.signal(sig, h)


def _unwritable(exc: OSError, what: Path) -> ParameterError:
    return ParameterError(f"cannot write in {_rel(what)} ({exc.strerror or exc}); nothing was "
                          f"run or changed: a run needs a checkout it can write (its notebooks/ "
                          f"and the output folder)")


@contextlib.contextmanager
def _setenv(name: str, value: str | None):
    """``os.environ[name] = value`` while the block runs (nothing when ``value`` is None)."""
    if value is None:
        yield
        return
    old = os.environ.get(name)
    os.environ[name] = value
    try:
        yield
    finally:
        if old is None:
            os.environ.pop(name, None)
        else:
            os.environ[name] = old


def _output_base(base: Path | None):
    """Relative output folders taken from ``base`` (``--copy-to``) while the block runs."""
    return _setenv(paths.OUTPUT_BASE_ENV, None if base is None else str(base))


def run(notebook: str | Path, overrides: dict | None = None, progress: bool = True,
        share: int = 1, copy_to: str | Path | None = None) -> float:
    """Validate, execute with papermill and, only if every cell succeeds, commit the notebook.

    The commit takes the executed notebook and its outputs
    (:func:`mtaccuracy.compendium.commit.commit`); returns seconds.

    ``copy_to``: store the executed notebook as ``<copy_to>/<stem>.ipynb`` and take relative
    output folders from ``copy_to`` (``<copy_to>/figures/<stem>/`` by default), touching
    nothing in the repository; the folder must lie outside it.  The same checks, staging and
    commit as a run in place.

    Raises :class:`RuntimeError` (failed), :class:`Interrupted` (SIGINT/SIGTERM) or
    :class:`ParameterError` (refused before it ran), each with a one-line message; the committed
    notebook and output folder are then unchanged and the partial run is kept in
    ``notebooks/.failed/``."""
    path = notebook_path(notebook)
    base = paths.check_copy_dir(copy_to) if copy_to is not None else None
    with _output_base(base):
        params = validate(path, overrides or {}, share)
        target = output_target(path, params)
        dest = written_notebook(path, params, copy_to=base)
        for folder in {dest.parent, *([target] if target is not None else [])}:
            commit.remove_stale(folder)  # what a killed run of this folder left
        for folder in [target] if target is not None else []:
            changed = commit.modified_outputs(folder, path.stem)
            if changed:
                raise ParameterError(
                    f"{path.stem}: {', '.join(changed)} in {_rel(folder)} changed since the "
                    f"compendium wrote it; the run would overwrite it: move it away first")
        if base is not None and dest.exists() and not commit.written_notebook_is_ours(
                dest, path.name):
            raise ParameterError(f"{path.stem}: {dest} exists and is not a notebook the "
                                 f"compendium stored; nothing there is overwritten")
        running, failed = paths.NOTEBOOKS / ".running", paths.NOTEBOOKS / ".failed"
        for d in (running, failed):
            try:
                d.mkdir(exist_ok=True)
                with tempfile.TemporaryFile(dir=d):  # it may exist and still refuse a file
                    pass
            except OSError as exc:
                raise _unwritable(exc, d) from None
        staging = None
        created = False
        if target is not None:
            try:
                created = not target.exists()
                target.mkdir(parents=True, exist_ok=True)
                staging = target / f"{commit.STAGING_PREFIX}{os.getpid()}"
                shutil.rmtree(staging, ignore_errors=True)
                staging.mkdir()
            except OSError as exc:
                raise _unwritable(exc, target) from None
        old_handlers = _install(_on_signal)
        try:
            with _setenv(paths.STAGING_ENV, None if staging is None else str(staging)):
                # one file per process: two runs of one notebook at once (the tests run 03
                # three times in parallel) must not write papermill's output into one file
                out = running / f"{path.stem}.{os.getpid()}.ipynb"
                seconds = _execute_and_commit(path, params, out, staging,
                                              target, dest, failed, progress)
        except BaseException:
            if created and target is not None and target.is_dir() and not any(
                    target.iterdir()):
                target.rmdir()  # a folder this run made, left empty
            raise
        finally:
            for sig, h in old_handlers.items():
                signal.signal(sig, h)
    if _in_place(path, target):
        _record_run(path.stem, seconds)
    return seconds


def _in_place(path: Path, target: Path | None) -> bool:
    """Whether a run replaces the committed notebook: it does when it writes into the
    notebook's own ``figures/<stem>/`` (or declares no output folder); a run into another
    folder stores the executed notebook there, as ``<output_dir>/<stem>.ipynb``."""
    return target is None or target == paths.FIGURES / path.stem


def written_notebook(notebook: str | Path, params: dict, copy_to: Path | None = None) -> Path:
    """Where a run with ``params`` stores the executed notebook.

    ``copy_to``: the folder of ``--copy-to``, where it always goes."""
    path = notebook_path(notebook)
    if copy_to is not None:
        return Path(copy_to) / path.name
    target = output_target(path, params)
    return path if _in_place(path, target) else target / path.name


def output_target(notebook: str | Path, params: dict) -> Path | None:
    """The folder a run with ``params`` writes into (its ``output_dir``, resolved)."""
    declared = read_parameters(notebook).get("output_dir")
    if declared is None:
        return None
    return paths.resolve_output(params.get("output_dir", declared.default))


@contextlib.contextmanager
def _kernel_stderr(log: Path):
    """Send what the kernel writes to its standard error (ipykernel's start-up warnings, the
    tracebacks of a kernel shut down in the middle of a cell) to ``log`` instead of the
    terminal, which keeps this process's own messages and progress bar."""
    sys.stderr.flush()
    saved = os.dup(2)
    old = sys.stderr
    with open(log, "ab") as fh:
        os.dup2(fh.fileno(), 2)  # inherited by the kernel started inside
    sys.stderr = os.fdopen(os.dup(saved), "w", buffering=1)
    try:
        yield
    finally:
        sys.stderr.flush()
        sys.stderr.close()
        sys.stderr = old
        os.dup2(saved, 2)
        os.close(saved)


def _keep_failed(path: Path, out: Path, log: Path, staging: Path | None, failed: Path) -> str:
    """Move what a failed run left into ``notebooks/.failed/``; say what was kept."""
    kept = []
    if out.exists():
        shutil.move(str(out), failed / path.name)
        kept.append(path.name)
    if log.exists():
        shutil.move(str(log), failed / f"{path.stem}.kernel.log")
    if staging is not None and staging.is_dir() and not any(staging.iterdir()):
        staging.rmdir()
    if staging is not None and staging.exists():
        dest = failed / f"{path.stem}.figures"
        shutil.rmtree(dest, ignore_errors=True)
        shutil.move(str(staging), dest)
        kept.append(dest.name)
    return f"partial run kept in {_rel(failed)}/" if kept else "nothing of it was kept"


def _execute_and_commit(path, params, out, staging, target, dest, failed, progress) -> float:
    t0 = time.perf_counter()
    log = out.with_suffix(".kernel.log")  # <stem>.<pid>.kernel.log
    for stale in (out, log):
        stale.unlink(missing_ok=True)
    source = path.read_bytes()
    tmp = None
    _RECEIVED.clear()
    try:
        import papermill as pm

        with _kernel_stderr(log):
            pm.execute_notebook(_parameterised(path, params), str(out),
                                cwd=str(paths.NOTEBOOKS), kernel_name="python3",
                                progress_bar=progress, log_output=False)
        seconds = time.perf_counter() - t0
        nb = _normalise(json.loads(out.read_text(encoding="utf-8")), _rel(path))
        text = json.dumps(nb, indent=1, ensure_ascii=False) + "\n"
        if dest == path and path.read_bytes() != source:
            raise commit.CommitConflict(f"{_rel(path)} was changed while it ran; nothing was "
                                        f"changed: run it again")
        if staging is not None and dest.parent == target:
            (staging / dest.name).write_text(text, encoding="utf-8")
            notebook = None
        else:
            tmp = dest.with_name(f".{dest.name}.commit-{os.getpid()}.tmp")
            tmp.write_text(text, encoding="utf-8")
            notebook = (tmp, dest)
        with _deferred_signals() as late:
            if staging is not None and any(staging.iterdir()):
                done = commit.commit(staging, target, stem=path.stem, notebook=notebook)
            else:  # a notebook that wrote nothing leaves its folder as it is
                if staging is not None:
                    staging.rmdir()
                done = commit.Result()
                if notebook is not None:
                    os.replace(tmp, dest)
    except BaseException as exc:
        _install(signal.SIG_IGN)  # a second Ctrl-C must not interrupt the clean-up
        if tmp is not None:
            tmp.unlink(missing_ok=True)
        where = _keep_failed(path, out, log, staging, failed)
        unchanged = f"{_rel(path)}{f' and {_rel(target)}' if target else ''} unchanged"
        if isinstance(exc, Interrupted | KeyboardInterrupt) or _RECEIVED:
            name = signal.Signals(_RECEIVED[0]).name if _RECEIVED else "SIGINT"
            raise Interrupted(f"{path.stem} interrupted ({name}): {unchanged}; "
                              f"{where}") from None
        if isinstance(exc, commit.CommitConflict):
            raise RuntimeError(f"{path.stem} not committed: {exc}; {where}") from None
        msg = getattr(exc, "evalue", None) or (str(exc).strip().splitlines() or [""])[-1]
        cell = getattr(exc, "exec_count", None)
        raise RuntimeError(
            f"{path.stem} failed{f' in cell [{cell}]' if cell else ''}: "
            f"{getattr(exc, 'ename', type(exc).__name__)}: {msg}\n  {unchanged}; {where}"
        ) from None
    out.unlink(missing_ok=True)
    log.unlink(missing_ok=True)
    if done.left_alone:
        print(f"left alone in {_rel(target)}/ (not written by the compendium, or changed "
              f"since): {', '.join(done.left_alone)}", file=sys.stderr, flush=True)
    if late:
        raise Interrupted(f"{path.stem}: {signal.Signals(late[0]).name} arrived while the "
                          f"finished run was being committed; the commit was completed: "
                          f"{_rel(dest)} and {_rel(target) if target else ''} are the new run")
    return seconds


RUNS = ".runs.json"


def _record_run(stem: str, seconds: float) -> None:
    """Keep each notebook's last run time and the commit it ran on, in
    ``figures/.runs.json``: not committed (a measurement of this machine), and the only place
    the commit is kept: figures carry content hashes (:mod:`mtaccuracy.compendium.provenance`)."""
    rt = paths.FIGURES / RUNS
    try:
        data = json.loads(rt.read_text(encoding="utf-8")) if rt.exists() else {}
    except ValueError:
        data = {}
    data[stem] = {"seconds": round(seconds, 1), "commit": git_commit()}
    rt.parent.mkdir(parents=True, exist_ok=True)
    tmp = rt.with_name(f"{RUNS}.{os.getpid()}.tmp")
    tmp.write_text(json.dumps(dict(sorted(data.items())), indent=1) + "\n", encoding="utf-8")
    os.replace(tmp, rt)


def last_runs() -> dict:
    """``{stem: {"seconds": s, "commit": c}}`` of the runs recorded on this machine."""
    rt = paths.FIGURES / RUNS
    try:
        return json.loads(rt.read_text(encoding="utf-8")) if rt.exists() else {}
    except ValueError:
        return {}


# --- command line ---------------------------------------------------------------------------

def _child_env() -> dict:
    env = dict(os.environ)
    for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        env[k] = "1"
    return env


def _run_parallel(plan: list[tuple[Path, list[str], dict]], jobs: int,
                  copy_to: Path | None = None) -> int:
    """Run each notebook in its own ``python -m mtaccuracy.compendium.runner`` process,
    ``jobs`` at a time, the longest (by the last recorded run) first; ``plan`` holds each
    notebook with its command-line parameters and their parsed values.  Returns the number
    that failed."""
    known = last_runs()
    order = sorted(plan, key=lambda p: -float(known.get(p[0].stem, {}).get("seconds", 0)))
    pending, active, failures = list(order), {}, 0
    n, t0 = len(order), time.perf_counter()
    old_handlers = _install(_on_signal)  # even where the shell started us with SIGINT ignored
    try:
        while pending or active:
            while pending and len(active) < jobs:
                t, items, overrides = pending.pop(0)
                cmd = [sys.executable, "-m", "mtaccuracy.compendium.runner", str(t), *items,
                       "--quiet", f"--share={jobs}"]
                if copy_to is not None:
                    cmd.append(f"--copy-to={copy_to}")
                active[t] = (subprocess.Popen(cmd, env=_child_env()), overrides)
                print(f"[{n - len(pending)}/{n}] started "
                      f"{t.stem}", flush=True)
            time.sleep(0.2)
            for t, (proc, _overrides) in list(active.items()):
                if proc.poll() is not None:
                    del active[t]
                    failures += proc.returncode != 0
                    if proc.returncode == 130:  # interrupted: stop the others too
                        raise Interrupted("")
    except (KeyboardInterrupt, Interrupted):
        _install(signal.SIG_IGN)
        procs = [p for p, _ in active.values()]
        deadline = time.perf_counter() + 1.0  # a Ctrl-C reached the children too
        while any(p.poll() is None for p in procs) and time.perf_counter() < deadline:
            time.sleep(0.05)
        for proc in procs:  # each child ends its own run and says so
            if proc.poll() is None:
                with contextlib.suppress(OSError):
                    proc.send_signal(signal.SIGINT)
        for proc in procs:
            proc.wait()
        raise Interrupted("") from None
    finally:
        for sig, h in old_handlers.items():
            signal.signal(sig, h)
    print(f"{n} notebook(s) in {time.perf_counter() - t0:.1f} s of wall-clock time"
          f"{f', {failures} failed' if failures else ''}", flush=True)
    return failures


def _arguments(argv) -> list[str]:
    """The command line, or ``NB`` and ``PARAMS`` from the environment (``--from-env``, as the
    Makefile passes them: split like a shell would, never evaluated by one)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if "--from-env" in argv:
        argv.remove("--from-env")
        try:
            extra = shlex.split(os.environ.get("PARAMS", ""))
        except ValueError as exc:
            raise ParameterError(f"PARAMS={os.environ.get('PARAMS', '')!r}: {exc}") from None
        argv = [os.environ.get("NB", "all") or "all", *extra, *argv]
    return argv


def _overrides(items: list[str]) -> dict:
    out = {}
    for item in items:
        if "=" not in item:
            raise ParameterError(f"parameter {item!r} must be written name=value")
        k, v = item.split("=", 1)
        out[k.strip()] = parse_value(v.strip())
    return out


def _per_notebook(targets: list[Path], items: list[str]) -> list[tuple[Path, list[str], dict]]:
    """Each notebook's parameters.  Several notebooks with one ``output_dir=X`` write one
    folder each, ``X/<stem>``: never one notebook's results over another's."""
    overrides = _overrides(items)
    if len(targets) == 1 or "output_dir" not in overrides:
        return [(t, list(items), dict(overrides)) for t in targets]
    base = str(overrides["output_dir"])
    rest = [i for i in items if i.split("=", 1)[0].strip() != "output_dir"]
    plan = []
    for t in targets:
        own = os.path.join(base, t.stem)
        plan.append((t, [*rest, f"output_dir={own!r}"], {**overrides, "output_dir": own}))
    return plan


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m mtaccuracy.compendium.runner",
                                 description="Validate parameters and run notebooks in place.")
    ap.add_argument("notebook", help="'all', a number such as 03, a stem or a path")
    ap.add_argument("params", nargs="*", help="name=value overrides (Python literals)")
    ap.add_argument("--check", action="store_true", help="validate only, do not run")
    ap.add_argument("--list", action="store_true", help="list the notebook's parameters")
    ap.add_argument("--jobs", type=int, default=None,
                    help="notebooks run at once for 'all' (default: 2 on 2+ cores)")
    ap.add_argument("--copy-to", metavar="DIR", default=None,
                    help="execute into DIR, a folder outside the repository (the notebook as "
                         "DIR/<stem>.ipynb, outputs in DIR/figures/<stem>/), touching nothing "
                         "in the repository")
    ap.add_argument("--quiet", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--share", type=int, default=1, help=argparse.SUPPRESS)
    try:
        commit.recover()
        args = ap.parse_intermixed_args(_arguments(argv))
        targets = all_notebooks() if args.notebook == "all" else [notebook_path(args.notebook)]
        plan = _per_notebook(targets, args.params)
        if args.list:
            for t in targets:
                print(f"{t.stem}:")
                for p in read_parameters(t).values():
                    print("  " + p.describe())
            return 0
        copy_to = paths.check_copy_dir(args.copy_to) if args.copy_to is not None else None
        jobs = max(1, min(args.jobs or min(2, os.cpu_count() or 1), len(targets)))
        with _output_base(copy_to):
            for t, _, overrides in plan:  # validate everything before running anything
                validate(t, overrides, share=max(jobs, args.share))
        if args.check:
            print("parameters ok")
            return 0
        if jobs > 1:
            return 1 if _run_parallel(plan, jobs, copy_to) else 0
        for t, _, overrides in plan:
            shown = " ".join(f"{k}={v!r}" for k, v in overrides.items()) or "defaults"
            if not args.quiet:
                print(f"{_rel(t)} ({shown})", flush=True)
            s = run(t, overrides, progress=not args.quiet, share=args.share, copy_to=copy_to)
            with _output_base(copy_to):
                where = written_notebook(t, overrides, copy_to=copy_to)
            print(f"{t.stem} done in {s:.1f} s -> {_rel(where)}", flush=True)
    except Interrupted as exc:
        if str(exc):
            print(f"interrupted: {exc}", file=sys.stderr, flush=True)
        return 130
    except KeyboardInterrupt:
        print("interrupted before any run started; nothing changed", file=sys.stderr)
        return 130
    except (ParameterError, RuntimeError, paths.OutputDirError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
