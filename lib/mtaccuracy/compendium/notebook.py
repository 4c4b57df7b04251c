"""What a notebook calls first, and what it saves through: :func:`start` and :class:`Run`.

A notebook's second code cell checks the values of its parameters cell (and of the cell
papermill injects after it) against its declaration, and opens its run::

    from mtaccuracy.compendium import notebook
    from mtaccuracy.papers import guo2016

    run = notebook.start(guo2016.Parameters, globals())

:func:`start` refuses a bad value or a run the machine cannot hold (one line, before any work),
resolves ``output_dir`` (``figures/<stem>`` by default, relative to the repository root; or a
folder outside the repository, or under ``build/`` where the workflow runs it) and begins the
run's provenance record.  Everything the run writes goes through the :class:`Run`: figures
(:meth:`Run.figure`), tables (:meth:`Run.table`), the scorecard (:meth:`Run.scorecard`); what it
reads is recorded through it too (:meth:`Run.input`, :meth:`Run.published`, ``on_read=run.track``).
After each save the folder's ``provenance.json`` lists every file written with its hash.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import pandas as pd
import psutil

from ..papers import printed
from ..papers.figure import Caption
from ..papers.parameters import NotebookParameters, ParameterError, check, values
from . import plotting, provenance, reproduction
from .provenance import ROOT

FIGURES = ROOT / "figures"
NOTEBOOKS = ROOT / "notebooks"
#: The workflow's own folder; runs it executes write under it.
BUILD = ROOT / "build"


def available_memory() -> tuple[float, str]:
    """The bytes a new run may use, and what limits them.

    The smaller of the memory the system calls available (psutil) and what the process's
    cgroup (v2) still allows; the kernel's own accounting is not modelled.

    Returns
    -------
    (float, str)
        Bytes, and ``"available memory"`` or ``"the cgroup limit"``.
    """
    have, what = float(psutil.virtual_memory().available), "available memory"
    try:
        rel = Path("/proc/self/cgroup").read_text().splitlines()[0].split("::", 1)[1]
        group = Path("/sys/fs/cgroup") / rel.lstrip("/")
        limit = (group / "memory.max").read_text().strip()
        if limit != "max":
            left = float(limit) - float((group / "memory.current").read_text())
            if left < have:
                have, what = left, "the cgroup limit"
    except (OSError, IndexError, ValueError):
        pass
    return have, what


def check_memory(filled: NotebookParameters, *, available: tuple[float, str] | None = None
                 ) -> None:
    """Refuse a run whose declared peak memory exceeds what the machine has left.

    Parameters
    ----------
    filled : NotebookParameters
        The run's parameters.
    available : (float, str), optional
        :func:`available_memory`, when the caller has it already.

    Raises
    ------
    ParameterError
        Naming the need, what is left and what limits it.
    """
    need = filled.memory_bytes()
    have, what = available or available_memory()
    if need > have:
        raise ParameterError(
            f"{filled.stem}: these parameters need about {need / 1e9:.3g} GB of memory, more "
            f"than the {have / 1e9:.3g} GB left ({what}); lower the sample sizes")


def output_folder(value, stem: str) -> Path:
    """The folder an ``output_dir`` value names, if notebook ``stem`` may write into it.

    Allowed: ``figures/<stem>`` (a relative path is taken from the repository root), a folder
    under ``build/`` (the workflow's), or a folder outside the repository that is new, empty or
    was written by an earlier run of the same notebook.

    Raises
    ------
    ParameterError
        Saying why not, and what is allowed.
    """
    allowed = (f"use figures/{stem} (the default) or a new or empty folder outside the "
               f"repository ({ROOT})")
    text = str(value).strip()
    if not text:
        raise ParameterError(f"{stem}: output_dir is empty, which would be the repository root; "
                             f"{allowed}")
    p = Path(text).expanduser()
    p = (p if p.is_absolute() else ROOT / p).resolve()
    if p != FIGURES / stem and not p.is_relative_to(BUILD):
        if p == ROOT or ROOT.is_relative_to(p):
            raise ParameterError(f"{stem}: output_dir {text!r} is {p}, the repository or a folder "
                                 f"that contains it; {allowed}")
        if p.is_relative_to(ROOT):
            owner = provenance.written_by(p)
            what = (f"another notebook's folder ({owner})" if owner not in (None, stem) else
                    "a folder inside the repository that is not this notebook's")
            raise ParameterError(f"{stem}: output_dir {text!r} is {what}; {allowed}")
    if p.exists() and not p.is_dir():
        raise ParameterError(f"{stem}: output_dir {text!r} is a file ({p}); {allowed}")
    if p.is_dir() and any(p.iterdir()) and provenance.written_by(p) != stem:
        owner = provenance.written_by(p)
        why = (f"it holds the outputs of {owner}" if owner else
               "it is not empty and was not written by the compendium")
        raise ParameterError(f"{stem}: output_dir {text!r} ({p}): {why}; nothing there is "
                             f"overwritten; {allowed}")
    return p


def input_path(value, what: str) -> Path:
    """An input file or folder a parameter names: relative to the repository root, or absolute.

    Raises
    ------
    FileNotFoundError
        Naming the parameter.
    """
    p = Path(str(value)).expanduser()
    p = p if p.is_absolute() else ROOT / p
    if not p.exists():
        raise FileNotFoundError(f"{what} {str(value)!r} not found ({p})")
    return p


def files_of(path: Path) -> list[Path]:
    """The files an input path stands for: itself, or a folder's files (its record left out)."""
    files = [path] if path.is_file() else sorted(x for x in path.rglob("*") if x.is_file())
    return [f for f in files if f.name != provenance.SIDECAR]


class Run:
    """One run of a notebook: its parameters, its output folder and its provenance record.

    Made by :func:`start`.  ``run.out`` is the output folder; ``run.parameters`` the filled
    declaration.
    """

    def __init__(self, filled: NotebookParameters, out: Path, notebook: Path):
        self.parameters = filled
        self.stem = filled.stem
        self.out = out
        self.record = provenance.record(self.stem, notebook, values(filled))
        earlier = provenance.read(out)
        same = earlier.get("run", {}).get("notebook") == self.stem
        # an interactive run into a folder written before replaces its files one by one
        self.files: dict = dict(earlier.get("files", {})) if same else {}
        self._figures = 0
        for name in type(filled).files():
            self.input(getattr(filled, name), name)

    # -- what the run reads ------------------------------------------------------------------
    def track(self, path) -> None:
        """Record an input file's hash (``on_read=run.track`` for the readers)."""
        p = Path(path)
        if p.is_file() and p.name != provenance.SIDECAR:
            self.record["inputs"][provenance.shown(p)] = provenance.sha256(p)

    def input(self, value, what: str) -> Path:
        """The input file or folder a parameter names (:func:`input_path`), recorded.

        A folder's files are recorded one by one (:func:`files_of`)."""
        p = input_path(value, what)
        for f in files_of(p):
            self.track(f)
        return p

    def published(self, name: str, required: list[str] | None = None) -> pd.DataFrame:
        """A table of printed numbers (:func:`mtaccuracy.papers.printed.published`), recorded."""
        df = printed.published(name, required)
        self.track(df.attrs["path"])
        return df

    # -- what the run writes -----------------------------------------------------------------
    def _register(self, name: str, entry: dict) -> None:
        self.files[name] = entry
        provenance.write_sidecar(self.out, {"run": self.record, "files": self.files})

    def figure(self, fig, caption: Caption, *, title: str | None = None, scored_with=None,
               formats=("png", "svg")) -> None:
        """Save ``fig`` as ``<caption.name>.png`` and ``.svg``, with its caption.

        Parameters
        ----------
        fig : matplotlib.figure.Figure
            The figure.
        caption : Caption
            Its file name, label and caption (declared in the paper module).
        title : str, optional
            The files' ``Title``.
        scored_with : list of str, optional
            The scorecard rows that score what it shows (default: ``caption.rows``).
        formats : tuple of str
            Formats written.

        Returns
        -------
        None
            So that a cell ending with it shows no machine-specific path.
        """
        stamp = provenance.as_text(self.record)
        rows = list(scored_with if scored_with is not None else caption.rows)
        for path in plotting.save(fig, self.out / caption.name, stamp=stamp, formats=formats,
                                  title=title, scored_with=rows):
            entry = {"sha256": provenance.sha256(path)}
            if path.suffix == ".png":
                entry.update(label=caption.label, caption=caption.text, order=self._figures,
                             **({"rows": rows} if rows else {}))
            self._register(path.name, entry)
        self._figures += 1

    def table(self, df: pd.DataFrame, name: str, *, float_format: str = "%.6g",
              tolerance=None, measured: bool = False) -> None:
        """Write ``df`` as ``<out>/<name>`` (:func:`reproduction.write_table`), recorded.

        Parameters
        ----------
        df : pandas.DataFrame
            The table.
        name : str
            Its file name (``table2_key_errors.csv``).
        float_format : str
            Format of float cells.
        tolerance : Tolerance or dict, optional
            How closely a regeneration elsewhere must match (default: the printed precision).
        measured : bool
            A measurement of the machine (wall-clock times): no hash, never compared.

        Returns
        -------
        None
            So that a cell ending with it shows no machine-specific path.
        """
        entry = reproduction.write_table(df, self.out / name, float_format=float_format,
                                         tolerance=tolerance, measured=measured)
        self._register(name, entry)

    def scorecard(self, card: reproduction.Card, *, tolerance=None) -> pd.DataFrame:
        """Write the card as ``reproduction.csv`` (its measured rows apart); return its rows.

        Rows whose quantity says ``(measured)`` go to ``reproduction_measured.csv``, declared
        measured, so that the card itself is the same on every run.  ``tolerance`` applies to
        the ``reproduced`` and ``tolerance`` columns (default: the printed precision).
        """
        if not card.rows:
            raise ValueError("an empty scorecard: add rows first")
        df = reproduction.card_frame(card.rows)
        measured = df["quantity"].astype(str).str.contains(reproduction.MEASURED_MARK,
                                                           regex=False)
        if measured.any():
            self.table(df[measured], reproduction.MEASURED_CARD, measured=True)
        tol = tolerance or reproduction.PRINTED
        if isinstance(tol, reproduction.Tolerance):
            tol = {"reproduced": tol, "tolerance": tol}
        self.table(df[~measured].reset_index(drop=True), "reproduction.csv", tolerance=tol)
        return df


def one_line_warning(message, category, filename, lineno, line=None) -> str:
    """A warning as a notebook shows it: its kind and message, one line.

    Python's default adds the file and line that raised it: in a notebook, a kernel's
    temporary file (``/tmp/ipykernel_<pid>/<hash>.py``) that differs on every run, so that an
    unchanged notebook's output would change; the message names what matters."""
    return f"{category.__name__}: {message}\n"


def start(declared: type[NotebookParameters], namespace: dict, *, notebook=None) -> Run:
    """Check a notebook's parameters and open its run (a notebook's first call).

    Parameters
    ----------
    declared : type
        The notebook's declaration (``papers.guo2016.Parameters``).
    namespace : dict
        The notebook's ``globals()``: the values of its parameters cell, and of the cell
        papermill injected after it.
    notebook : path, optional
        The notebook file, whose source and imports the record hashes (default:
        ``notebooks/<stem>.ipynb``).

    Returns
    -------
    Run
        The run: ``run.out``, ``run.parameters``, and the saving methods.  From here on a
        warning shows as one line (:func:`one_line_warning`).

    Raises
    ------
    ParameterError
        One line, before any work: a value that is not allowed, an output folder that may not
        be written, or a run that needs more memory than is left.
    """
    stem = declared.stem
    missing = [n for n in declared.names() if n not in namespace]
    if missing:
        raise ParameterError(f"{stem}: parameter(s) {', '.join(missing)} not defined: run the "
                             f"cell tagged 'parameters' first")
    filled = check(declared, {n: namespace[n] for n in declared.names()})
    check_memory(filled)
    warnings.formatwarning = one_line_warning
    out = output_folder(filled.output_dir, stem)
    out.mkdir(parents=True, exist_ok=True)
    return Run(filled, out, Path(notebook) if notebook else NOTEBOOKS / f"{stem}.ipynb")
