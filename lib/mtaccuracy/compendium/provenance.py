"""Provenance of every output: which code, notebook, parameters and input data made it.

A notebook's first call, :func:`mtaccuracy.compendium.parameters.check_parameters`, starts a
record (:func:`start`); every input file read through the library is hashed into it (:func:`track`,
called by ``reproduction.published`` and the data readers); every figure and table saved
through ``plotting.save`` and ``reproduction.save_table`` carries it: PNG text chunk
``mtaccuracy:provenance``, SVG ``Description``, and for CSVs the sidecar ``provenance.json`` of
their folder, which lists every output file with its SHA-256.

The record holds content hashes only: of the library sources, of the notebook's source
cells (code and markdown, not outputs), of each input file, plus the notebook's parameters
(except ``output_dir``, which only says where files go) and the versions of the main packages.
It has no timestamp and no git commit: unchanged code, notebook, inputs and parameters give
identical records and so identical figure bytes, whatever was committed in between.  The runner
keeps the commit of each run in ``figures/.runs.json`` (not committed; see
:mod:`mtaccuracy.compendium.runner`).

Each file entry of the sidecar also says how the regenerated-table test compares it on another
machine: ``tolerance`` (per float column, see
:class:`mtaccuracy.compendium.reproduction.Tolerance`) or
``measured`` (a measurement of the machine, such as wall-clock time: never compared, no hash).

Before an output is shown (the book, ``make book``) it is checked against that list
(:func:`output_problem`, :func:`folder_problems`): missing, unreadable, unlisted or changed
files are named; a file the sidecar does not list is the user's, never judged or shown
(:func:`not_outputs`).
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import platform
import subprocess
import xml.etree.ElementTree as ET
from importlib import metadata
from pathlib import Path

from . import paths

PACKAGES = ("numpy", "scipy", "pandas", "matplotlib", "SALib", "chaospy", "scikit-learn",
            "sympy", "papermill")
SIDECAR = "provenance.json"
_IGNORED_PARAMETERS = {"output_dir"}
_state: dict = {"notebook": None, "parameters": {}, "inputs": {}, "notebook_sha256": None}


def sha256(path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


_rel = paths.relative


def git_commit() -> str:
    """The checkout's commit, for the runner's ``figures/.runs.json`` (never in a figure)."""
    try:
        out = subprocess.run(["git", "rev-parse", "HEAD"], cwd=paths.ROOT, capture_output=True,
                             text=True, timeout=10)
        return out.stdout.strip() or "unknown"
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def notebook_source_hash(path) -> str:
    """SHA-256 over a notebook's cell types and sources: what the reader wrote.

    Without outputs, execution counts, metadata or the cell papermill injects: not what a run
    produced."""
    nb = json.loads(Path(path).read_text(encoding="utf-8"))
    h = hashlib.sha256()
    for c in nb.get("cells", []):
        if "injected-parameters" in c.get("metadata", {}).get("tags", []):
            continue
        src = c.get("source", "")
        h.update(c.get("cell_type", "").encode() + b"\0")
        h.update(("".join(src) if isinstance(src, list) else src).encode("utf-8") + b"\0")
    return h.hexdigest()


@functools.cache
def library_hash() -> str:
    """SHA-256 over the library's Python sources and its package data, in path order.

    The package data is ``mtaccuracy/data``: the error catalogue.  Computed once per process: the
    code a process runs is the code it imported, whatever changes on disk later."""
    h = hashlib.sha256()
    lib = Path(__file__).resolve().parent.parent   # the mtaccuracy package
    data = [p for p in (lib / "data").rglob("*") if p.is_file()]
    for p in sorted([*lib.rglob("*.py"), *data]):
        h.update(p.relative_to(lib).as_posix().encode())
        h.update(p.read_bytes())
    return h.hexdigest()


def start(notebook: str, parameters: dict, source=None) -> None:
    """Begin the record of a notebook run (called by ``check_parameters``).

    ``source`` is the notebook file, whose source cells are hashed."""
    _state["notebook"] = notebook
    _state["notebook_sha256"] = notebook_source_hash(source) if source else None
    _state["parameters"] = {k: v for k, v in sorted(parameters.items())
                            if k not in _IGNORED_PARAMETERS}
    _state["inputs"] = {}
    for value in _state["parameters"].values():  # a parameter naming a data file or folder
        if isinstance(value, str) and value and not value.startswith("/"):
            p = paths.ROOT / value
            for f in ([p] if p.is_file() else sorted(p.rglob("*")) if p.is_dir() else []):
                if f.name != SIDECAR:  # a folder's own record is an output, not an input
                    track(f)


def track(path) -> None:
    """Add an input file's hash to the current record."""
    p = Path(path)
    if p.is_file():
        _state["inputs"][_rel(p)] = sha256(p)


