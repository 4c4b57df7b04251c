"""The workflow: ``make reproduce`` and ``make sweep`` on Snakemake (``workflow/Snakefile``).

``python -m mtaccuracy.compendium.workflow reproduce|sweep`` checks what the user asked for
(which notebooks, which parameters, the memory they need) and refuses bad input in one line
before any work; then it runs Snakemake, which executes each notebook that needs it (its
notebook source, the library modules it imports, its data or its parameters changed since the
last run here) with all the machine's cores, and re-runs a notebook whose run was interrupted
or killed.  Each notebook runs in two steps, both Snakemake jobs:

1. :func:`execute`: papermill runs the notebook into ``build/runs/<stem>/`` (the executed
   notebook, and its outputs in ``outputs/``).  A failed or interrupted run is Snakemake's
   incomplete output, removed before the next; the executed notebook of a failed run is kept
   beside the job's log, ``build/logs/<stem>.ipynb``.
2. :func:`publish`: the finished run is copied into place, ``figures/<stem>/`` and
   ``notebooks/<stem>.ipynb`` (or the ``output_dir`` given).  Written by hand because no
   engine mechanism keeps a user's files in a folder it writes: only the files the previous run
   listed in ``provenance.json`` are replaced or removed, a file it did not write (or one edited
   since) is never touched, and the copy is refused whole before anything moves if a new
   output would overwrite one.  Ctrl-C and SIGTERM are held during the copy (milliseconds); a
   kill -9 in it leaves the job incomplete, and the next ``make reproduce`` publishes again.

``make sweep`` runs a notebook over seeds (and settings) into ``build/sweep/<stem>/`` and
publishes :func:`summarise`'s tables into ``<output_dir>/sweep/``.
"""

from __future__ import annotations

import argparse
import ast
import base64
import contextlib
import copy
import itertools
import json
import os
import shlex
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd

from ..papers import (
    guo2016,
    rong,
    xu2022,
    yang2021,
    your_machine,
    your_measurements,
    your_spindle,
    zheng2024,
)
from ..papers.parameters import NotebookParameters, ParameterError, check, values
from . import provenance
from .notebook import (
    FIGURES,
    NOTEBOOKS,
    ROOT,
    available_memory,
    files_of,
    input_path,
    output_folder,
)
from .notebook import check_memory as refuse_oversized
from .reproduction import VERDICTS, write_table

#: Every notebook's declaration, in notebook order.
DECLARATIONS = tuple(m.Parameters for m in (zheng2024, rong, guo2016, xu2022, yang2021,
                                             your_machine, your_spindle, your_measurements))
SNAKEFILE = ROOT / "workflow" / "Snakefile"
MEASURED_NOTE = ("[output of a cell tagged 'measured' (wall-clock times of the machine that ran "
                 "it): not stored, so that re-running an unchanged notebook leaves it unchanged; "
                 "the values are in the output files declared measured]\n")


def declaration(stem: str) -> type[NotebookParameters]:
    """The declaration of notebook ``stem``."""
    for cls in DECLARATIONS:
        if cls.stem == stem:
            return cls
    raise ParameterError(f"no notebook {stem!r}; notebooks: "
                         f"{', '.join(c.stem for c in DECLARATIONS)}")


def notebooks(name: str) -> list[str]:
    """The stems ``NB`` names: ``all``, a number (``03``), a stem or its start, or a path.

    Compared as text, never as a pattern (``*`` matches nothing)."""
    stems = [c.stem for c in DECLARATIONS]
    text = str(name).strip()
    if text in ("", "all"):
        return stems
    if text.endswith(".ipynb") or "/" in text:
        p = Path(text).expanduser()
        p = (p if p.is_absolute() else Path.cwd() / p).resolve()
        if p.parent == NOTEBOOKS and p.stem in stems:
            return [p.stem]
        raise ParameterError(f"{text!r} is not one of the compendium's notebooks: "
                             f"{', '.join(stems)}")
    hits = [s for s in stems if s.startswith(text)]
    if len(hits) != 1:
        shown = text if len(text) <= 60 else text[:57] + "..."
        raise ParameterError(f"{'no notebook matches' if not hits else 'several notebooks match'}"
                             f" {shown!r}; notebooks: {', '.join(hits or stems)}")
    return hits


def parse_params(text: str) -> dict:
    """``PARAMS`` as ``{name: value}``: split like a shell would, never run by one.

    Each value is a Python literal if it reads as one, else the text."""
    try:
        items = shlex.split(text or "")
    except ValueError as exc:
        raise ParameterError(f"PARAMS={text!r}: {exc}") from None
    out = {}
    for item in items:
        if "=" not in item:
            raise ParameterError(f"parameter {item!r} must be written name=value")
        k, v = item.split("=", 1)
        try:
            out[k.strip()] = ast.literal_eval(v.strip())
        except (ValueError, SyntaxError, MemoryError, RecursionError):
            out[k.strip()] = v.strip()
    return out


def plan(nb: str, params: str) -> dict[str, dict]:
    """What ``make reproduce NB=.. PARAMS=..`` runs: ``{stem: {name: value}}``, all checked.

    Several notebooks with one ``output_dir=X`` write one folder each, ``X/<stem>``; an input
    file a parameter names must exist.

    Raises
    ------
    ParameterError
        The first refusal, in one line.
    """
    stems = notebooks(nb)
    given = parse_params(params)
    runs = {}
    for stem in stems:
        mine = dict(given)
        if "output_dir" in mine and len(stems) > 1:
            mine["output_dir"] = os.path.join(str(mine["output_dir"]), stem)
        filled = check(declaration(stem), mine)
        output_folder(filled.output_dir, stem)
        for name in type(filled).files():
            try:
                input_path(getattr(filled, name), name)
            except FileNotFoundError as exc:
                raise ParameterError(f"{stem}: {exc}") from None
        runs[stem] = {k: v for k, v in values(filled).items() if k in mine}
    return runs


def target(stem: str, given: dict) -> tuple[Path, Path]:
    """Where a run with parameters ``given`` is published: (output folder, notebook file)."""
    out = output_folder(given.get("output_dir", declaration(stem).param["output_dir"].default),
                        stem)
    return out, (NOTEBOOKS / f"{stem}.ipynb" if out == FIGURES / stem else out / f"{stem}.ipynb")


def in_place(stem: str, given: dict) -> bool:
    """Whether a run publishes into ``figures/<stem>/`` and replaces the committed notebook."""
    return target(stem, given)[0] == FIGURES / stem


def edited_outputs(folder: Path, stem: str) -> list[str]:
    """The files a run of ``stem`` listed in ``folder`` whose bytes changed since."""
    side = provenance.read(folder)
    if side.get("run", {}).get("notebook") != stem:
        return []
    return sorted(n for n, e in side.get("files", {}).items()
                  if (folder / n).is_file() and "sha256" in e
                  and provenance.sha256(folder / n) != e["sha256"])


def check_memory(runs: dict[str, dict]) -> int:
    """Refuse a run that cannot fit in the memory left; return that memory in MB.

    Snakemake then schedules the runs so that their declared bounds never add up to more."""
    have = available_memory()
    for stem, given in runs.items():
        refuse_oversized(check(declaration(stem), given), available=have)
    return int(have[0] / 1e6)


# --- what Snakemake needs to know of a run --------------------------------------------------

def source_hash(stem: str) -> str:
    """The hash of a notebook's source cells: a run re-executes when it changes."""
    return provenance.notebook_source_hash(NOTEBOOKS / f"{stem}.ipynb")


def memory_mb(stem: str, given: dict) -> int:
    """A run's declared peak memory, in MB (Snakemake's ``mem_mb`` resource)."""
    return int(check(declaration(stem), given).memory_bytes() / 1e6) + 1