@functools.cache
def _versions() -> dict:
    versions = {}
    for pkg in PACKAGES:
        try:
            versions[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            versions[pkg] = "not installed"
    versions["python"] = platform.python_version()
    return versions


def record() -> dict:
    """The current provenance record (JSON-serialisable, deterministic)."""
    versions = dict(_versions())
    return {"library_sha256": library_hash(), "notebook": _state["notebook"],
            "notebook_sha256": _state["notebook_sha256"],
            "parameters": dict(_state["parameters"]),
            "inputs": dict(sorted(_state["inputs"].items())), "packages": versions}


def as_text(rec: dict | None = None) -> str:
    return json.dumps(rec or record(), sort_keys=True, separators=(",", ":"), default=str)


def register_output(path, measured: bool = False, tolerance: dict | None = None) -> None:
    """Record an output file in its folder's ``provenance.json``.

    It is recorded with its hash and, for tables, the tolerance of each float column; a
    ``measured`` file (wall-clock times) without a hash.
    """
    p = Path(path)
    side = p.parent / SIDECAR
    data = json.loads(side.read_text(encoding="utf-8")) if side.exists() else {}
    if _rel(p) in _state["inputs"]:  # an input the run rewrites (notebook 04's data/thermal):
        track(p)                     # the record holds the bytes on disk, not those replaced
    rec = record()
    files = data.get("files", {}) if data.get("run", {}).get("notebook") == rec["notebook"] \
        else {}
    entry: dict = {"measured": True} if measured else {"sha256": sha256(p)}
    if tolerance:
        entry["tolerance"] = tolerance
    files[p.name] = entry
    write_sidecar(p.parent, {"run": rec, "files": files})


def write_sidecar(folder, data: dict) -> None:
    """Write ``folder/provenance.json`` (files sorted, fixed format), replaced whole.

    It is written only when its bytes change."""
    side = Path(folder) / SIDECAR
    data = {**data, "files": dict(sorted(data.get("files", {}).items()))}
    text = json.dumps(data, sort_keys=True, indent=1, default=str) + "\n"
    if not side.exists() or side.read_text(encoding="utf-8") != text:
        tmp = side.with_name(f".{SIDECAR}.{os.getpid()}.tmp")
        tmp.write_text(text, encoding="utf-8")
        os.replace(tmp, side)


def read(folder) -> dict:
    """The sidecar of an output folder ({} when there is none)."""
    side = Path(folder) / SIDECAR
    return json.loads(side.read_text(encoding="utf-8")) if side.exists() else {}


def from_png(path) -> dict:
    """The provenance record stamped into a PNG (or {})."""
    from PIL import Image  # Pillow: only where a PNG is read or written

    with Image.open(path) as im:
        text = im.info.get("mtaccuracy:provenance")
    return json.loads(text) if text else {}


# ---------------------------------------------------------- checks before an output is shown

def output_kind(path: Path) -> str:
    """What an output file is, for the messages: "figure", "table" or "file"."""
    return {".png": "figure", ".svg": "figure", ".csv": "table"}.get(Path(path).suffix, "file")


def output_problem(path: Path, side: dict) -> str | None:
    """Why an output file cannot be shown or linked, or None when it is sound.

    Parameters
    ----------
    path : Path
        The file, in its output folder.
    side : dict
        That folder's ``provenance.json`` (:func:`read`).

    Returns
    -------
    str or None
        The problem in words, to follow the file's name ("is missing ...", "cannot be read
        ...", "is not listed ...", "does not match the hash ..."): missing though listed, a
        figure that cannot be decoded, not listed, no hash though not ``measured``, or bytes
        that are not the ones the run recorded.  A ``measured`` entry is only required to
        exist (and, for a figure, to be readable).
    """
    path = Path(path)
    entry = side.get("files", {}).get(path.name)
    if not path.is_file():
        return (f"is missing (listed in {SIDECAR}, not on disk)" if entry is not None
                else "is missing")
    # Pillow here, not at the top: make's recovery step (commit.py) imports this module with
    # the system's Python, before .venv exists
    from PIL import Image  # Pillow: only where a PNG is read or written

    try:
        if path.suffix == ".png":
            with Image.open(path) as im:
                im.load()  # decodes every byte: a truncated file fails here
        elif path.suffix == ".svg":
            ET.parse(path)
    except Exception as exc:  # PIL and expat raise many kinds
        return f"cannot be read ({type(exc).__name__}: {str(exc)[:80]})"
    if entry is None:
        return f"is not listed in {SIDECAR} (not written by this folder's run)"
    if entry.get("measured"):
        return None  # a measurement of the machine: no hash to check
    if "sha256" not in entry:
        return f"has no hash in {SIDECAR} and is not declared measured"
    if entry["sha256"] != sha256(path):
        return f"does not match the hash in {SIDECAR} (changed after its run)"
    return None


def folder_problems(folder: Path, side: dict | None = None) -> list[tuple[Path, str]]:
    """Every problem (:func:`output_problem`) of an output folder's outputs.

    Its outputs are the files its ``provenance.json`` lists; a file it does not list is not the
    compendium's (:func:`not_outputs`) and is not judged.

    Parameters
    ----------
    folder : Path
        A notebook's output folder (``figures/<stem>``).
    side : dict, optional
        Its ``provenance.json`` (read when not given).

    Returns
    -------
    list of (Path, str)
        ``(path, why)`` for each file with a problem, sorted by name.
    """
    folder = Path(folder)
    side = read(folder) if side is None else side
    found = ((folder / n, output_problem(folder / n, side)) for n in sorted(side.get("files", {})))
    return [(p, why) for p, why in found if why]


def not_outputs(folder: Path, side: dict | None = None) -> list[str]:
    """The files in an output folder that its ``provenance.json`` does not list.

    They were put there by someone else (notes, an input file), are left alone by every run, and
    are never shown or linked as results.

    Parameters
    ----------
    folder : Path
        A notebook's output folder.
    side : dict, optional
        Its ``provenance.json`` (read when not given).

    Returns
    -------
    list of str
        Their names, sorted.
    """
    folder = Path(folder)
    side = read(folder) if side is None else side
    listed = set(side.get("files", {})) | {SIDECAR}
    return sorted(p.name for p in folder.iterdir() if p.is_file()
                  and not p.name.startswith(".") and p.name not in listed) \
        if folder.is_dir() else []