def inputs(stem: str, given: dict) -> list[str]:
    """The files a run of ``stem`` depends on, besides its source and parameters (absolute).

    The library modules its code imports (:func:`provenance.library_modules`), the files its
    file parameters name, and the files its last published run read (its ``provenance.json``,
    like a compiler's dependency file): a notebook that starts reading a new file has changed
    its source, so the list is never short."""
    filled = check(declaration(stem), given)
    found = set(provenance.library_modules(NOTEBOOKS / f"{stem}.ipynb"))
    for name in type(filled).files():
        found.update(files_of(input_path(getattr(filled, name), name)))
    last = provenance.read(target(stem, given)[0]).get("run", {}).get("inputs", {})
    for name in last:
        p = Path(name) if Path(name).is_absolute() else ROOT / name
        if p.is_file():
            found.add(p)
    return sorted(str(p) for p in found)


# --- step 1: execute ----------------------------------------------------------------------------

def _merge_streams(outputs: list) -> list:
    """Consecutive outputs of one stream as one: how the kernel splits a cell's printing
    depends on timing, not on the result."""
    merged: list = []
    for o in outputs:
        prev = merged[-1] if merged else None
        if (o.get("output_type") == "stream" and prev is not None
                and prev.get("output_type") == "stream" and prev.get("name") == o.get("name")):
            prev["text"] = ("".join(prev["text"]) + "".join(o["text"])).splitlines(keepends=True)
        else:
            if o.get("output_type") == "stream":
                o = dict(o, text="".join(o["text"]).splitlines(keepends=True))
            merged.append(o)
    return merged


def normalise(nb: dict, stem: str, shown: dict) -> dict:
    """An executed notebook as it is stored: what makes two identical runs differ removed.

    Timestamps, durations and papermill's paths go; a cell tagged ``measured`` keeps a note
    instead of its output; the cell papermill injected shows ``shown`` (the parameters the
    user gave, without the workflow's own output folder), or goes when that is empty.
    """
    from papermill.translators import translate_parameters  # papermill: only where it runs

    nb = copy.deepcopy(nb)
    meta = nb.get("metadata", {}).get("papermill", {})
    for k in ("start_time", "end_time", "duration", "environment_variables", "exception"):
        meta.pop(k, None)
    if meta:
        meta["input_path"] = meta["output_path"] = f"notebooks/{stem}.ipynb"
        meta["parameters"] = shown
    cells = []
    for c in nb.get("cells", []):
        md = c.get("metadata", {})
        md.pop("papermill", None)
        md.pop("execution", None)
        if "injected-parameters" in md.get("tags", []):
            if not shown:
                continue
            c["source"] = translate_parameters("python3", "python", shown,
                                               "Parameters").splitlines(keepends=True)
        if c.get("cell_type") == "code":
            if "measured" in md.get("tags", []):
                c["outputs"] = [{"name": "stdout", "output_type": "stream",
                                 "text": [MEASURED_NOTE]}]
            c["outputs"] = _merge_streams(c.get("outputs", []))
        cells.append(c)
    count = 0
    for c in cells:  # numbered as a run without the injected cell numbers them
        if c.get("cell_type") == "code" and c.get("execution_count") is not None:
            count += 1
            c["execution_count"] = count
            for o in c.get("outputs", []):
                if "execution_count" in o:
                    o["execution_count"] = count
    nb["cells"] = cells
    return nb


@contextlib.contextmanager
def _stderr_to(log: Path):
    """What the kernel writes to its standard error (start-up warnings, the traceback of a
    kernel stopped mid-cell) goes to ``log``: the terminal keeps the workflow's own lines."""
    sys.stderr.flush()
    saved = os.dup(2)
    with open(log, "ab") as fh:
        os.dup2(fh.fileno(), 2)  # inherited by the kernel
    try:
        yield
    finally:
        sys.stderr.flush()
        os.dup2(saved, 2)
        os.close(saved)


def execute(notebook: Path, given: dict, run_dir: Path, log: Path, *, threads: int = 1) -> float:
    """Run a notebook with papermill into ``run_dir``; return the seconds it took.

    Parameters
    ----------
    notebook : Path
        The committed notebook (read, never written).
    given : dict
        The parameters the user gave (checked), shown in the executed notebook's injected
        cell; the run itself writes into ``run_dir/outputs``.
    run_dir : Path
        Receives ``<stem>.ipynb`` (executed, :func:`normalise`) and ``outputs/``.
    log : Path
        The kernel's standard error (``<stem>.log``); the notebook as it runs is written
        beside it (``<stem>.ipynb``) and kept only when the run fails.
    threads : int
        BLAS threads of the kernel.

    Raises
    ------
    RuntimeError
        One line: the cell that failed and its error.
    """
    import papermill as pm  # papermill and its kernel machinery: only where a notebook runs

    stem = notebook.stem
    run_dir, log = Path(run_dir).resolve(), Path(log).resolve()
    running = log.with_suffix(".ipynb")
    run_dir.mkdir(parents=True, exist_ok=True)
    log.parent.mkdir(parents=True, exist_ok=True)
    env = {"OPENBLAS_NUM_THREADS": str(threads), "OMP_NUM_THREADS": str(threads),
           "MKL_NUM_THREADS": str(threads), "JUPYTER_RUNTIME_DIR": str(run_dir / ".jupyter")}
    old = {k: os.environ.get(k) for k in env}
    os.environ.update(env)
    t0 = time.perf_counter()
    try:
        with _stderr_to(log):
            pm.execute_notebook(notebook, running, cwd=notebook.parent, kernel_name="python3",
                                parameters={**given, "output_dir": str(run_dir / "outputs")},
                                progress_bar=False, log_output=False)
    except pm.PapermillExecutionError as exc:
        raise RuntimeError(f"{stem} failed in cell [{exc.exec_count}]: {exc.ename}: "
                           f"{exc.evalue}; the executed notebook is {provenance.shown(running)}"
                           ) from None
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
        shutil.rmtree(run_dir / ".jupyter", ignore_errors=True)
    nb = normalise(json.loads(running.read_text(encoding="utf-8")), stem, given)
    (run_dir / f"{stem}.ipynb").write_text(
        json.dumps(nb, indent=1, ensure_ascii=False, sort_keys=True) + "\n", encoding="utf-8")
    running.unlink()  # kept only when the run fails
    return time.perf_counter() - t0


# --- step 2: publish ----------------------------------------------------------------------------

class PublishRefused(RuntimeError):
    """Publishing would overwrite a file the compendium did not write."""


def _copy_into(src: Path, dest: Path) -> None:
    tmp = dest.with_name(f".{dest.name}.{os.getpid()}.tmp")
    shutil.copyfile(src, tmp)
    os.replace(tmp, dest)


def publish(outputs: Path, target: Path, *, notebook: tuple[Path, Path] | None = None) -> list[str]:
    """Copy a finished run's outputs (and its executed notebook) into place.

    Parameters
    ----------
    outputs : Path
        The run's output folder (its ``provenance.json`` lists what it wrote).
    target : Path
        The folder to publish into (``figures/<stem>``).
    notebook : (Path, Path), optional
        The executed notebook and where it goes.

    Returns
    -------
    list of str
        The files of ``target`` left alone: not written by the compendium, or edited since.

    Raises
    ------
    PublishRefused
        Before anything is copied: a new output would overwrite such a file.
    """
    new = provenance.read(outputs)
    stem = new.get("run", {}).get("notebook")
    names = list(new.get("files", {}))
    old = provenance.read(target) if provenance.written_by(target) == stem else {}
    old_files = old.get("files", {})

    def ours(name: str) -> bool:
        entry = old_files.get(name)
        return entry is not None and ("sha256" not in entry
                                      or provenance.sha256(target / name) == entry["sha256"])

    clash = [n for n in names if (target / n).exists() and not ours(n)]
    if (target / provenance.SIDECAR).exists() and not old and any(target.iterdir()):
        clash.append(provenance.SIDECAR)
    if clash:
        raise PublishRefused(f"{provenance.shown(target)}: {', '.join(sorted(clash))} would be "
                             f"overwritten but {'was' if len(clash) == 1 else 'were'} not "
                             f"written by the compendium or changed since; nothing was copied: "
                             f"move {'it' if len(clash) == 1 else 'them'} away and run again")
    stale = [n for n in old_files if n not in new.get("files", {})]
    held = {s: signal.signal(s, signal.SIG_IGN) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        target.mkdir(parents=True, exist_ok=True)
        for n in names:
            _copy_into(outputs / n, target / n)
        _copy_into(outputs / provenance.SIDECAR, target / provenance.SIDECAR)
        for n in stale:
            if (target / n).is_file() and ours(n):
                (target / n).unlink()
        if notebook is not None:
            _copy_into(*notebook)
    finally:
        for s, h in held.items():
            signal.signal(s, h)
    left = {n for n in stale if (target / n).exists()}
    return sorted(left | set(provenance.not_outputs(target, new)))


def write_parameters_cell(stem: str) -> bool:
    """Rewrite a notebook's cell tagged ``parameters`` as its declaration's rendering.

    Nothing else of the notebook changes (its outputs are those of its last run until the next).
    Returns whether the cell changed."""
    import nbformat  # nbformat: only where a notebook is edited

    path = NOTEBOOKS / f"{stem}.ipynb"
    nb = nbformat.read(path, as_version=4)
    [cell] = [c for c in nb.cells if "parameters" in c.metadata.get("tags", [])]
    new = declaration(stem).cell()
    if cell.source == new:
        return False
    cell.source = new
    nbformat.write(nb, path)
    return True


# --- sweeps ----------------------------------------------------------------------------------

def sweep_runs(stem: str, seeds: int, params: str) -> dict[str, dict]:
    """The runs of ``make sweep``: ``{run id: parameters}``, every value checked.

    ``seeds`` runs per setting, with seeds ``seed, seed + 1, ...`` from the declared (or
    given) seed; a parameter written ``name=a|b|c`` is swept over those values (every
    combination); the runs write only under ``build/sweep/``.
    """
    decl = declaration(stem)
    if "seed" not in decl.names():
        raise ParameterError(f"{stem} has no seed parameter: a sweep over seeds means nothing")
    if not 1 <= seeds <= 1000:
        raise ParameterError(f"SEEDS={seeds}: give 1 to 1000 seeds")
    fixed, swept = {}, {}
    for k, v in parse_params(params).items():
        if isinstance(v, str) and "|" in v:
            swept[k] = [parse_params(f"x={part}")["x"] for part in v.split("|")]
        else:
            fixed[k] = v
    if "output_dir" in swept:
        raise ParameterError("output_dir cannot be swept")
    base = check(decl, fixed).seed
    runs = {}
    names = list(swept)
    for i, combo in enumerate(itertools.product(*swept.values())):
        for k in range(seeds):
            given = {**{n: v for n, v in fixed.items() if n != "output_dir"},
                     **dict(zip(names, combo, strict=True)), "seed": base + k}
            check(decl, given)
            runs[f"{f'setting{i + 1}-' if names else ''}seed{base + k}"] = given
    return runs


def summarise(stem: str, runs: dict[str, dict], folders: dict[str, Path], out: Path) -> None:
    """Write a sweep's tables into ``out`` (recorded in its ``provenance.json``).

    ``values.csv``: item, quantity, (setting,) seed and the reproduced value of every row of
    every run; ``verdict_stability.csv``: item, quantity, (setting,) then how many runs gave
    each verdict (``reproduced``, ``close``, ``differs``, ``not_reproducible``) and whether
    the verdict changed with the seed.
    """
    swept = sorted({k for g in runs.values() for k in g} - {"seed"})
    varied = [k for k in swept if len({json.dumps(g.get(k)) for g in runs.values()}) > 1]
    rows = []
    for run, given in runs.items():
        card = pd.read_csv(Path(folders[run]) / "reproduction.csv", dtype=str,
                           keep_default_na=False)
        setting = " ".join(f"{k}={given[k]!r}" for k in varied)
        for _, r in card.iterrows():
            rows.append({"item": r["item"], "quantity": r["quantity"],
                         **({"setting": setting} if varied else {}), "seed": given["seed"],
                         "reproduced": r["reproduced"], "verdict": r["verdict"]})
    df = pd.DataFrame(rows)
    keys = ["item", "quantity", *(["setting"] if varied else [])]
    counts = (df.groupby(keys, sort=False)["verdict"].value_counts().unstack(fill_value=0)
              .reindex(columns=list(VERDICTS), fill_value=0).reset_index())
    counts.columns = [c.replace(" ", "_") for c in counts.columns]
    counts["changes_with_seed"] = (counts[[v.replace(" ", "_") for v in VERDICTS]] > 0) \
        .sum(axis=1) > 1
    out.mkdir(parents=True, exist_ok=True)
    record = {"notebook": f"{stem} (sweep)", "runs": runs}
    files = {name: write_table(table, out / name)
             for name, table in (("values.csv", df.drop(columns="verdict")),
                                 ("verdict_stability.csv", counts))}
    provenance.write_sidecar(out, {"run": record, "files": files})


# --- the user's commands ---------------------------------------------------------------------

def encode_plan(plan: dict) -> str:
    """The plan as one ``--config`` value: JSON in URL-safe base64.

    Snakemake reads ``--config`` values as YAML and would turn the JSON's numbers into
    strings."""
    return "b64:" + base64.urlsafe_b64encode(json.dumps(plan).encode()).decode()


def decode_plan(text: str) -> dict:
    """The inverse of :func:`encode_plan` (in the Snakefile)."""
    return json.loads(base64.urlsafe_b64decode(text.removeprefix("b64:").encode()))


@contextlib.contextmanager
def _one_at_a_time(workdir: Path):
    """Hold the checkout's workflow lock while Snakemake runs (it then runs with ``--nolock``).

    Written by hand because Snakemake's own lock (files in ``.snakemake/locks``) outlives a
    killed run and then refuses the next one until ``--unlock``; an ``flock`` is released by the
    kernel when its process dies, however it dies, so a second ``make reproduce`` is refused only
    while the first is really running."""
    import fcntl  # POSIX only, like the rest of the workflow

    path = Path(workdir) / ".snakemake" / "workflow.lock"
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w") as fh:
        try:
            fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise ParameterError(f"another make reproduce or make sweep is running in "
                                 f"{provenance.shown(workdir)}; wait for it to end") from None
        yield


def _snakemake(config: dict, *, cores: int, mem_mb: int, force: bool, targets=(),
               workdir: Path = ROOT, profile: str | None = None) -> int:
    cmd = [sys.executable, "-m", "snakemake", *targets, "--snakefile", str(SNAKEFILE),
           "--directory", str(workdir), "--cores", str(cores), "--resources", f"mem_mb={mem_mb}",
           "--rerun-incomplete", "--nolock", "--quiet", "rules", "host", "reason",
           # a changed file re-runs (its checksum, not only its time); a file newly listed as
           # read (the last run's record) does not: the run that listed it read it
           "--rerun-triggers", "mtime", "params", "code",
           "--max-checksum-file-size", str(100 * 2**20),
           "--config", f"plan={encode_plan(config)}"]
    if force:
        cmd.append("--forceall")
    if profile:  # a cluster: the profile's executor submits the jobs (workflow/profiles/)
        cmd += ["--profile", str(SNAKEFILE.parent / "profiles" / profile)]
    Path(workdir).mkdir(parents=True, exist_ok=True)
    with _one_at_a_time(workdir):
        proc = subprocess.Popen(cmd, cwd=workdir)
        while True:  # Ctrl-C reaches Snakemake too: it stops its jobs; wait for it to say so
            try:
                return proc.wait()
            except KeyboardInterrupt:
                continue


def _cores(text: str | None) -> int:
    try:
        n = int(text) if text else (os.cpu_count() or 1)
    except ValueError:
        raise ParameterError(f"CORES={text!r} is not a whole number") from None
    return max(1, n)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m mtaccuracy.compendium.workflow")
    sub = ap.add_subparsers(dest="command", required=True)
    r = sub.add_parser("reproduce", help="run the notebooks that need it, then the scorecard")
    r.add_argument("--nb", default="all")
    r.add_argument("--params", default="")
    r.add_argument("--force", action="store_true", help="re-run every notebook")
    r.add_argument("--cores", default=None)
    r.add_argument("--workdir", type=Path, default=ROOT, help=argparse.SUPPRESS)  # the tests'
    r.add_argument("--profile", default=None, help="a Snakemake profile of workflow/profiles/")
    s = sub.add_parser("sweep", help="run a notebook over seeds (and settings)")
    s.add_argument("--nb", required=True)
    s.add_argument("--seeds", type=int, default=5)
    s.add_argument("--params", default="")
    s.add_argument("--cores", default=None)
    s.add_argument("--profile", default=None, help="a Snakemake profile of workflow/profiles/")
    ls = sub.add_parser("list", help="the parameters a notebook declares")
    ls.add_argument("nb")
    c = sub.add_parser("cell", help="write each notebook's parameters cell from its declaration")
    c.add_argument("nb", nargs="?", default="all")
    e = sub.add_parser("execute")  # a Snakemake job
    e.add_argument("stem")
    e.add_argument("given")
    e.add_argument("run_dir", type=Path)
    e.add_argument("log", type=Path)
    p = sub.add_parser("publish")  # a Snakemake job
    p.add_argument("run_dir", type=Path)
    p.add_argument("target", type=Path)
    p.add_argument("--notebook", type=Path, default=None)
    p.add_argument("--stem", default=None)
    m = sub.add_parser("summarise")  # a Snakemake job
    m.add_argument("stem")
    m.add_argument("runs")
    m.add_argument("out", type=Path)
    args = ap.parse_args(argv)
    try:
        if args.command == "list":
            for stem in notebooks(args.nb):
                decl = declaration(stem)
                print(f"{stem}:")
                for n in decl.names():
                    print("  " + decl.describe(n))
            return 0
        if args.command == "cell":
            for stem in notebooks(args.nb):
                what = ("rewritten from its declaration" if write_parameters_cell(stem)
                        else "already its declaration")
                print(f"notebooks/{stem}.ipynb: parameters cell {what}")
            return 0
        if args.command == "reproduce":
            runs = plan(args.nb, args.params)
            for stem, given in runs.items():
                folder, _ = target(stem, given)
                edited = edited_outputs(folder, stem)
                if edited:
                    raise ParameterError(f"{stem}: {', '.join(edited)} in "
                                         f"{provenance.shown(folder)} changed since the "
                                         f"compendium wrote it; a run would overwrite it: move "
                                         f"it away first")
            cores = _cores(args.cores)
            mem = check_memory(runs)
            return _snakemake({"runs": runs}, cores=cores, mem_mb=mem, force=args.force,
                              workdir=args.workdir, profile=args.profile)
        if args.command == "sweep":
            [stem] = notebooks(args.nb)
            runs = sweep_runs(stem, args.seeds, args.params)
            given = parse_params(args.params)
            out = output_folder(given.get("output_dir",
                                          declaration(stem).param["output_dir"].default), stem)
            cores = _cores(args.cores)
            mem = check_memory({stem: max(runs.values(), key=lambda g: memory_mb(stem, g))})
            return _snakemake({"sweep": {"stem": stem, "runs": runs, "out": str(out)}},
                              cores=cores, mem_mb=mem, force=False, targets=["sweep"],
                              profile=args.profile)
        if args.command == "execute":
            seconds = execute(NOTEBOOKS / f"{args.stem}.ipynb", json.loads(args.given),
                              args.run_dir, args.log)
            print(f"{args.stem} ran in {seconds:.1f} s", flush=True)
            return 0
        if args.command == "publish":
            nb = None
            if args.notebook is not None:
                nb = (args.run_dir / args.notebook.name, args.notebook)
            src = args.run_dir / "outputs" if (args.run_dir / "outputs").is_dir() else args.run_dir
            left = publish(src, args.target, notebook=nb)
            print(f"{provenance.shown(args.target)}: published"
                  + (f"; left alone (not written by the compendium, or edited since): "
                     f"{', '.join(left)}" if left else ""), flush=True)
            return 0
        if args.command == "summarise":
            runs = json.loads(args.runs)
            # a Snakemake job runs in the workflow's directory: build/ is relative to it
            folders = {k: Path("build") / "sweep" / args.stem / k / "outputs" for k in runs}
            summarise(args.stem, runs, folders, args.out)
            return 0
    except KeyboardInterrupt:
        print("interrupted (Ctrl-C): nothing was changed", file=sys.stderr)
        return 130
    except (ParameterError, RuntimeError, FileNotFoundError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
